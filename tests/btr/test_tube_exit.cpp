// first_tube_exit (the first point where a circular arc leaves the tube of a cylinder or a drum wall):
// arcs built by hand whose exit is known in closed form, a grazing arc that just touches the wall, and
// agreement to the last bit with the plain bisection the function replays (issue 22: the bisection's
// path is now followed from a Newton iteration, evaluating the gap only where its sign is uncertain).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "btr/placement/circle_arc.h"
#include "random_arcs.h"

namespace btr {
namespace {

// The function as it was before the replay (commit 2793f0e): branch and bound, each bracket bisected
// to 1e-13. The new one must return exactly what this returns.
double bisection_tube_exit(const CircleArc& arc, const Vec3& point, int axis, double R, double t_max) {
  constexpr double kSkip = 1e-9, kApproach = 1e-9, kTol = 1e-13;
  const TubeGap f(arc, point, axis, R);
  const double scale = R * R + std::abs(f.a0) + arc.rho * arc.rho;
  if (f.max_bound() < -1e-14 * scale) return -1.0;
  const double second = std::hypot(f.a1, f.b1) + 4.0 * std::hypot(f.a2, f.b2);
  double a = 0.0, fa = f.value(0.0);
  if (std::abs(fa) <= 1e-9 * R * R) {
    const double out = f.slope(0.0), tangent = 2.0 * kApproach * arc.rho * R;
    if (out > tangent || (out >= -tangent && f.curvature(0.0) > 0.0)) return 0.0;
    a = std::min(kSkip, t_max);
    fa = f.value(a);
  } else if (fa > 0.0) {
    return 0.0;
  }
  struct Span { double lo, hi, flo, fhi; };
  Span stack[200];
  int n = 0;
  if (a >= t_max) return -1.0;
  const double level = std::max(0.0, fa);
  stack[n++] = {a, t_max, fa, f.value(t_max)};
  while (n > 0) {
    Span s = stack[--n];
    for (;;) {
      if (s.fhi > level && s.hi - s.lo <= kTol) return s.lo;
      const double h = 0.5 * (s.hi - s.lo), m = s.lo + h, fm = f.value(m);
      if (fm > level) {
        s = {s.lo, m, s.flo, fm};
        continue;
      }
      if (s.fhi <= level && h <= kTol) break;
      if (s.fhi <= level && fm + std::abs(f.slope(m)) * h + 0.5 * second * h * h <= level) break;
      if (n == 200) break;
      stack[n++] = {m, s.hi, fm, s.fhi};
      s = {s.lo, m, s.flo, fm};
    }
  }
  return -1.0;
}

// An arc whose circle lies in a plane tilted by alpha about the tube's x axis, parametrised so that its
// point at t_star is the farthest from the tube's axis in x: projected on the tube's cross-section it is
// an ellipse with semi-axes rho (along x) and rho cos(alpha), centred at (centre_x, 0). `drum`: the tube
// is the drum's (axis along y through (0, 0, z_axis)), otherwise the vertical cylinder's (axis z).
struct TiltedArc {
  double rho, alpha, centre_x, t_star;
  bool drum;
  double z_axis = 0.0;

  // The tube's cross-section coordinates (x, across) and the coordinate along its axis.
  Vec3 to_world(double x, double across, double along) const {
    return drum ? Vec3(x, along, z_axis + across) : Vec3(x, across, along);
  }
  CircleArc arc(double t_end) const {
    const Vec3 e1 = to_world(1.0, 0.0, 0.0) - to_world(0.0, 0.0, 0.0);
    const Vec3 e2 = to_world(0.0, std::cos(alpha), std::sin(alpha)) - to_world(0.0, 0.0, 0.0);
    CircleArc a;
    a.C = to_world(centre_x, 0.0, 0.3);
    a.rho = rho;
    // cos t u + sin t v = cos(t - t_star) e1 + sin(t - t_star) e2
    a.u = std::cos(t_star) * e1 - std::sin(t_star) * e2;
    a.v = std::sin(t_star) * e1 + std::cos(t_star) * e2;
    a.t_end = t_end;
    return a;
  }
  Vec3 axis_point() const { return drum ? Vec3(0.0, 0.0, z_axis) : Vec3::Zero(); }
  int axis() const { return drum ? 1 : 2; }
  // The first t at which the ellipse (k + rho cos tau, rho cos(alpha) sin tau), tau = t - t_star, reaches
  // distance R from the axis coming from tau < 0: (k + rho c)^2 + rho^2 cos^2 alpha (1 - c^2) = R^2 with
  // c = cos tau, the root nearest 1, in long double.
  double first_exit(double R) const {
    const long double k = centre_x, r = rho, ca = std::cos(static_cast<long double>(alpha));
    const long double A = r * r * (1.0L - ca * ca), B = 2.0L * k * r, Cc = k * k + r * r * ca * ca - R * static_cast<long double>(R);
    const long double c = -2.0L * Cc / (B + std::sqrt(B * B - 4.0L * A * Cc));  // the larger root (B > 0)
    return static_cast<double>(t_star - std::acos(std::min(1.0L, c)));
  }
};

double gap(const CircleArc& arc, const TiltedArc& g, double R, double t) {
  const Vec3 p = arc.at(t) - g.axis_point();
  return g.drum ? std::hypot(p.x(), p.z()) - R : std::hypot(p.x(), p.y()) - R;
}

TEST(TubeExit, KnownCrossingOfTheDrumWallAndTheCylinder) {
  // A 23 mm drum's centre surface (R = 22 mm) and a grain rolling on an arc of radius 1.8 mm whose
  // projection pokes 0.3 mm out of it: the exit, in closed form, is well before the farthest point.
  const double R = 0.022;
  for (bool drum : {true, false}) {
    for (double alpha : {0.0, 0.4, 1.2}) {
      TiltedArc g{0.0018, alpha, R - 0.0018 + 0.0003, 2.0, drum, drum ? 0.0231 : 0.0};
      const CircleArc arc = g.arc(3.0);
      const double expected = g.first_exit(R);
      ASSERT_GT(expected, 0.5);
      ASSERT_LT(expected, g.t_star);
      const double t = first_tube_exit(arc, g.axis_point(), g.axis(), R, arc.t_end);
      EXPECT_NEAR(t, expected, 1e-12) << "drum " << drum << " alpha " << alpha;
      EXPECT_LE(t, expected + 1e-13);  // the last point inside (to the bisection's 1e-13)
      EXPECT_LE(gap(arc, g, R, t), 1e-15 * R);
      EXPECT_GT(gap(arc, g, R, t + 2e-13), 0.0);
      EXPECT_EQ(t, bisection_tube_exit(arc, g.axis_point(), g.axis(), R, arc.t_end));
    }
  }
}

TEST(TubeExit, GrazingArcThatJustTouchesTheWall) {
  const double R = 0.022, rho = 0.0018;
  for (bool drum : {true, false}) {
    // Tilted so that the ellipse curves more than the wall at its touching point: touching from inside.
    TiltedArc g{rho, 0.6, R - rho, 1.3, drum, drum ? 0.0231 : 0.0};
    const CircleArc touch = g.arc(2.5);
    // Exactly touching at t_star: a double root, so within round-off of f either no exit or one at t_star
    // to the square root of the round-off; both the new and the old code say the same.
    const double t0 = first_tube_exit(touch, g.axis_point(), g.axis(), R, touch.t_end);
    if (t0 >= 0.0) {
      EXPECT_NEAR(t0, g.t_star, 1e-6);
    }
    EXPECT_EQ(t0, bisection_tube_exit(touch, g.axis_point(), g.axis(), R, touch.t_end));
    // A hair inside: no exit.
    g.centre_x = R - rho - 1e-9 * R;
    const CircleArc inside = g.arc(2.5);
    EXPECT_LT(first_tube_exit(inside, g.axis_point(), g.axis(), R, inside.t_end), 0.0);
    // A hair out (1e-8 R, 1e-6 R): the window about t_star is found, at its first end.
    for (double out : {1e-8, 1e-6}) {
      g.centre_x = R - rho + out * R;
      const CircleArc graze = g.arc(2.5);
      const double expected = g.first_exit(R);
      ASSERT_LT(expected, g.t_star);
      const double t = first_tube_exit(graze, g.axis_point(), g.axis(), R, graze.t_end);
      // f rises through 0 with a slope of about sqrt(out): t to round-off / slope.
      EXPECT_NEAR(t, expected, 1e-9) << "drum " << drum << " out " << out;
      EXPECT_LE(gap(graze, g, R, t), 1e-15 * R);
      EXPECT_EQ(t, bisection_tube_exit(graze, g.axis_point(), g.axis(), R, graze.t_end));
    }
  }
}

TEST(TubeExit, SameBitsAsTheBisectionOnDrumArcs) {
  // Arcs like a drum step's rolls (drum radius 23 mm, grains 0.8-1 mm: arcs of radius 1.6-2 mm about a
  // support near the wall, any orientation, up to half a turn, and some cut short by an event): the exit
  // is the bisection's to the last bit, whether it is found by the replay or not.
  btr_test::UniformDraws uniform{2026112722};
  const Vec3 axis(0.0, 0.0, 0.0231);
  int exits = 0, trials = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double R = 0.0231 - (0.0008 + 0.0002 * uniform());
    CircleArc arc;
    arc.rho = 0.0016 + 0.0004 * uniform();
    const double phi = kTwoPi * uniform(), dist = R - arc.rho * (2.0 * uniform() - 0.5);
    arc.C = axis + Vec3(dist * std::cos(phi), 0.02 * (uniform() - 0.5), dist * std::sin(phi));
    const Vec3 u = Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalized();
    arc.u = u;
    arc.v = (Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).cross(u)).normalized();
    arc.t_end = M_PI * uniform();
    const double t_max = uniform() < 0.3 ? arc.t_end * uniform() + 1e-13 : arc.t_end + 1e-13;
    const double expected = bisection_tube_exit(arc, axis, 1, R, t_max);
    const double t = first_tube_exit(arc, axis, 1, R, t_max);
    ++trials;
    if (expected > 0.0) ++exits;
    ASSERT_EQ(t, expected) << "trial " << trial;
  }
  EXPECT_GT(exits, trials / 10);
}

TEST(TubeExit, SameBitsAsTheBisectionOnRandomArcs) {
  // The arcs of TubeExitAgreesWithDenseSampling (unit tube, any size up to half the tube), many more.
  btr_test::UniformDraws uniform{12345};
  int exits = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const CircleArc arc = btr_test::arc_about_unit_tube(uniform);
    const double expected = bisection_tube_exit(arc, Vec3::Zero(), 2, 1.0, arc.t_end);
    if (expected > 0.0) ++exits;
    ASSERT_EQ(first_tube_exit(arc, Vec3::Zero(), 2, 1.0, arc.t_end), expected) << "trial " << trial;
  }
  EXPECT_GT(exits, 2000);
}

}  // namespace
}  // namespace btr
