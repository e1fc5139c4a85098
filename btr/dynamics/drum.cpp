#include "btr/dynamics/drum.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "btr/dynamics/shaking.h"
#include "btr/placement/deposition.h"

namespace btr {

DrumStepper::DrumStepper(int dimension, const Container& container, double lift)
    : dimension_(dimension), container_(container), lift_(lift) {
  if (container.kind != ContainerKind::Drum) throw std::invalid_argument("DrumStepper: the container is not a drum");
  if (!(lift > 0.0)) throw std::invalid_argument("DrumStepper: lift must be positive");
}

Vec3 DrumStepper::rotate(const Vec3& x, double dphi) const {
  return rotate(x, std::cos(dphi), std::sin(dphi));
}

Vec3 DrumStepper::rotate(const Vec3& x, double c, double s) const {
  const double za = container_.radius;
  const double px = x.x(), pz = x.z() - za;
  return Vec3(px * c - pz * s, x.y(), za + px * s + pz * c);
}

Grains DrumStepper::step(const Grains& grains, double dphi) const {
  Grains moved(grains.size());
  double r_max = 0.0;
  const double c = std::cos(dphi), s = std::sin(dphi);
  for (std::size_t i = 0; i < grains.size(); ++i) {
    moved[i] = grains[i];
    moved[i].x = rotate(grains[i].x, c, s);
    // Round-off of the rotation must not put a grain touching the wall through it.
    const double half = container_.radius - grains[i].r;
    moved[i].x.x() = std::clamp(moved[i].x.x(), -half, half);
    if (dimension_ == 3 && !container_.periodic_ends) {  // a grain on an end wall may sit there within round-off
      const double half_y = 0.5 * container_.size_y - grains[i].r;
      moved[i].x.y() = std::clamp(moved[i].x.y(), -half_y, half_y);
    }
    r_max = std::max(r_max, grains[i].r);
  }
  Grains out(grains.size());
  if (grains.empty()) return out;
  Deposition engine(dimension_, container_, r_max);
  engine.reserve(static_cast<std::int64_t>(grains.size()), false);  // the grains' array allocated once
  // Every grain is lifted by the same amount, so the order by height is the order after rotation; the
  // engine keeps each lifted start inside the drum.
  // The drops gathered in that order first: a loop of independent reads, where reading each grain
  // between two placements waited for memory every time.
  const std::vector<std::size_t> order = Shaker::height_order(moved);
  std::vector<Drop> drops(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Grain& g = moved[order[k]];
    drops[k] = Drop{g.x.x(), dimension_ == 3 ? g.x.y() : 0.0, g.r, g.species, g.x.z() + lift_};
  }
  // No Deposition::prefetch here (run_scene asks for each fall's memory ahead): in a drum its three calls a drop
  // cost more than they saved (docs/guide/bench.md, issue 22).
  for (std::size_t k = 0; k < drops.size(); ++k) out[order[k]] = engine.place(drops[k]);
  return out;
}

}  // namespace btr
