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
  const double za = container_.radius, c = std::cos(dphi), s = std::sin(dphi);
  const double px = x.x(), pz = x.z() - za;
  return Vec3(px * c - pz * s, x.y(), za + px * s + pz * c);
}

Grains DrumStepper::step(const Grains& grains, double dphi) const {
  Grains moved(grains.size());
  double r_max = 0.0;
  for (std::size_t i = 0; i < grains.size(); ++i) {
    moved[i] = grains[i];
    moved[i].x = rotate(grains[i].x, dphi);
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
  // Every grain is lifted by the same amount, so the order by height is the order after rotation; the
  // engine keeps each lifted start inside the drum.
  for (std::size_t i : Shaker::height_order(moved)) {
    const Grain& g = moved[i];
    Drop d{g.x.x(), dimension_ == 3 ? g.x.y() : 0.0, g.r, g.species, g.x.z() + lift_};
    out[i] = engine.place(d);
  }
  return out;
}

}  // namespace btr
