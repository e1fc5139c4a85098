#include "coupling/dem/dem_walls.h"

#include "btr/placement/mesh_index.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace btr {

double DemWall::distance(const Vec3& x) const {
  if (kind == Kind::Cylinder) return position - std::hypot(x.x(), x.y());
  if (drum_radius > 0.0) {
    double d = drum_radius - std::hypot(x.x(), x.z() - drum_radius);
    if (drum_ends) d = std::min(d, drum_half - std::abs(x.y()));
    return d;
  }
  if (kind == Kind::Mesh) {
    // Unsigned: a mesh has no inside to tell (an open mesh least of all); a grain is never beyond it.
    // Triangles farther than `position` (a twentieth of the mesh's size) count as that far.
    std::vector<int> near;
    mesh->collect(x - Vec3::Constant(position), x + Vec3::Constant(position), near);
    double d = position;
    for (int t : near) d = std::min(d, mesh->distance(t, x));
    return d;
  }
  return inward * (x[axis] - position);
}

namespace {

void require_positive(double v, const char* what, const Container& c) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::runtime_error(std::string("container '") + to_string(c.kind) + "': " + what +
                             " must be a positive number, got " + std::to_string(v));
}

DemWall plane(const char* name, int axis, double pos, int inward) {
  DemWall w;
  w.kind = DemWall::Kind::Plane;
  w.name = name;
  w.axis = axis;
  w.position = pos;
  w.inward = inward;
  return w;
}

}  // namespace

std::vector<DemWall> dem_walls(const Container& c, int dimension) {
  if (dimension != 2 && dimension != 3)
    throw std::runtime_error("dimension must be 2 or 3, got " + std::to_string(dimension));
  std::vector<DemWall> walls{plane("floor", 2, 0.0, +1)};
  switch (c.kind) {
    case ContainerKind::Open:
      break;
    case ContainerKind::Periodic:
      require_positive(c.size_x, "size_x", c);
      if (dimension == 3) require_positive(c.size_y, "size_y", c);
      break;
    case ContainerKind::Box:
      require_positive(c.size_x, "size_x", c);
      walls.push_back(plane("x-", 0, -0.5 * c.size_x, +1));
      walls.push_back(plane("x+", 0, 0.5 * c.size_x, -1));
      if (dimension == 3) {
        require_positive(c.size_y, "size_y", c);
        walls.push_back(plane("y-", 1, -0.5 * c.size_y, +1));
        walls.push_back(plane("y+", 1, 0.5 * c.size_y, -1));
      }
      break;
    case ContainerKind::HeleShaw:
      if (dimension != 3) throw std::runtime_error("container 'hele-shaw' exists in 3D only");
      require_positive(c.size_x, "size_x", c);
      require_positive(c.gap, "gap", c);
      walls.push_back(plane("x-", 0, -0.5 * c.size_x, +1));
      walls.push_back(plane("x+", 0, 0.5 * c.size_x, -1));
      walls.push_back(plane("y-", 1, -0.5 * c.gap, +1));
      walls.push_back(plane("y+", 1, 0.5 * c.gap, -1));
      break;
    case ContainerKind::Cylinder: {
      if (dimension != 3) throw std::runtime_error("container 'cylinder' exists in 3D only");
      require_positive(c.radius, "radius", c);
      DemWall w;
      w.kind = DemWall::Kind::Cylinder;
      w.name = "cylinder";
      w.position = c.radius;
      walls.push_back(w);
      break;
    }
    case ContainerKind::Mesh: {
      if (dimension != 3) throw std::runtime_error("container 'mesh' exists in 3D only");
      if (!c.mesh) throw std::runtime_error("container 'mesh' without its triangles");
      DemWall w;
      w.kind = DemWall::Kind::Mesh;
      w.name = "mesh";
      w.position = 0.05 * (c.mesh->hi - c.mesh->lo).norm();
      w.triangles = c.mesh;
      w.mesh = std::make_shared<const MeshIndex>(*c.mesh, w.position);
      walls.push_back(w);
      break;
    }
    case ContainerKind::Drum: {
      // The drum's surface only: the floor z = 0 is its lowest line, which turns with it.
      require_positive(c.radius, "radius", c);
      if (dimension == 3) require_positive(c.size_y, "length", c);
      if (dimension == 3 && c.periodic_ends)
        throw std::runtime_error(
            "container 'drum' (periodic ends): DEM export of a drum with periodic ends is not supported (its mesh "
            "would cross the periodic boundary, and YADE's cell is not written for it); relax or rotate drums with "
            "ends = \"walls\", or 2D drums");
      DemWall w;
      w.kind = DemWall::Kind::Mesh;
      w.name = "drum";
      w.drum_radius = c.radius;
      w.drum_half = 0.5 * c.size_y;
      w.drum_ends = dimension == 3 && !c.periodic_ends;
      walls.assign(1, w);
      break;
    }
  }
  return walls;
}

}  // namespace btr
