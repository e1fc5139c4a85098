#pragma once
// A circular arc P(t) = C + rho (cos t u + sin t v), t in [0, t_end]: the path of a grain rolling on
// one grain (a meridian of the contact sphere) or on two supports (where two contact surfaces meet).
#include <Eigen/Geometry>
#include <cmath>

#include "btr/model/grain.h"

namespace btr {

constexpr double kTwoPi = 6.283185307179586476925286766559;

struct CircleArc {
  Vec3 C = Vec3::Zero();
  double rho = 0.0;
  Vec3 u = Vec3::UnitX(), v = Vec3::UnitY();  // orthonormal; P(0) = C + rho u, P'(0) along v
  double t_end = 0.0;

  Vec3 at(double t) const { return C + rho * (std::cos(t) * u + std::sin(t) * v); }
  Vec3 tangent(double t) const { return -std::sin(t) * u + std::cos(t) * v; }
  Vec3 axis() const { return u.cross(v); }
  // Axis-aligned box around the arc.
  void bounds(Vec3& lo, Vec3& hi) const;
};

// Smallest t in (t_min, t_max] with a cos t + b sin t = c where the left side is increasing
// (crossing c from below). Returns a negative value when there is none. screen (optional) is
// root_screen(t_max): a root whose direction lies beyond it is rejected before its angle is computed.
double first_rising_root(double a, double b, double c, double t_min, double t_max, double screen = 5.0);

// A monotone stand-in for the angle of the direction (x, y) over [0, 2 pi), in [0, 4): comparing two of
// them orders the angles without inverse trigonometry.
inline double pseudo_angle(double x, double y) {
  const double p = x / (std::abs(x) + std::abs(y));
  return y >= 0.0 ? 1.0 - p : 3.0 + p;
}
// The screen for roots up to t_max: the pseudo-angle of t_max plus a margin (1e-9, far above its
// round-off and below nothing the roots' own tolerance needs); no screen (5) when t_max is near 2 pi.
inline double root_screen(double t_max) {
  if (!(t_max < kTwoPi - 1e-6)) return 5.0;
  return pseudo_angle(std::cos(t_max), std::sin(t_max)) + 1e-9;
}

// All t in (t_min, t_max] with a cos t + b sin t = c, ascending; returns how many (0, 1 or 2).
// screen as for first_rising_root.
int trig_roots(double a, double b, double c, double t_min, double t_max, double out[2], double screen = 5.0);

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
double first_tube_exit(const CircleArc& arc, const Vec3& point, int axis, double R, double t_max);

}  // namespace btr
