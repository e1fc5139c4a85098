#pragma once
// Reading a container's triangle mesh from an STL file (ASCII or binary) with VTK's reader.
#include <memory>
#include <string>

#include "btr/model/mesh.h"

namespace btr {

// The mesh of `path`, its coordinates multiplied by `scale` and shifted so that its bounding box is
// centred on the z axis with its lowest point at z = 0 (btr/model/mesh.h). Throws SceneError naming the
// file: unreadable, no triangles, degenerate triangles (by their index, counted from 0 in file order).
std::shared_ptr<const TriangleMesh> read_mesh(const std::string& path, double scale);

}  // namespace btr
