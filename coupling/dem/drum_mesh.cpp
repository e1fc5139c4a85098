#include "coupling/dem/drum_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace btr {

int drum_panels(double radius, double r_min) {
  if (!(radius > 0.0) || !(r_min > 0.0)) throw std::invalid_argument("drum_panels: radius and r_min must be positive");
  // 1 - cos(pi/n) <= f r_min / R, n a power of two (the end discs halve it ring by ring)
  const double bound = kDrumSagittaFraction * r_min / radius;
  int n = 64;
  while (1.0 - std::cos(M_PI / n) > bound && n < (1 << 24)) n *= 2;
  return n;
}

namespace {

// An end disc at y in the plane of the rim ring (vertices first..first+n-1, n a power of two >= 8): rings of
// half as many vertices, each inward by the outer ring's vertex spacing, down to 8 vertices, then a fan of 8
// to the centre. Triangles of about equal sides, so their bounding boxes stay small (a fan of n long
// triangles from the centre would put a grain near it in the boxes of a quarter of them: YADE's collider
// then tests each). `outward` orients the triangles' normals (+1: +y).
void add_end_disc(TriangleMesh& m, int first, int n, double rho, double y, double za, int outward) {
  auto tri = [&](int a, int b, int c) {
    if (outward > 0) m.triangles.push_back({a, b, c});
    else m.triangles.push_back({a, c, b});
  };
  while (n > 8) {
    const double inner = rho * (1.0 - 2.0 * M_PI / n);
    const int half = n / 2, start = static_cast<int>(m.vertices.size());
    for (int i = 0; i < half; ++i) {
      const double a = 2.0 * M_PI * (2 * i) / n;
      m.vertices.emplace_back(inner * std::cos(a), y, za + inner * std::sin(a));
    }
    for (int i = 0; i < half; ++i) {
      const int o0 = first + 2 * i, o1 = first + 2 * i + 1, o2 = first + (2 * i + 2) % n;
      const int i0 = start + i, i1 = start + (i + 1) % half;
      tri(o1, o0, i0);
      tri(o2, o1, i1);
      tri(i1, o1, i0);
    }
    first = start, n = half, rho = inner;
  }
  const int centre = static_cast<int>(m.vertices.size());
  m.vertices.emplace_back(0.0, y, za);
  for (int k = 0; k < n; ++k) tri(first + (k + 1) % n, first + k, centre);
}

}  // namespace

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
    add_end_disc(*m, 0, n, rv, -half, za, -1);
    add_end_disc(*m, n, n, rv, half, za, +1);
  }
  m->lo = Vec3(-rv, -half, za - rv);
  m->hi = Vec3(rv, half, za + rv);
  return m;
}

}  // namespace btr
