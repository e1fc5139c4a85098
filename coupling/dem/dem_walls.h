#pragma once
// The walls a DEM engine needs for a container (exactly those the container has: the floor, the
// side walls of a box, the plates and end walls of a Hele-Shaw cell, a cylinder, a mesh container's
// triangles; none laterally for open and periodic containers; a drum's surface alone, with no floor),
// with the geometry to measure a grain against each.
#include <memory>
#include <string>
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

class MeshIndex;

struct DemWall {
  enum class Kind { Plane, Cylinder, Mesh };
  Kind kind = Kind::Plane;
  std::string name;     // "floor", "x-", "x+", "y-", "y+", "cylinder"
  int axis = 2;         // plane: 0, 1, 2 for x, y, z
  double position = 0;  // plane: coordinate along axis; cylinder: radius (axis = z through x = y = 0)
  int inward = 1;       // plane: +1 if the grains are on the side of larger coordinates
  std::shared_ptr<const TriangleMesh> triangles;  // mesh: the container's triangles, as placed
  std::shared_ptr<const MeshIndex> mesh;           // and their index (distance: to the nearest one)
  // A drum (Kind::Mesh, name "drum", triangles null: the writers build them for the grains, drum_mesh.h):
  // the distance is the exact cylinder's (axis along y at z = drum_radius), and the end walls' at y = +-drum_half
  // when drum_ends; the engines' panels lie within kDrumSagittaFraction r_min of it.
  double drum_radius = 0.0;
  double drum_half = 0.0;
  bool drum_ends = false;

  // Signed distance of a point from the wall, positive on the grains' side.
  double distance(const Vec3& x) const;
};

// Throws std::runtime_error if the container's sizes are not positive or its kind does not exist in
// this dimension (hele-shaw and cylinder are 3D only).
std::vector<DemWall> dem_walls(const Container& container, int dimension);

}  // namespace btr
