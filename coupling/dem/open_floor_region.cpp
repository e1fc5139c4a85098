#include "coupling/dem/open_floor_region.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace btr {

FloorRegion open_floor_region(const Grains& grains, int dimension, double margin, double heap_angle_deg) {
  FloorRegion region;
  for (int a = 0; a < 2; ++a) {
    region.lo[a] = std::numeric_limits<double>::infinity(), region.hi[a] = -region.lo[a];
    for (const Grain& g : grains)
      region.lo[a] = std::min(region.lo[a], g.x[a] - g.r), region.hi[a] = std::max(region.hi[a], g.x[a] + g.r);
  }
  const double volume = solid_volume(grains, dimension);
  // The heap's base radius: V / phi = (pi / 3) R^3 tan(angle) for a cone, A / phi = R^2 tan(angle) for a triangle.
  const double slope = std::tan(heap_angle_deg * M_PI / 180.0);
  const double base = dimension == 3 ? std::cbrt(3.0 * volume / (kHeapRegionPhi * M_PI * slope))
                                     : std::sqrt(volume / (kHeapRegionPhi2D * slope));
  for (int a = 0; a < 2; ++a) {
    const double mid = 0.5 * (region.lo[a] + region.hi[a]);
    region.lo[a] -= margin, region.hi[a] += margin;
    if (a == 1 && dimension == 2) continue;  // disks in the plane y = 0: no heap across it
    region.lo[a] = std::min(region.lo[a], mid - base), region.hi[a] = std::max(region.hi[a], mid + base);
  }
  return region;
}

}  // namespace btr
