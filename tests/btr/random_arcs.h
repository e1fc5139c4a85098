#pragma once
// Random circular arcs for the drum-wall exit's tests (first_tube_exit): a fixed-seed generator, and arcs about
// a unit tube along z, the same sequence in every test that draws them.
#include <cstdint>

#include "btr/placement/circle_arc.h"

namespace btr_test {

// Uniform numbers in [0, 1) from a 64-bit linear congruential generator (Knuth's MMIX constants).
struct UniformDraws {
  std::uint64_t state;
  double operator()() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(state >> 11) * 0x1.0p-53;
  }
};

// An arc about a unit tube (axis z): centre within 0.8 of the axis and up to 1 high, radius 0.05-0.55, any
// orientation, up to a full turn.
inline btr::CircleArc arc_about_unit_tube(UniformDraws& uniform) {
  btr::CircleArc arc;
  arc.C = btr::Vec3(1.6 * uniform() - 0.8, 1.6 * uniform() - 0.8, uniform());
  arc.rho = 0.05 + 0.5 * uniform();
  const btr::Vec3 u = btr::Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalized();
  arc.u = u;
  arc.v = (btr::Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).cross(u)).normalized();
  arc.t_end = btr::kTwoPi * uniform();
  return arc;
}

}  // namespace btr_test
