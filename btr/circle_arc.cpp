#include "btr/circle_arc.h"

#include <algorithm>

namespace btr {

void CircleArc::bounds(Vec3& lo, Vec3& hi) const {
  Vec3 p0 = at(0.0), p1 = at(t_end);
  lo = p0.cwiseMin(p1);
  hi = p0.cwiseMax(p1);
  for (int k = 0; k < 3; ++k) {
    // Extremes of component k at t* = atan2(v_k, u_k) and t* + pi.
    double ts = std::atan2(v[k], u[k]);
    for (double t : {ts, ts + M_PI, ts - M_PI, ts + kTwoPi}) {
      if (t > 0.0 && t < t_end) {
        double x = C[k] + rho * (std::cos(t) * u[k] + std::sin(t) * v[k]);
        lo[k] = std::min(lo[k], x);
        hi[k] = std::max(hi[k], x);
      }
    }
  }
}

double first_rising_root(double a, double b, double c, double t_min, double t_max) {
  // a cos t + b sin t = A cos(t - phi), rising where sin(t - phi) < 0.
  const double A = std::hypot(a, b);
  if (A <= 0.0 || std::abs(c) > A) return -1.0;
  const double phi = std::atan2(b, a);
  const double delta = std::acos(std::clamp(c / A, -1.0, 1.0));
  // Rising root: t - phi = -delta (mod 2 pi).
  double t = phi - delta;
  t = std::fmod(t, kTwoPi);
  if (t < 0.0) t += kTwoPi;
  while (t <= t_min) t += kTwoPi;
  return t <= t_max ? t : -1.0;
}

int trig_roots(double a, double b, double c, double t_min, double t_max, double out[2]) {
  const double A = std::hypot(a, b);
  if (A <= 0.0 || std::abs(c) > A) return 0;
  const double phi = std::atan2(b, a);
  const double delta = std::acos(std::clamp(c / A, -1.0, 1.0));
  int n = 0;
  for (double t : {phi - delta, phi + delta}) {
    t = std::fmod(t, kTwoPi);
    if (t < 0.0) t += kTwoPi;
    while (t <= t_min) t += kTwoPi;
    if (t <= t_max) out[n++] = t;
  }
  if (n == 2 && out[1] < out[0]) std::swap(out[0], out[1]);
  return n;
}

}  // namespace btr
