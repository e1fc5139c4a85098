// Linked against btr_verify alone (with btr_model): if the self-check used any placement code, this program
// would not link. It also checks a hand-built row of disks: resting on the floor between the walls, then
// with one disk pushed into its neighbour.
#include <cstdio>

#include "btr/verify/check.h"

int main() {
  btr::Container box;
  box.kind = btr::ContainerKind::Box;
  box.size_x = 4.0;  // walls at x = -2 and 2: four disks of radius 0.5 fill the floor row exactly
  btr::Grains row;
  for (double x : {-1.5, -0.5, 0.5, 1.5}) row.push_back({btr::Vec3(x, 0.0, 0.5), 0.5, 1, 0});
  const btr::CheckReport resting = btr::check_packing(row, 2, box);
  row[1].x.x() = -0.9;  // 0.4 = 0.8 r into the first disk
  const btr::CheckReport pushed = btr::check_packing(row, 2, box);
  const bool pass = resting.ok() && pushed.overlaps == 1 && pushed.max_overlap > 0.79 && pushed.max_overlap < 0.81;
  std::printf("resting row: ok %d; pushed disk: overlaps %lld, largest %.3f r\n", resting.ok(),
              static_cast<long long>(pushed.overlaps), pushed.max_overlap);
  return pass ? 0 : 1;
}
