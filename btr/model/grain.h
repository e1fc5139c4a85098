#pragma once
// The grains of a packing: the one data structure every stage shares.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace btr {

using Vec3 = Eigen::Vector3d;

// A placed grain. Its id is its index + 1 (ids follow deposition order, starting at 1).
struct Grain {
  Vec3 x;           // centre [m]; 2D packings have x.y() == 0
  double r = 0.0;   // radius [m]
  int species = 1;  // component of a mixture, 1, 2, ...
  std::int32_t cluster = 0;  // rigid cluster it belongs to, 1, 2, ...; 0 = a free grain
};

using Grains = std::vector<Grain>;

// Volume of a sphere of radius r (3D), or area of a disk (2D).
inline double grain_volume(double r, int dimension) {
  return dimension == 3 ? 4.0 / 3.0 * M_PI * r * r * r : M_PI * r * r;
}

// What the grains fill: the sum of their volumes (3D) or areas (2D).
inline double solid_volume(const Grains& grains, int dimension) {
  double volume = 0.0;
  for (const Grain& g : grains) volume += grain_volume(g.r, dimension);
  return volume;
}

// The largest radius (0 for no grains).
inline double max_radius(const Grains& grains) {
  double r = 0.0;
  for (const Grain& g : grains) r = std::max(r, g.r);
  return r;
}

}  // namespace btr
