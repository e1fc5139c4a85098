#pragma once
// Containers the BTR tests build by hand (lengths in metres or in radii, as each test says).
#include "btr/model/container.h"

namespace btr::test {

inline Container box(double sx, double sy = 0.0) {
  Container c;
  c.kind = ContainerKind::Box;
  c.size_x = sx;
  c.size_y = sy;
  return c;
}

inline Container periodic(double sx, double sy = 0.0) {
  Container c = box(sx, sy);
  c.kind = ContainerKind::Periodic;
  return c;
}

}  // namespace btr::test
