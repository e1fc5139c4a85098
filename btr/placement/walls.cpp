#include "btr/placement/walls.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace btr {
namespace {

Obstacle plane(int number, const Vec3& normal, double offset) {
  Obstacle o;
  o.kind = Obstacle::Kind::Plane;
  o.key = -1 - number;
  o.c = normal;
  o.R = offset;
  return o;
}

}  // namespace

void container_walls(const Container& c, int dimension, double r, std::vector<Obstacle>& walls) {
  walls.clear();
  walls.push_back(plane(0, Vec3::UnitZ(), r));  // the floor: z = r
  auto x_walls = [&](double half) {
    walls.push_back(plane(1, Vec3::UnitX(), -half + r));
    walls.push_back(plane(2, -Vec3::UnitX(), -(half - r)));
  };
  auto y_walls = [&](double half) {
    walls.push_back(plane(3, Vec3::UnitY(), -half + r));
    walls.push_back(plane(4, -Vec3::UnitY(), -(half - r)));
  };
  switch (c.kind) {
    case ContainerKind::Open:
    case ContainerKind::Periodic:
    case ContainerKind::Mesh:  // the triangles are the walls (btr/placement/mesh_placement.cpp)
      break;
    case ContainerKind::Box:
      x_walls(0.5 * c.size_x);
      if (dimension == 3) y_walls(0.5 * c.size_y);
      break;
    case ContainerKind::HeleShaw:
      x_walls(0.5 * c.size_x);
      y_walls(0.5 * c.gap);
      break;
    case ContainerKind::Cylinder: {
      Obstacle o;
      o.kind = Obstacle::Kind::Cylinder;
      o.key = -6;
      o.R = c.radius - r;
      walls.push_back(o);
      break;
    }
    case ContainerKind::Drum: {
      // The floor z = r stays walls[0]: it touches the drum's centre surface only on its lowest line.
      if (dimension == 3 && !c.periodic_ends) y_walls(0.5 * c.size_y);
      Obstacle o;
      o.kind = Obstacle::Kind::Drum;
      o.key = -7;
      o.c = Vec3(0.0, 0.0, c.radius);
      o.R = c.radius - r;
      walls.push_back(o);
      break;
    }
  }
}

namespace {

// Where a drop's centre may be: within wall_x - r of the axis in x and wall_y - r in y on the bounded
// axes, or, round (the cylinder), within wall_x - r of the z axis.
struct Footprint {
  bool round = false, bound_x = false, bound_y = false;
  double wall_x = 0.0, wall_y = 0.0;
};

Footprint footprint(const Container& c, int dimension) {
  Footprint f;
  switch (c.kind) {
    case ContainerKind::Open:
    case ContainerKind::Periodic:
      break;
    case ContainerKind::Box:
    case ContainerKind::Mesh:  // its bounding box; the mesh's own footprint is MeshIndex::footprint_misfit
      f.bound_x = true, f.wall_x = 0.5 * c.size_x;
      f.bound_y = dimension == 3, f.wall_y = 0.5 * c.size_y;
      break;
    case ContainerKind::HeleShaw:
      f.bound_x = f.bound_y = true, f.wall_x = 0.5 * c.size_x, f.wall_y = 0.5 * c.gap;
      break;
    case ContainerKind::Cylinder:
      f.round = true, f.wall_x = c.radius;
      break;
    case ContainerKind::Drum:
      f.bound_x = true, f.wall_x = c.radius;
      f.bound_y = dimension == 3 && !c.periodic_ends, f.wall_y = 0.5 * c.size_y;
      break;
  }
  return f;
}

}  // namespace

std::string drop_misfit(const Container& c, int dimension, double x, double y, double r) {
  const Footprint f = footprint(c, dimension);
  const double slack = 1e-12 * r;
  const bool out_round = f.round && std::hypot(x, y) > f.wall_x - r + slack;
  const bool out_x = f.bound_x && std::abs(x) > f.wall_x - r + slack;
  const bool out_y = f.bound_y && std::abs(y) > f.wall_y - r + slack;
  if (!out_round && !out_x && !out_y) return {};  // the hot path: no stream unless the drop does not fit
  std::ostringstream why;
  if (out_round)
    why << "(x, y) = (" << x << ", " << y << ") puts a grain of radius " << r << " through the cylinder of radius "
        << c.radius;
  if (out_x) {
    why << "x = " << x << " puts a grain of radius " << r;
    if (c.kind == ContainerKind::Drum) why << " through the drum of radius " << c.radius << "; ";
    else why << " through the wall at +-" << f.wall_x << "; ";
  }
  if (out_y) why << "y = " << y << " puts a grain of radius " << r << " through the wall at +-" << f.wall_y << "; ";
  return why.str();
}

void onto_footprint(const Container& c, int dimension, double& x, double& y, double r) {
  const Footprint f = footprint(c, dimension);
  if (f.round) {
    const double R = f.wall_x - r, h = std::hypot(x, y);
    if (h > R) x *= R / h, y *= R / h;
  }
  if (f.bound_x) x = std::clamp(x, -(f.wall_x - r), f.wall_x - r);
  if (f.bound_y) y = std::clamp(y, -(f.wall_y - r), f.wall_y - r);
}

}  // namespace btr
