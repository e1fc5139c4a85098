#include "btr/placement/mesh_line_reach.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace btr {
namespace {

// Keeps the part of [lo, hi] where p + q s >= 0.
void keep_linear(double p, double q, HeightInterval& in) {
  if (q > 0.0) in.lo = std::max(in.lo, -p / q);
  else if (q < 0.0) in.hi = std::min(in.hi, -p / q);
  else if (p < 0.0) in.lo = 1.0, in.hi = -1.0;
}

// Keeps the part of [lo, hi] where A s^2 + B s + C <= 0 (A >= 0; A = 0 only for a line along the axis, where
// B = 0 too: then all or nothing).
void keep_quadratic(double A, double B, double C, HeightInterval& in) {
  if (A <= 1e-14) {
    if (C > 0.0) in.lo = 1.0, in.hi = -1.0;
    return;
  }
  const double disc = B * B - 4.0 * A * C;
  if (disc < 0.0) {
    in.lo = 1.0, in.hi = -1.0;
    return;
  }
  const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));  // the roots without cancellation
  double s1 = q / A, s2 = q != 0.0 ? C / q : 0.0;
  if (s1 > s2) std::swap(s1, s2);
  in.lo = std::max(in.lo, s1), in.hi = std::min(in.hi, s2);
}

void join(HeightInterval& all, const HeightInterval& part) {
  if (part.empty()) return;
  if (all.empty()) all = part;
  else all.lo = std::min(all.lo, part.lo), all.hi = std::max(all.hi, part.hi);
}

}  // namespace

HeightInterval line_within(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n, const Vec3& x, double d) {
  const double inf = std::numeric_limits<double>::infinity();
  HeightInterval all;
  const Vec3* v[3] = {&a, &b, &c};
  // The slab over the face: within d of the plane, the foot inside the three edges (the edges' in-plane normals
  // are orthogonal to n, so the foot's test is the point's).
  if (n.allFinite()) {
    HeightInterval face{-inf, inf};
    const double h = n.dot(x - a);
    keep_linear(d - h, -n.z(), face);
    keep_linear(d + h, n.z(), face);
    for (int j = 0; j < 3 && !face.empty(); ++j) {
      const Vec3 &p = *v[j], &q = *v[(j + 1) % 3], &o = *v[(j + 2) % 3];
      Vec3 m = n.cross(q - p);
      if (m.dot(o - p) < 0.0) m = -m;
      keep_linear(m.dot(x - p), m.z(), face);
    }
    join(all, face);
  }
  for (int j = 0; j < 3; ++j) {
    const Vec3 &p = *v[j], &q = *v[(j + 1) % 3];
    const Vec3 w = x - p;
    // The vertex's sphere: |w + s z|^2 <= d^2.
    HeightInterval ball{-inf, inf};
    keep_quadratic(1.0, 2.0 * w.z(), w.squaredNorm() - d * d, ball);
    join(all, ball);
    // The edge's cylinder, between its ends: |w + s z|^2 - (u.(w + s z))^2 <= d^2 with 0 <= u.(w + s z) <= L.
    const double L = (q - p).norm();
    if (!(L > 0.0)) continue;
    const Vec3 u = (q - p) / L;
    const double s0 = u.dot(w);
    HeightInterval tube{-inf, inf};
    keep_linear(s0, u.z(), tube);
    keep_linear(L - s0, -u.z(), tube);
    if (!tube.empty()) keep_quadratic(1.0 - u.z() * u.z(), 2.0 * (w.z() - s0 * u.z()), w.squaredNorm() - s0 * s0 - d * d, tube);
    join(all, tube);
  }
  return all;
}

}  // namespace btr
