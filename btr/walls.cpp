#include "btr/walls.h"

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

// Does the drop fit? (The hot path: no stream is built unless it does not.)
bool drop_fits(const Container& c, int dimension, double x, double y, double r) {
  const double slack = 1e-12 * r;
  auto fits = [&](double v, double half) { return !(std::abs(v) > half - r + slack); };
  switch (c.kind) {
    case ContainerKind::Open:
    case ContainerKind::Periodic:
      return true;
    case ContainerKind::Box:
      return fits(x, 0.5 * c.size_x) && (dimension != 3 || fits(y, 0.5 * c.size_y));
    case ContainerKind::HeleShaw:
      return fits(x, 0.5 * c.size_x) && fits(y, 0.5 * c.gap);
    case ContainerKind::Cylinder:
      return !(std::hypot(x, y) > c.radius - r + slack);
    case ContainerKind::Drum:
      return fits(x, c.radius) && (dimension != 3 || c.periodic_ends || fits(y, 0.5 * c.size_y));
  }
  return false;
}

}  // namespace

std::string drop_misfit(const Container& c, int dimension, double x, double y, double r) {
  if (drop_fits(c, dimension, x, y, r)) return {};
  std::ostringstream why;
  const double slack = 1e-12 * r;
  auto check = [&](double v, double half, const char* axis) {
    if (std::abs(v) > half - r + slack)
      why << axis << " = " << v << " puts a grain of radius " << r << " through the wall at +-" << half << "; ";
  };
  switch (c.kind) {
    case ContainerKind::Open:
    case ContainerKind::Periodic:
      break;
    case ContainerKind::Box:
      check(x, 0.5 * c.size_x, "x");
      if (dimension == 3) check(y, 0.5 * c.size_y, "y");
      break;
    case ContainerKind::HeleShaw:
      check(x, 0.5 * c.size_x, "x");
      check(y, 0.5 * c.gap, "y");
      break;
    case ContainerKind::Cylinder:
      if (std::hypot(x, y) > c.radius - r + slack)
        why << "(x, y) = (" << x << ", " << y << ") puts a grain of radius " << r
            << " through the cylinder of radius " << c.radius;
      break;
    case ContainerKind::Drum:
      if (std::abs(x) > c.radius - r + slack)
        why << "x = " << x << " puts a grain of radius " << r << " through the drum of radius " << c.radius << "; ";
      if (dimension == 3 && !c.periodic_ends) check(y, 0.5 * c.size_y, "y");
      break;
  }
  return why.str();
}

}  // namespace btr
