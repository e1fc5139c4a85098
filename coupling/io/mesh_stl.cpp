#include "coupling/io/mesh_stl.h"

#include <Eigen/Geometry>
#include <cstdio>
#include <string>

#include "coupling/io/atomic_file.h"

namespace btr {

void write_mesh_stl(const TriangleMesh& mesh, const std::string& path) {
  std::string text = "solid btr_mesh\n";
  char buf[160];
  auto vec = [&](const char* what, const Vec3& v) {
    std::snprintf(buf, sizeof buf, "%s %.17g %.17g %.17g\n", what, v.x(), v.y(), v.z());
    text += buf;
  };
  for (const auto& f : mesh.triangles) {
    const Vec3 &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    vec("facet normal", (b - a).cross(c - a).normalized());
    text += "outer loop\n";
    vec("vertex", a);
    vec("vertex", b);
    vec("vertex", c);
    text += "endloop\nendfacet\n";
  }
  text += "endsolid btr_mesh\n";
  write_text_file(path, text);
}

}  // namespace btr
