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
  }
  return "?";
}

bool wraps_x(const Container& c) { return c.kind == ContainerKind::Periodic; }

bool wraps_y(const Container& c, int dimension) {
  return dimension == 3 && (c.kind == ContainerKind::Periodic || (c.kind == ContainerKind::Drum && c.periodic_ends));
}

}  // namespace btr
