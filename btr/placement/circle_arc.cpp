#include "btr/placement/circle_arc.h"

#include <algorithm>
#include <limits>

namespace btr {

void CircleArc::bounds(Vec3& lo, Vec3& hi) const {
  // The ends, then the extremes of each component k, C_k -+ rho |(u_k, v_k)| where (cos t, sin t) is
  // -+(u_k, v_k) / |(u_k, v_k)|, when that point lies inside the arc (0, t_end): no inverse trigonometry.
  const ArcDirection e = direction_of(t_end, end);
  const double ce = e.c, se = e.s;
  const Vec3 p0 = C + rho * u, p1 = C + rho * (ce * u + se * v);
  lo = p0.cwiseMin(p1);
  hi = p0.cwiseMax(p1);
  // Is the direction of (c, s) at an angle in (0, t_end) (t_end in [0, 2 pi])? Only signs are read, so
  // (c, s) need not be a unit vector: (u_k, v_k) itself, without the divisions by its length.
  const bool half_turn = end_within_half_turn();
  auto inside = [&](double c, double s) {
    const double after_end = c * se - s * ce;  // > 0: (c, s) is before the end direction (within pi of it)
    if (half_turn) return s > 0.0 && after_end > 0.0;
    return s > 0.0 || after_end > 0.0;
  };
  for (int k = 0; k < 3; ++k) {
    const double m = std::sqrt(u[k] * u[k] + v[k] * v[k]);
    if (m <= 0.0) continue;
    if (inside(u[k], v[k])) hi[k] = std::max(hi[k], C[k] + rho * m);
    if (inside(-u[k], -v[k])) lo[k] = std::min(lo[k], C[k] - rho * m);
  }
}

bool CircleArc::end_within_half_turn() const {
  if (!end_pending) return t_end <= M_PI;
  // The angle is atan2(end_y, end_x), or that plus 2 pi when not positive: in (0, pi] for end_y > 0, clearly
  // past pi for end_y clearly negative; within a hair of pi, as atan2 rounds it.
  if (end_y > 0.0) return true;
  if (end.s < -1e-9) return false;
  return end_angle() <= M_PI;
}

// Roots of a cos t + b sin t = c without the amplitude's angle: with A^2 = a^2 + b^2 and q = sqrt(A^2 - c^2),
// the rising root (t = phi - delta, phi = atan2(b, a), delta = acos(c / A)) has cos t = (a c + b q) / A^2 and
// sin t = (b c - a q) / A^2, the falling one (t = phi + delta) cos t = (a c - b q) / A^2, sin t = (b c + a q) / A^2:
// one atan2 each, and A^2 cancels in it. |(x, y)| = A^2 exactly ((ac + bq)^2 + (bc - aq)^2 = (a^2 + b^2)(c^2 + q^2)), and
// to a few ulps as computed (q^2 carries the round-off of A^2 - c^2, a few ulps of A^2): (x, y) / A^2 is the root's
// direction without a square root.
namespace {

double wrap_after(double t, double t_min) {
  if (t < 0.0) t += kTwoPi;
  while (t <= t_min) t += kTwoPi;
  return t;
}

}  // namespace

double angle_after(double x, double y, double t_min) { return wrap_after(std::atan2(y, x), t_min); }

double first_rising_root(double a, double b, double c, double t_min, double t_max, double screen,
                         ArcDirection* direction) {
  TrigRoot root;
  if (!rising_root(a, b, c, root)) return -1.0;
  const double x = root.x, y = root.y;
  // Beyond t_max whatever t_min is (a root wrapped past t_min lies beyond 2 pi).
  if (screen < 5.0 && pseudo_angle(x, y) > screen) return -1.0;
  if (direction) *direction = {x / root.A2, y / root.A2};  // before the call: x and y need not be kept across it
  const double t = wrap_after(std::atan2(y, x), t_min);
  return t <= t_max ? t : -1.0;
}

int trig_roots(double a, double b, double c, double t_min, double t_max, double out[2], double screen,
               ArcDirection directions[2]) {
  const double A2 = a * a + b * b;
  if (A2 <= 0.0 || c * c > A2) return 0;
  const double q = std::sqrt(A2 - c * c);
  int n = 0;
  const double ys[2] = {b * c - a * q, b * c + a * q}, xs[2] = {a * c + b * q, a * c - b * q};
  for (int k = 0; k < 2; ++k) {
    if (screen < 5.0 && pseudo_angle(xs[k], ys[k]) > screen) continue;
    const double t = wrap_after(std::atan2(ys[k], xs[k]), t_min);
    if (t > t_max) continue;
    if (directions) directions[n] = {xs[k] / A2, ys[k] / A2};
    out[n++] = t;
  }
  if (n == 2 && out[1] < out[0]) {
    std::swap(out[0], out[1]);
    if (directions) std::swap(directions[0], directions[1]);
  }
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

namespace {

// A span of the tube exit's branch and bound: [lo, hi] with f(lo) <= level; fhi = f(hi) (only its sign
// against the level is ever read).
struct Span { double lo, hi, flo, fhi; };

// The bisection's own path to the first exit in s (fhi > level), found without evaluating f where the
// sign of f at a midpoint is certain, when f is known to rise across s. A safeguarded Newton iteration
// from x (inside s, f(x) = fx, f'(x) = dx as computed) finds the crossing to round-off; then each
// midpoint the bisection would visit is decided against it: f(m) above the level by more than the
// round-off of f is the bisection's "exit in [lo, m]", below it by more than that its "inside up to m"
// (f rises, so every point of [lo, m] is below the level too, and the bisection's search of that half
// finds nothing). Where neither is certain the function stops and the caller's bisection goes on from
// s with real evaluations, so the result is the bisection's to the last bit. Returns true when s is
// within tol (its lo is then the exit).
// f' > 0 over s is the caller's proof; curve bounds |f''|; err_f and err_s bound the round-off of f and f'
// as TubeGap computes them.
bool replay_bisection(const TubeGap& f, Span& s, double level, double x, double fx, double dx, double curve,
                      double err_f, double err_s, double tol) {
  double a = s.lo, b = s.hi;
  for (int it = 0; it < 40; ++it) {
    if (fx > level) b = x;
    else a = x;
    const double F = fx - level;
    if (std::abs(F) <= 2.0 * err_f || b - a <= 0.25 * tol) break;
    double next = dx > 0.0 ? x - F / dx : a - 1.0;
    if (!(next > a && next < b)) next = a + 0.5 * (b - a);
    x = next;
    const double c = std::cos(x), sn = std::sin(x);
    fx = f.a0 + f.a1 * c + f.b1 * sn + f.a2 * (c * c - sn * sn) + f.b2 * (2.0 * sn * c);
    dx = -f.a1 * sn + f.b1 * c - 2.0 * f.a2 * (2.0 * sn * c) + 2.0 * f.b2 * (c * c - sn * sn);
  }
  // Near x (within w) f' >= g; beyond, f still rises (f' > 0 over all of s). So f(m) - level, as computed,
  //   is above 0 for m >= x when F - margin + g min(m - x, w) > 0,
  //   is below 0 for m <= x (and so over all of [lo, m]) when F + margin - g min(x - m, w) < 0,
  // with margin twice the round-off of f. As cuts on m, each widened by a relative 1e-9 and by more than
  // the round-off of x + z:
  const double g = 0.75 * (dx - err_s);
  if (!(g > 0.0)) return false;
  const double w = 0.25 * (dx - err_s) / curve;
  const double F = fx - level, margin = 2.0 * err_f, up = (margin - F) / g, down = (margin + F) / g;
  const double inf = std::numeric_limits<double>::infinity();
  const double slack = 4e-16 * (1.0 + std::abs(x));
  const double hi_cut = up < w ? x + std::max(up, 0.0) * (1.0 + 1e-9) + slack : inf;
  const double lo_cut = down < w ? x - std::max(down, 0.0) * (1.0 + 1e-9) - slack : -inf;
  for (;;) {
    if (s.hi - s.lo <= tol) return true;  // s.fhi > level throughout
    const double h = 0.5 * (s.hi - s.lo), m = s.lo + h;
    if (m > hi_cut) {
      s.hi = m;  // f(m) > level, as computed
      s.fhi = inf;
    } else if (m < lo_cut) {
      s.lo = m;  // f <= level over [lo, m], as computed
    } else {
      return false;
    }
  }
}

}  // namespace

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
  Span stack[200];
  int n = 0;
  if (a >= t_max) return -1.0;
  // Just past a skipped tangency f may still be a round-off above 0 while heading in: an exit is then
  // where f rises above that level again.
  const double level = std::max(0.0, fa);
  // Bounds of the round-off of f and f' as TubeGap computes them: with cos and sin within 1 ulp and u =
  // 2^-53, f is within 6 u (|a0| + |a1| + |b1| + 2 |a2| + 2 |b2|) and f' within 6 u (|a1| + |b1| + 4 |a2| +
  // 4 |b2|) (the products' errors and the four additions'); taken 3 times that. And |f''| a hair above its bound.
  const double s1 = std::abs(f.a1) + std::abs(f.b1), s2 = std::abs(f.a2) + std::abs(f.b2);
  const double err_f = 2e-15 * (std::abs(f.a0) + s1 + 2.0 * s2), err_s = 2e-15 * (s1 + 4.0 * s2);
  const double curve = second * (1.0 + 1e-12);
  bool replayed = false;
  stack[n++] = {a, t_max, fa, f.value(t_max)};
  while (n > 0) {
    Span s = stack[--n];
    for (;;) {
      if (s.fhi > level && s.hi - s.lo <= kTol) return s.lo;
      const double h = 0.5 * (s.hi - s.lo), m = s.lo + h, fm = f.value(m);
      if (!replayed && s.fhi > level) {
        // The first exit is in (lo, hi]. Where f provably rises across the span (so the exit is its only
        // crossing), the bisection's path to it is replayed from a Newton iteration (same result). The
        // span reaches at most h plus the round-off of m from m.
        const double dm = f.slope(m);
        if (dm - err_s - curve * (h + 4e-16 * (1.0 + m)) > 0.0) {
          replayed = true;
          if (replay_bisection(f, s, level, m, fm, dm, curve, err_f, err_s, kTol)) return s.lo;
          continue;  // the bisection goes on from where the replay could not decide
        }
      }
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
