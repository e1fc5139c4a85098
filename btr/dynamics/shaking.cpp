#include "btr/dynamics/shaking.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "btr/placement/deposition.h"

namespace btr {

Shaker::Shaker(int dimension, const Container& container, double lift, double noise, std::uint64_t seed)
    : dimension_(dimension), container_(container), lift_(lift), noise_(noise), rng_(seed) {}

std::vector<std::size_t> Shaker::height_order(const Grains& grains) {
  // The heights sorted with their indices beside them (no reads into the grains while sorting); the
  // index breaks ties, so this is the stable order by height.
  std::vector<std::pair<double, std::size_t>> keyed(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) keyed[i] = {grains[i].x.z(), i};
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::size_t> order(grains.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

void Shaker::keep_inside(double& x, double& y, double r) const {
  const Container& c = container_;
  auto clamp = [](double& v, double half) { v = std::clamp(v, -half, half); };
  switch (c.kind) {
    case ContainerKind::Box:
      clamp(x, 0.5 * c.size_x - r);
      if (dimension_ == 3) clamp(y, 0.5 * c.size_y - r);
      break;
    case ContainerKind::HeleShaw:
      clamp(x, 0.5 * c.size_x - r);
      clamp(y, 0.5 * c.gap - r);
      break;
    case ContainerKind::Cylinder: {
      const double rho = std::hypot(x, y), max = c.radius - r;
      if (rho > max) x *= max / rho, y *= max / rho;
      break;
    }
    default: break;
  }
}

Grains Shaker::cycle(const Grains& grains) {
  Grains out(grains.size());
  if (grains.empty()) return out;
  const double r_max = max_radius(grains);
  Deposition engine(dimension_, container_, r_max);
  for (std::size_t i : height_order(grains)) {
    const Grain& g = grains[i];
    Drop d{g.x.x(), dimension_ == 3 ? g.x.y() : 0.0, g.r, g.species, g.x.z() + lift_};
    if (noise_ > 0.0) {
      d.x += noise_ * (2.0 * uniform() - 1.0);
      if (dimension_ == 3) d.y += noise_ * (2.0 * uniform() - 1.0);
      keep_inside(d.x, d.y, d.r);
    }
    const Grain& placed = engine.place(d);
    out[i] = placed;
  }
  return out;
}

}  // namespace btr
