#include "btr/model/container.h"

namespace btr {

const char* to_string(ContainerKind kind) {
  switch (kind) {
    case ContainerKind::Open: return "open";
    case ContainerKind::Box: return "box";
    case ContainerKind::Periodic: return "periodic";
    case ContainerKind::HeleShaw: return "hele-shaw";
    case ContainerKind::Cylinder: return "cylinder";
    case ContainerKind::Drum: return "drum";
    case ContainerKind::Mesh: return "mesh";
  }
  return "?";
}

bool wraps_x(const Container& c) { return c.kind == ContainerKind::Periodic; }

bool wraps_y(const Container& c, int dimension) {
  return dimension == 3 && (c.kind == ContainerKind::Periodic || (c.kind == ContainerKind::Drum && c.periodic_ends));
}

double period_along(const Container& c, int dimension, int axis) {
  if (axis == 0) return wraps_x(c) ? c.size_x : 0.0;
  return axis == 1 && wraps_y(c, dimension) ? c.size_y : 0.0;
}

Vec3 wrap_into_cell(const Container& c, int dimension, Vec3 x) {
  if (wraps_x(c)) x.x() = wrap_coordinate(x.x(), c.size_x);
  if (wraps_y(c, dimension)) x.y() = wrap_coordinate(x.y(), c.size_y);
  return x;
}

}  // namespace btr
