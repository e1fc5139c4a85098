// The open floor's region (coupling/dem/open_floor_region.h): the footprint grown by the margin, widened to
// hold the heap of the grains' volume, checked against cones and triangles computed by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "coupling/dem/open_floor_region.h"

namespace btr {
namespace {

// n grains of radius r in a tight column at (x, y): a footprint of one diameter.
Grains column(int n, double r, double x, double y) {
  Grains g(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) g[i] = Grain{Vec3(x, y, r * (2 * i + 1)), r, 1};
  return g;
}

TEST(OpenFloorRegion, HoldsTheConeOfTheGrainsVolumeAboutTheFootprintsMiddle) {
  const double r = 1e-3, angle = 20.0;
  const Grains g = column(1000, r, 0.01, -0.02);
  const FloorRegion region = open_floor_region(g, 3, 2e-3, angle);
  // 1000 spheres at packing fraction 0.5 fill a cone of volume (pi / 3) R^3 tan(20 deg).
  const double volume = 1000 * 4.0 / 3.0 * M_PI * r * r * r / 0.5;
  const double R = std::cbrt(volume / (M_PI / 3.0 * std::tan(20.0 * M_PI / 180.0)));
  EXPECT_GT(R, 10 * r) << "the case must test the cone, not the margin";
  EXPECT_NEAR(region.lo[0], 0.01 - R, 1e-12);
  EXPECT_NEAR(region.hi[0], 0.01 + R, 1e-12);
  EXPECT_NEAR(region.lo[1], -0.02 - R, 1e-12);
  EXPECT_NEAR(region.hi[1], -0.02 + R, 1e-12);
  // A flatter heap is wider: the base grows as tan(angle)^(-1/3).
  const FloorRegion flat = open_floor_region(g, 3, 2e-3, 2.0);
  const double ratio = std::cbrt(std::tan(20.0 * M_PI / 180.0) / std::tan(2.0 * M_PI / 180.0));
  EXPECT_NEAR(flat.hi[0] - 0.01, ratio * R, 1e-12);
}

TEST(OpenFloorRegion, HoldsTheTriangleOfTheDisksAreaIn2D) {
  const double r = 0.5e-3;
  const Grains g = column(400, r, -0.03, 0.0);
  const FloorRegion region = open_floor_region(g, 2, 1e-3, 10.0);
  // 400 disks at packing fraction 0.75 fill a triangle of area R^2 tan(10 deg).
  const double R = std::sqrt(400 * M_PI * r * r / 0.75 / std::tan(10.0 * M_PI / 180.0));
  EXPECT_NEAR(region.lo[0], -0.03 - R, 1e-12);
  EXPECT_NEAR(region.hi[0], -0.03 + R, 1e-12);
  // Across the plane of the disks only the margin: no heap spreads in y.
  EXPECT_NEAR(region.lo[1], -r - 1e-3, 1e-15);
  EXPECT_NEAR(region.hi[1], r + 1e-3, 1e-15);
}

TEST(OpenFloorRegion, AWideFootprintKeepsItsMargin) {
  // Grains spread over 0.2 m: their heap at 45 deg is far narrower, so the footprint and margin decide.
  Grains g = column(10, 1e-3, -0.1, 0.0);
  g.push_back(Grain{Vec3(0.1, 0.05, 1e-3), 1e-3, 1});
  const FloorRegion region = open_floor_region(g, 3, 4e-3, 45.0);
  EXPECT_NEAR(region.lo[0], -0.1 - 1e-3 - 4e-3, 1e-15);
  EXPECT_NEAR(region.hi[0], 0.1 + 1e-3 + 4e-3, 1e-15);
  EXPECT_NEAR(region.lo[1], -1e-3 - 4e-3, 1e-15);
  EXPECT_NEAR(region.hi[1], 0.05 + 1e-3 + 4e-3, 1e-15);
}

}  // namespace
}  // namespace btr
