#pragma once
// A circular arc P(t) = C + rho (cos t u + sin t v), t in [0, t_end]: the path of a grain rolling on
// one grain (a meridian of the contact sphere) or on two supports (where two contact surfaces meet).
#include <Eigen/Geometry>
#include <cmath>

#include "btr/grain.h"

namespace btr {

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

constexpr double kTwoPi = 6.283185307179586476925286766559;

// Smallest t in (t_min, t_max] with a cos t + b sin t = c where the left side is increasing
// (crossing c from below). Returns a negative value when there is none.
double first_rising_root(double a, double b, double c, double t_min, double t_max);

// All t in (t_min, t_max] with a cos t + b sin t = c, ascending; returns how many (0, 1 or 2).
int trig_roots(double a, double b, double c, double t_min, double t_max, double out[2]);

}  // namespace btr
