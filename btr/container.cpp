#include "btr/container.h"

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

}  // namespace btr
