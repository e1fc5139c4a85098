#include "btr/model/cluster.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace btr {

void ClusterShape::centre(int dimension) {
  Vec3 g = Vec3::Zero();
  double m = 0.0;
  for (std::size_t k = 0; k < size(); ++k) {
    const double mk = std::pow(radii[k], dimension);
    g += mk * offsets[k];
    m += mk;
  }
  if (m <= 0.0) return;
  g /= m;
  for (Vec3& x : offsets) x -= g;
}

double ClusterShape::extent() const {
  double e = 0.0;
  for (std::size_t k = 0; k < size(); ++k) e = std::max(e, offsets[k].norm() + radii[k]);
  return e;
}

namespace {

double uniform(std::mt19937_64& rng) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }

Vec3 random_direction(int dimension, std::mt19937_64& rng) {
  if (dimension == 2) {
    const double a = 2.0 * M_PI * uniform(rng);
    return Vec3(std::cos(a), 0.0, std::sin(a));
  }
  const double z = 2.0 * uniform(rng) - 1.0, a = 2.0 * M_PI * uniform(rng);
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Vec3(s * std::cos(a), s * std::sin(a), z);
}

}  // namespace

ClusterShape random_compact_cluster(int dimension, int n, std::mt19937_64& rng,
                                    const std::function<double(std::mt19937_64&)>& radius, int species) {
  ClusterShape shape;
  if (n < 1) return shape;
  shape.add(Vec3::Zero(), radius(rng), species);
  constexpr int kCandidates = 8;
  while (static_cast<int>(shape.size()) < n) {
    const double r = radius(rng);
    Vec3 g = Vec3::Zero();
    for (const Vec3& x : shape.offsets) g += x;
    g /= static_cast<double>(shape.size());
    bool found = false;
    Vec3 best;
    double best_d = 0.0;
    for (int attempt = 0; attempt < 1000 && !(found && attempt >= kCandidates); ++attempt) {
      const std::size_t j = std::uniform_int_distribution<std::size_t>(0, shape.size() - 1)(rng);
      const Vec3 x = shape.offsets[j] + (shape.radii[j] + r) * random_direction(dimension, rng);
      bool free = true;
      for (std::size_t k = 0; k < shape.size() && free; ++k)
        if (k != j && (x - shape.offsets[k]).norm() < shape.radii[k] + r) free = false;
      if (!free) continue;
      const double d = (x - g).norm();
      if (!found || d < best_d) { best = x; best_d = d; found = true; }
    }
    if (!found) break;  // unreachable in practice: the outermost member always has free room
    shape.add(best, r, species);
  }
  shape.centre(dimension);
  return shape;
}

Eigen::Quaterniond random_orientation(int dimension, std::mt19937_64& rng) {
  if (dimension == 2) return Eigen::Quaterniond(Eigen::AngleAxisd(2.0 * M_PI * uniform(rng), Vec3::UnitY()));
  // Shoemake's uniform random rotation.
  const double u1 = uniform(rng), u2 = 2.0 * M_PI * uniform(rng), u3 = 2.0 * M_PI * uniform(rng);
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)).normalized();
}

std::vector<std::vector<std::size_t>> rigid_bodies(const Grains& grains) {
  std::vector<std::vector<std::size_t>> bodies;
  std::map<std::int32_t, std::size_t> slot;
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const std::int32_t c = grains[i].cluster;
    if (c == 0) { bodies.push_back({i}); continue; }
    auto [it, fresh] = slot.emplace(c, bodies.size());
    if (fresh) bodies.emplace_back();
    bodies[it->second].push_back(i);
  }
  return bodies;
}

}  // namespace btr
