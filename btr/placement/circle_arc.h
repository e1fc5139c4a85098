#pragma once
// A circular arc P(t) = C + rho (cos t u + sin t v), t in [0, t_end]: the path of a grain rolling on
// one grain (a meridian of the contact sphere) or on two supports (where two contact surfaces meet).
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "btr/model/grain.h"

namespace btr {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// (cos t, sin t) for a parameter t of an arc, from the direction t was taken from: a root's, or an end's atan2
// arguments, divided by their length. Reading a point or a box from it needs no cosine or sine. NaN: not known.
struct ArcDirection {
  double c, s;
  static constexpr ArcDirection unknown() {
    return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  }
  bool known() const { return c == c; }
  // The direction of (x, y); not known when (x, y) = 0.
  static ArcDirection of(double x, double y) {
    const double h = std::sqrt(x * x + y * y);
    return {x / h, y / h};
  }
};
inline constexpr ArcDirection kArcStart{1.0, 0.0};  // the direction of t = 0
// d when known, else the direction of the angle t.
inline ArcDirection direction_of(double t, ArcDirection d) {
  return d.known() ? d : ArcDirection{std::cos(t), std::sin(t)};
}

struct CircleArc {
  Vec3 C = Vec3::Zero();
  double rho = 0.0;
  Vec3 u = Vec3::UnitX(), v = Vec3::UnitY();  // orthonormal; P(0) = C + rho u, P'(0) along v
  double t_end = 0.0;  // NaN while end_pending: read it by end_angle()
  // The direction of t_end when the caller knows it (set_end). Code that sets t_end alone must leave it unknown.
  ArcDirection end = ArcDirection::unknown();
  // An end set by set_end_towards whose angle is not taken yet: its direction's atan2 arguments and pseudo-angle.
  bool end_pending = false;
  double end_x = 0.0, end_y = 0.0, end_key = 0.0;

  void set_end(double t, ArcDirection direction) { t_end = t, end = direction, end_pending = false; }
  // The end at the angle of (x, y) taken in (0, 2 pi] (angle_after(x, y, 0)), only when something reads it
  // (end_angle, Event::resolve); its direction is known at once.
  void set_end_towards(double x, double y);
  double end_angle() const;
  bool end_within_half_turn() const;  // t_end <= pi
  Vec3 at(double t) const { return C + rho * (std::cos(t) * u + std::sin(t) * v); }
  Vec3 at(ArcDirection d) const { return C + rho * (d.c * u + d.s * v); }
  // The point at t, from its direction d when that is known.
  Vec3 at(double t, ArcDirection d) const { return at(direction_of(t, d)); }
  Vec3 tangent(double t) const { return -std::sin(t) * u + std::cos(t) * v; }
  Vec3 axis() const { return u.cross(v); }
  // The direction of the circle's lowest point: (cos t, sin t) along (-u_z, -v_z).
  ArcDirection lowest_direction() const { return ArcDirection::of(-u.z(), -v.z()); }
  // Axis-aligned box around the arc.
  void bounds(Vec3& lo, Vec3& hi) const;
};

// Smallest t in (t_min, t_max] with a cos t + b sin t = c where the left side is increasing
// (crossing c from below). Returns a negative value when there is none. screen (optional) is
// root_screen(t_max): a root whose direction lies beyond it is rejected before its angle is computed.
// direction (optional) receives the root's direction (cos t, sin t) when a root is returned.
double first_rising_root(double a, double b, double c, double t_min, double t_max, double screen = 5.0,
                         ArcDirection* direction = nullptr);

// The rising root of a cos t + b sin t = c as its direction (x, y) = A^2 (cos t, sin t), A^2 = a^2 + b^2 (the
// arithmetic of first_rising_root, which uses it). False when there is none.
struct TrigRoot { double x, y, A2; };
inline bool rising_root(double a, double b, double c, TrigRoot& root) {
  const double A2 = a * a + b * b;
  if (A2 <= 0.0 || c * c > A2) return false;
  const double q = std::sqrt(A2 - c * c);
  root = {a * c + b * q, b * c - a * q, A2};
  return true;
}
// The angle of the direction (x, y) taken in (t_min, t_min + 2 pi] (t_min >= 0): first_rising_root's t.
double angle_after(double x, double y, double t_min);
// atan2(y, x) > 0 without the call, for x and y finite or NaN (a unit vector's components): y > 0, or y = +0
// with x negative or -0 (the angle pi).
inline bool positive_angle(double x, double y) {
  return x == x && (y > 0.0 || (y == 0.0 && !std::signbit(y) && std::signbit(x)));
}
inline double CircleArc::end_angle() const { return end_pending ? angle_after(end_x, end_y, 0.0) : t_end; }

// A monotone stand-in for the angle of the direction (x, y) over [0, 2 pi), in [0, 4): comparing two of
// them orders the angles without inverse trigonometry.
inline double pseudo_angle(double x, double y) {
  const double p = x / (std::abs(x) + std::abs(y));
  return y >= 0.0 ? 1.0 - p : 3.0 + p;
}
// cos t and sin t to about 1e-15 (Taylor polynomials on [-pi/4, pi/4] after reduction by quarter
// turns): for the screen below and the roll queries' part boxes, which need far less than the library's
// last-bit accuracy.
inline void screen_cos_sin(double t, double& c, double& s) {
  constexpr double kHalfPiHi = 1.5707963267948966, kHalfPiLo = 6.123233995736766e-17;
  const double k = std::nearbyint(t * (2.0 / M_PI));
  const double x = (t - k * kHalfPiHi) - k * kHalfPiLo, x2 = x * x;
  const double sx = x + x * x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880 +
                    x2 * (-1.0 / 39916800 + x2 * (1.0 / 6227020800 + x2 * (-1.0 / 1307674368000.0)))))));
  const double cx = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320 + x2 * (-1.0 / 3628800 +
                    x2 * (1.0 / 479001600 + x2 * (-1.0 / 87178291200.0 + x2 * (1.0 / 20922789888000.0))))))));
  switch (static_cast<long>(k) & 3) {
    case 0: c = cx, s = sx; break;
    case 1: c = -sx, s = cx; break;
    case 2: c = -cx, s = -sx; break;
    default: c = sx, s = -cx; break;
  }
}

// The screen for roots up to t_max: the pseudo-angle of t_max plus a margin (1e-9, far above its
// round-off and below nothing the roots' own tolerance needs); no screen (5) when t_max is near 2 pi.
// A screen only rejects roots beyond t_max early: every root it lets through is still compared with
// t_max exactly, so its own accuracy (screen_cos_sin) changes no result.
constexpr double kScreenMargin = 1e-9;
inline bool has_root_screen(double t_max) { return t_max < kTwoPi - 1e-6; }
inline double root_screen(double t_max) {
  if (!has_root_screen(t_max)) return 5.0;
  double c, s;
  screen_cos_sin(t_max, c, s);
  return pseudo_angle(c, s) + kScreenMargin;
}
// root_screen(t + extra) (extra at most 1e-12) without a cosine or sine when d, the direction of t, is known (an
// event's: a root's own or the arc's end's): over that angle the pseudo-angle grows by at most as much (its slope
// is at most 1), far within the margin.
inline double root_screen_after(double t, ArcDirection d, double extra) {
  if (!d.known()) return root_screen(t + extra);
  return has_root_screen(t + extra) ? pseudo_angle(d.c, d.s) + kScreenMargin : 5.0;
}

inline void CircleArc::set_end_towards(double x, double y) {
  end = ArcDirection::of(x, y);
  end_x = x, end_y = y;
  // A pending end's pseudo-angle stands for its angle in the root screens (Event::pending_screen); near angle 0,
  // where the angle may wrap to 2 pi, it cannot, so the angle is taken at once.
  end_key = pseudo_angle(end.c, end.s);
  end_pending = end_key > kScreenMargin;
  t_end = end_pending ? std::numeric_limits<double>::quiet_NaN() : angle_after(x, y, 0.0);
}

// All t in (t_min, t_max] with a cos t + b sin t = c, ascending; returns how many (0, 1 or 2).
// screen as for first_rising_root; directions (optional) receives the roots' directions.
int trig_roots(double a, double b, double c, double t_min, double t_max, double out[2], double screen = 5.0,
               ArcDirection directions[2] = nullptr);

// The arc inside a tube: the surface at distance R from the line through `point` along coordinate axis
// `axis` (2: the vertical cylinder; 1: the drum). The squared distance from the line is the
// trigonometric polynomial of degree 2, f(t) + R^2, with
//   f(t) = a0 + a1 cos t + b1 sin t + a2 cos 2t + b2 sin 2t.
struct TubeGap {
  double a0, a1, b1, a2, b2;
  TubeGap(const CircleArc& arc, const Vec3& point, int axis, double R);
  double value(double t) const;  // > 0: outside the tube
  double slope(double t) const;
  double curvature(double t) const;
  double max_bound() const;  // an upper bound of f over all t
};

// Smallest t in [0, t_max] where the arc leaves the tube (f rises through 0), found by branch and bound
// on f with a bound of |f''|, so a grazing exit is never stepped over; t is the last point inside, to
// 1e-13. A start on the surface (|f(0)| <= 1e-9 R^2) is an exit at 0 if the arc heads out (slope, or
// zero slope and curving out); otherwise that tangency is skipped as for grains. Negative: none.
// Once a bisection interval holds the exit and f provably rises across it (f' at its middle beats the
// |f''| bound times its half-width), the rest of the bisection's path is replayed from a Newton root,
// with f evaluated only at the midpoints within its round-off of the root: the same t to the last bit,
// with about 8 evaluations of f a call instead of about 60 (a drum revolution's average).
double first_tube_exit(const CircleArc& arc, const Vec3& point, int axis, double R, double t_max);

}  // namespace btr
