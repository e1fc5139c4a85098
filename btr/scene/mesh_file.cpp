#include "btr/scene/mesh_file.h"

#include <vtkCellArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "btr/scene/scene_toml.h"

namespace btr {

std::shared_ptr<const TriangleMesh> read_mesh(const std::string& path, double scale) {
  if (!std::ifstream(path)) throw SceneError(path + ": cannot open the mesh file (container.file)");
  if (std::filesystem::is_directory(path)) throw SceneError(path + ": is a folder, expected an STL file (container.file)");
  vtkObject::GlobalWarningDisplayOff();  // the reader's complaints come back as our error below
  vtkNew<vtkSTLReader> reader;
  reader->SetFileName(path.c_str());
  reader->MergingOn();  // shared vertices: the edges between triangles are known by their ends
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || poly == nullptr || poly->GetPoints() == nullptr)
    throw SceneError(path + ": cannot read the mesh: expected an ASCII or binary STL file");
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->file = path;
  mesh->scale = scale;
  vtkPoints* points = poly->GetPoints();
  const vtkIdType np = points->GetNumberOfPoints();
  mesh->vertices.reserve(static_cast<std::size_t>(np));
  for (vtkIdType i = 0; i < np; ++i) {
    double p[3];
    points->GetPoint(i, p);
    mesh->vertices.emplace_back(scale * p[0], scale * p[1], scale * p[2]);
  }
  vtkCellArray* polys = poly->GetPolys();
  vtkNew<vtkIdList> ids;
  std::int64_t index = 0;
  for (polys->InitTraversal(); polys->GetNextCell(ids); ++index) {
    if (ids->GetNumberOfIds() != 3) {
      std::ostringstream why;
      why << path << ": facet " << index << " has " << ids->GetNumberOfIds() << " vertices, expected 3";
      throw SceneError(why.str());
    }
    mesh->triangles.push_back({static_cast<int>(ids->GetId(0)), static_cast<int>(ids->GetId(1)),
                               static_cast<int>(ids->GetId(2))});
  }
  if (mesh->triangles.empty()) throw SceneError(path + ": the mesh has no triangles (an empty or unreadable STL file)");
  for (const Vec3& v : mesh->vertices)
    if (!v.allFinite()) throw SceneError(path + ": the mesh has a non-finite vertex coordinate");
  Vec3 lo = mesh->vertices[0], hi = lo;
  for (const Vec3& v : mesh->vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  // Degenerate: an area below 1e-12 of the box's diagonal squared (a sliver, repeated vertices, a line).
  const double diag2 = (hi - lo).squaredNorm();
  std::ostringstream bad;
  int n_bad = 0;
  for (std::size_t t = 0; t < mesh->triangles.size(); ++t) {
    const auto& f = mesh->triangles[t];
    const Vec3 a = mesh->vertices[f[0]], b = mesh->vertices[f[1]], c = mesh->vertices[f[2]];
    const double area2 = (b - a).cross(c - a).norm();
    if (!(area2 > 1e-12 * diag2)) {
      if (n_bad < 10) bad << (n_bad ? ", " : "") << t;
      ++n_bad;
    }
  }
  if (n_bad > 0) {
    std::ostringstream why;
    why << path << ": " << n_bad << " degenerate triangle" << (n_bad > 1 ? "s" : "")
        << " (zero area; index from 0 in file order): " << bad.str() << (n_bad > 10 ? ", ..." : "");
    throw SceneError(why.str());
  }
  mesh->shift = Vec3(-0.5 * (lo.x() + hi.x()), -0.5 * (lo.y() + hi.y()), -lo.z());
  for (Vec3& v : mesh->vertices) v += mesh->shift;
  mesh->lo = lo + mesh->shift;
  mesh->hi = hi + mesh->shift;
  return mesh;
}

}  // namespace btr
