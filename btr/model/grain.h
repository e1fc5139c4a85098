#pragma once
// The grains of a packing: the one data structure every stage shares.
#include <Eigen/Core>
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

}  // namespace btr
