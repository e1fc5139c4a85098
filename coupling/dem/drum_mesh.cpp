#include "coupling/dem/drum_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace btr {

int drum_panels(double radius, double r_min) {
  if (!(radius > 0.0) || !(r_min > 0.0)) throw std::invalid_argument("drum_panels: radius and r_min must be positive");
  // 1 - cos(pi/n) <= f r_min / R  <=>  n >= pi / acos(1 - f r_min / R)
  const double c = std::max(-1.0, 1.0 - kDrumSagittaFraction * r_min / radius);
  return std::max(64, static_cast<int>(std::ceil(M_PI / std::acos(c))));
}

std::shared_ptr<const TriangleMesh> drum_mesh(const Container& c, int dimension, const Grains& grains) {
  if (c.kind != ContainerKind::Drum) throw std::invalid_argument("drum_mesh: the container is not a drum");
  if (grains.empty()) throw std::invalid_argument("drum_mesh: no grains");
  double r_min = std::numeric_limits<double>::infinity(), r_max = 0.0;
  for (const Grain& g : grains) r_min = std::min(r_min, g.r), r_max = std::max(r_max, g.r);
  const int n = drum_panels(c.radius, r_min);
  const double rv = c.radius / std::cos(M_PI / n), za = c.radius;
  const double half = dimension == 2 ? 0.5 * r_max : 0.5 * c.size_y;
  auto m = std::make_shared<TriangleMesh>();
  m->file = "(generated: drum of radius " + std::to_string(c.radius) + " m, " + std::to_string(n) + " panels)";
  // Vertex k of ring s (s = 0 at y = -half, 1 at +half): angle 2 pi k / n, panel k spans vertices k, k+1 and is
  // tangent to the cylinder at its middle. Panel 0's middle is at angle pi/n; none is tangent at the lowest line
  // unless n is odd, which does not matter: every panel is tangent to the cylinder.
  for (int s = 0; s < 2; ++s)
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * M_PI * k / n;
      m->vertices.emplace_back(rv * std::cos(a), s == 0 ? -half : half, za + rv * std::sin(a));
    }
  for (int k = 0; k < n; ++k) {
    const int k1 = (k + 1) % n;
    m->triangles.push_back({k, k1, n + k1});
    m->triangles.push_back({k, n + k1, n + k});
  }
  if (dimension == 3 && !c.periodic_ends) {
    const int lo = static_cast<int>(m->vertices.size());
    m->vertices.emplace_back(0.0, -half, za);
    m->vertices.emplace_back(0.0, half, za);
    for (int k = 0; k < n; ++k) {
      const int k1 = (k + 1) % n;
      m->triangles.push_back({lo, k1, k});
      m->triangles.push_back({lo + 1, n + k, n + k1});
    }
  }
  m->lo = Vec3(-rv, -half, za - rv);
  m->hi = Vec3(rv, half, za + rv);
  return m;
}

}  // namespace btr
