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
#include <string>

namespace btr {

enum class ContainerKind { Open, Box, Periodic, HeleShaw, Cylinder, Drum };

struct Container {
  ContainerKind kind = ContainerKind::Open;
  double size_x = 0.0;  // box, periodic, hele-shaw [m]
  double size_y = 0.0;  // box, periodic, drum length (3D only) [m]
  double gap = 0.0;     // hele-shaw plate distance w [m]
  double radius = 0.0;  // cylinder, drum inner radius [m]
  double height = 0.0;  // optional wall height for the DEM stage; 0 = derived from the packing
  bool periodic_ends = false;  // drum (3D): periodic in y with period size_y instead of flat end walls
};

// Axes along which the container wraps, with the domain [-L/2, L/2): x in a periodic container; y in a
// 3D periodic container and in a 3D drum with periodic ends.
bool wraps_x(const Container& container);
bool wraps_y(const Container& container, int dimension);

const char* to_string(ContainerKind kind);

}  // namespace btr
