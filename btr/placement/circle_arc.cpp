#include "btr/placement/circle_arc.h"

#include <algorithm>

namespace btr {

void CircleArc::bounds(Vec3& lo, Vec3& hi) const {
  // The ends, then the extremes of each component k, C_k -+ rho |(u_k, v_k)| where (cos t, sin t) is
  // -+(u_k, v_k) / |(u_k, v_k)|, when that point lies inside the arc (0, t_end): no inverse trigonometry.
  const double ce = std::cos(t_end), se = std::sin(t_end);
  const Vec3 p0 = C + rho * u, p1 = C + rho * (ce * u + se * v);
  lo = p0.cwiseMin(p1);
  hi = p0.cwiseMax(p1);
  // Is the direction (c, s) at an angle in (0, t_end) (t_end in [0, 2 pi])?
  auto inside = [&](double c, double s) {
    const double after_end = c * se - s * ce;  // > 0: (c, s) is before the end direction (within pi of it)
    if (t_end <= M_PI) return s > 0.0 && after_end > 0.0;
    return s > 0.0 || after_end > 0.0;
  };
  for (int k = 0; k < 3; ++k) {
    const double m = std::sqrt(u[k] * u[k] + v[k] * v[k]);
    if (m <= 0.0) continue;
    const double c = u[k] / m, s = v[k] / m;
    if (inside(c, s)) hi[k] = std::max(hi[k], C[k] + rho * m);
    if (inside(-c, -s)) lo[k] = std::min(lo[k], C[k] - rho * m);
  }
}

// Roots of a cos t + b sin t = c without the amplitude's angle: with A^2 = a^2 + b^2 and q = sqrt(A^2 - c^2),
// the rising root (t = phi - delta, phi = atan2(b, a), delta = acos(c / A)) has cos t = (a c + b q) / A^2 and
// sin t = (b c - a q) / A^2, the falling one (t = phi + delta) cos t = (a c - b q) / A^2, sin t = (b c + a q) / A^2:
// one atan2 each, and A^2 cancels in it.
namespace {

double wrap_after(double t, double t_min) {
  if (t < 0.0) t += kTwoPi;
  while (t <= t_min) t += kTwoPi;
  return t;
}

}  // namespace

double first_rising_root(double a, double b, double c, double t_min, double t_max, double screen) {
  const double A2 = a * a + b * b;
  if (A2 <= 0.0 || c * c > A2) return -1.0;
  const double q = std::sqrt(A2 - c * c);
  const double y = b * c - a * q, x = a * c + b * q;
  // Beyond t_max whatever t_min is (a root wrapped past t_min lies beyond 2 pi).
  if (screen < 5.0 && pseudo_angle(x, y) > screen) return -1.0;
  const double t = wrap_after(std::atan2(y, x), t_min);
  return t <= t_max ? t : -1.0;
}

int trig_roots(double a, double b, double c, double t_min, double t_max, double out[2], double screen) {
  const double A2 = a * a + b * b;
  if (A2 <= 0.0 || c * c > A2) return 0;
  const double q = std::sqrt(A2 - c * c);
  int n = 0;
  const double ys[2] = {b * c - a * q, b * c + a * q}, xs[2] = {a * c + b * q, a * c - b * q};
  for (int k = 0; k < 2; ++k) {
    if (screen < 5.0 && pseudo_angle(xs[k], ys[k]) > screen) continue;
    const double t = wrap_after(std::atan2(ys[k], xs[k]), t_min);
    if (t <= t_max) out[n++] = t;
  }
  if (n == 2 && out[1] < out[0]) std::swap(out[0], out[1]);
  return n;
}

TubeGap::TubeGap(const CircleArc& arc, const Vec3& point, int axis, double R) {
  Vec3 w = arc.C - point, u = arc.u, v = arc.v;
  w[axis] = u[axis] = v[axis] = 0.0;
  const double rho2 = arc.rho * arc.rho, uu = u.squaredNorm(), vv = v.squaredNorm();
  a0 = w.squaredNorm() - R * R + 0.5 * rho2 * (uu + vv);
  a1 = 2.0 * arc.rho * w.dot(u);
  b1 = 2.0 * arc.rho * w.dot(v);
  a2 = 0.5 * rho2 * (uu - vv);
  b2 = rho2 * u.dot(v);
}

double TubeGap::value(double t) const {
  const double c = std::cos(t), s = std::sin(t);
  return a0 + a1 * c + b1 * s + a2 * (c * c - s * s) + b2 * (2.0 * s * c);
}

double TubeGap::slope(double t) const {
  const double c = std::cos(t), s = std::sin(t);
  return -a1 * s + b1 * c - 2.0 * a2 * (2.0 * s * c) + 2.0 * b2 * (c * c - s * s);
}

double TubeGap::curvature(double t) const {
  const double c = std::cos(t), s = std::sin(t);
  return -a1 * c - b1 * s - 4.0 * a2 * (c * c - s * s) - 4.0 * b2 * (2.0 * s * c);
}

double TubeGap::max_bound() const { return a0 + std::hypot(a1, b1) + std::hypot(a2, b2); }

double first_tube_exit(const CircleArc& arc, const Vec3& point, int axis, double R, double t_max) {
  constexpr double kSkip = 1e-9, kApproach = 1e-9, kTol = 1e-13;
  const TubeGap f(arc, point, axis, R);
  // Round-off of f: its terms are squared lengths of the size of R^2 + |w|^2 + rho^2.
  const double scale = R * R + std::abs(f.a0) + arc.rho * arc.rho;
  if (f.max_bound() < -1e-14 * scale) return -1.0;  // the whole circle stays inside
  const double second = std::hypot(f.a1, f.b1) + 4.0 * std::hypot(f.a2, f.b2);  // bounds |f''|
  double a = 0.0, fa = f.value(0.0);
  if (std::abs(fa) <= 1e-9 * R * R) {
    const double out = f.slope(0.0), tangent = 2.0 * kApproach * arc.rho * R;
    if (out > tangent || (out >= -tangent && f.curvature(0.0) > 0.0)) return 0.0;
    a = std::min(kSkip, t_max);
    fa = f.value(a);
  } else if (fa > 0.0) {
    return 0.0;  // starts outside (not reached by a path that was inside before)
  }
  // Leftmost-first branch and bound over [a, t_max]: intervals [lo, hi] with f(lo) <= level on a stack.
  struct Span { double lo, hi, flo, fhi; };
  Span stack[200];
  int n = 0;
  if (a >= t_max) return -1.0;
  // Just past a skipped tangency f may still be a round-off above 0 while heading in: an exit is then
  // where f rises above that level again.
  const double level = std::max(0.0, fa);
  stack[n++] = {a, t_max, fa, f.value(t_max)};
  while (n > 0) {
    Span s = stack[--n];
    for (;;) {
      if (s.fhi > level && s.hi - s.lo <= kTol) return s.lo;
      const double h = 0.5 * (s.hi - s.lo), m = s.lo + h, fm = f.value(m);
      if (fm > level) {  // an exit in [lo, m]: the first one is there
        s = {s.lo, m, s.flo, fm};
        continue;
      }
      if (s.fhi <= level && h <= kTol) break;  // grazes the surface from inside within round-off: no exit
      // Inside throughout (an interval that ends outside always holds an exit, whatever round-off says).
      if (s.fhi <= level && fm + std::abs(f.slope(m)) * h + 0.5 * second * h * h <= level) break;
      if (n == 200) break;  // unreachable: the depth is at most log2(2 pi / kTol) < 50
      stack[n++] = {m, s.hi, fm, s.fhi};
      s = {s.lo, m, s.flo, fm};
    }
  }
  return -1.0;
}

}  // namespace btr
