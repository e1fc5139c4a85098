#pragma once
// One grain's fall, roll and rest in a mesh container: the triangles are contact partners like the fixed
// grains. The centre of a grain of radius r touches a triangle where its distance from the triangle is r:
// a plane offset by r over the face, a cylinder of radius r about an edge, a sphere of radius r about a
// vertex (docs/design.md, "Mesh containers").
#include <cstdint>

#include "btr/model/grain.h"

namespace btr {

class NeighbourGrid;
class MeshIndex;

struct MeshEngine {
  const NeighbourGrid& grid;
  const MeshIndex& mesh;
  double r_max;
  int max_events;
};

// The resting centre of a grain of radius r dropped from x (above everything in its column). Throws
// PlacementError naming grain `id`: it falls out of the mesh (an open outlet), comes to rest outside it,
// meets too many contacts, or exceeds its event budget.
Vec3 place_in_mesh(const MeshEngine& engine, std::int64_t id, Vec3 x, double r);

}  // namespace btr
