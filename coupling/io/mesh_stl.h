#pragma once
// A mesh container's triangles written for a DEM engine: ASCII STL in the packing's coordinates (scaled
// and placed as the scene says, btr/model/mesh.h), so the engine reads them with no scale or shift.
#include <string>

#include "btr/model/mesh.h"

namespace btr {

// Written under a temporary name and renamed (coupling/io/atomic_file.h).
void write_mesh_stl(const TriangleMesh& mesh, const std::string& path);

}  // namespace btr
