#pragma once
// A container given as a triangle mesh (an STL file from CAD). The mesh is stored as placed: scaled by
// the scene's `scale` and shifted so that its bounding box is centred on the z axis with its lowest
// point at z = 0, like every other container (btr/model/container.h).
#include <array>
#include <string>
#include <vector>

#include "btr/model/grain.h"

namespace btr {

struct TriangleMesh {
  std::string file;        // the file it was read from (resolved against the scene's folder)
  double scale = 1.0;      // the scene's scale, applied to the file's coordinates first
  Vec3 shift = Vec3::Zero();  // then added: file coordinates p become scale * p + shift
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;  // indices into vertices
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();   // bounding box of the placed mesh
};

}  // namespace btr
