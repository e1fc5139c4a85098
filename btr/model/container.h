#pragma once
// The container a packing is built in. Gravity is along -z; the floor is z = 0 in every kind.
// Lateral geometry is centred on the z axis:
//   open       floor only, unbounded laterally
//   box        side walls at x = +-size_x/2 (and y = +-size_y/2 in 3D)
//   periodic   periodic in x (and y in 3D) with period size_x (size_y), domain [-L/2, L/2)
//   hele-shaw  (3D only) plates at y = +-gap/2, end walls at x = +-size_x/2
//   cylinder   (3D only) vertical cylinder of radius `radius` about the z axis
//   drum       horizontal cylinder of radius `radius` with its axis along y at height z = radius (its
//              lowest line is the floor z = 0); 3D: flat end walls at y = +-size_y/2 (its length)
//              or, with periodic_ends, periodic in y with period size_y; 2D: a circle of disks in the x-z plane
//   mesh       (3D only) a triangle mesh read from an STL file (btr/model/mesh.h); size_x, size_y and
//              height are its bounding box, centred on the z axis, its lowest point at z = 0
#include <cmath>
#include <memory>
#include <string>

#include "btr/model/grain.h"
#include "btr/model/mesh.h"

namespace btr {

enum class ContainerKind { Open, Box, Periodic, HeleShaw, Cylinder, Drum, Mesh };

struct Container {
  ContainerKind kind = ContainerKind::Open;
  double size_x = 0.0;  // box, periodic, hele-shaw [m]
  double size_y = 0.0;  // box, periodic, drum length (3D only) [m]
  double gap = 0.0;     // hele-shaw plate distance w [m]
  double radius = 0.0;  // cylinder, drum inner radius [m]
  double height = 0.0;  // optional wall height for the DEM stage; 0 = derived from the packing
  bool periodic_ends = false;  // drum (3D): periodic in y with period size_y instead of flat end walls
  std::shared_ptr<const TriangleMesh> mesh;  // mesh: the triangles, as placed
};

// Axes along which the container wraps, with the domain [-L/2, L/2): x in a periodic container; y in a
// 3D periodic container and in a 3D drum with periodic ends.
bool wraps_x(const Container& container);
bool wraps_y(const Container& container, int dimension);

// The period along x (axis 0) or y (axis 1): size_x or size_y where the container wraps, else 0.
double period_along(const Container& container, int dimension, int axis);

// The periodic wrap, written once (the self-check in btr/verify keeps its own on purpose):
// a coordinate brought into the domain [-L/2, L/2) of period L,
inline double wrap_coordinate(double x, double period) {
  x -= period * std::floor(x / period + 0.5);
  if (x >= 0.5 * period) x -= period;  // round-off can leave x on the far side of a bound
  if (x < -0.5 * period) x = -0.5 * period;
  return x;
}
// and a separation along a periodic axis reduced to its nearest image (d itself when |d| <= L/2).
inline double minimum_image(double d, double period) {
  return std::abs(d) > 0.5 * period ? d - period * std::round(d / period) : d;
}

// A centre with its coordinates along the container's periodic axes wrapped into the cell.
Vec3 wrap_into_cell(const Container& container, int dimension, Vec3 x);

const char* to_string(ContainerKind kind);

}  // namespace btr
