#include "btr/drum.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "btr/deposition.h"
#include "btr/shaking.h"

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
    if (dimension_ == 3) {  // a grain on an end wall may sit there within round-off
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

DrumMeasures drum_measures(const Grains& grains, int dimension, const Container& container) {
  DrumMeasures m;
  if (grains.empty()) return m;
  const double za = container.radius;
  std::vector<double> radii;
  double w_sum = 0.0, r_max = 0.0;
  for (const Grain& g : grains) {
    radii.push_back(g.r);
    const double w = dimension == 3 ? g.r * g.r * g.r : g.r * g.r;
    m.com_x += w * g.x.x(), m.com_z += w * g.x.z(), w_sum += w;
    r_max = std::max(r_max, g.r);
  }
  m.com_x /= w_sum, m.com_z /= w_sum;
  std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
  m.split_radius = radii[radii.size() / 2];
  double n_small = 0, n_large = 0;
  for (const Grain& g : grains) {
    const double axis = std::hypot(g.x.x(), g.x.z() - za), core = std::hypot(g.x.x() - m.com_x, g.x.z() - m.com_z);
    if (g.r <= m.split_radius) m.axis_small += axis, m.core_small += core, ++n_small;
    else m.axis_large += axis, m.core_large += core, ++n_large;
  }
  if (n_small) m.axis_small /= n_small, m.core_small /= n_small;
  if (n_large) m.axis_large /= n_large, m.core_large /= n_large;
  m.segregation_index = n_small && n_large ? (m.axis_large - m.axis_small) / container.radius : 0.0;

  const double half = 0.6 * container.radius, width = 2.0 * r_max;
  const int n = std::max(1, static_cast<int>(std::floor(2.0 * half / width)));
  std::vector<double> top(n, -1.0);
  for (const Grain& g : grains) {
    if (g.x.x() < -half || g.x.x() >= half) continue;
    const int k = std::min(n - 1, static_cast<int>((g.x.x() + half) / (2.0 * half) * n));
    top[k] = std::max(top[k], g.x.z() + g.r);
  }
  double sx = 0, sz = 0, sxx = 0, sxz = 0, k_used = 0;
  for (int k = 0; k < n; ++k) {
    if (top[k] < 0.0) continue;
    const double x = -half + (k + 0.5) * (2.0 * half / n);
    sx += x, sz += top[k], sxx += x * x, sxz += x * top[k], ++k_used;
  }
  if (k_used >= 3) {
    const double slope = (k_used * sxz - sx * sz) / (k_used * sxx - sx * sx);
    m.surface_valid = true;
    m.surface_angle_deg = std::atan(slope) * 180.0 / M_PI;
  }
  return m;
}

}  // namespace btr
