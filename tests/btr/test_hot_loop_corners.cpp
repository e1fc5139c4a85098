// The corners of the placement's hot loop (issue 22), each built by hand: what used to pass silently
// is now handled exactly or reported as a PlacementError naming the grain. Expected values are
// computed here in closed form, independently of the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "btr/placement/circle_arc.h"
#include "btr/placement/deposition.h"
#include "btr/placement/descent.h"
#include "btr/placement/neighbour_grid.h"
#include "btr/placement/obstacle.h"
#include "btr/placement/path_graze.h"
#include "btr/verify/check.h"
#include "containers.h"
#include "random_arcs.h"

namespace btr {
namespace {

Vec3 drop(Deposition& dep, double x, double y, double r) { return dep.place(Drop{x, y, r}).x; }

void expect_valid(const Deposition& dep) {
  const CheckReport rep = check_packing(dep.grains(), dep.dimension(), dep.container());
  EXPECT_TRUE(rep.ok()) << "overlaps " << rep.overlaps << " (max " << rep.max_overlap << "), unsupported "
                        << rep.unsupported << ", outside " << rep.outside;
}

// A ring of n small grains (radius rs) on the floor at distance h from the z axis, then a large grain
// (radius 1) dropped on the axis: it meets all n at once, at height rs + sqrt((1 + rs)^2 - h^2).
void ring(Deposition& dep, int n, double h, double rs) {
  for (int k = 0; k < n; ++k) {
    const double a = kTwoPi * k / n;
    const Vec3 p = drop(dep, h * std::cos(a), h * std::sin(a), rs);
    ASSERT_NEAR(p.z(), rs, 1e-12);  // the ring grains do not touch each other: 2 h sin(pi / n) > 2 rs
  }
}

// ---------------------------------------------------------------------------------------------
// More simultaneous contacts than the engine used to hold (8): up to kMaxContacts are all kept, and one
// more is an error naming the grain instead of a contact dropped without a word.

TEST(HotLoopCorners, TwelveSimultaneousContactsAreAllHeld) {
  const double h = 0.6, rs = 0.1;
  ASSERT_GT(2 * h * std::sin(M_PI / 12), 2 * rs);
  Deposition dep(3, Container{}, 1.0);
  ring(dep, 12, h, rs);
  const Vec3 p = drop(dep, 0.0, 0.0, 1.0);
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 0.0, 1e-12);
  EXPECT_NEAR(p.z(), rs + std::sqrt((1 + rs) * (1 + rs) - h * h), 1e-12);
  expect_valid(dep);
}

TEST(HotLoopCorners, MoreSimultaneousContactsThanHeldIsAnErrorNamingTheGrain) {
  const int n = kMaxContacts + 1;
  const double h = 0.6, rs = 0.1;
  ASSERT_GT(2 * h * std::sin(M_PI / n), 2 * rs);
  ASSERT_GT(rs + std::sqrt((1 + rs) * (1 + rs) - h * h), 1.0);  // the ring is met above the floor
  Deposition dep(3, Container{}, 1.0);
  ring(dep, n, h, rs);
  try {
    drop(dep, 0.0, 0.0, 1.0);
    FAIL() << "a grain meeting " << n << " grains at once was placed";
  } catch (const PlacementError& e) {
    EXPECT_EQ(e.grain_id(), n + 1);
    EXPECT_NE(std::string(e.what()).find("simultaneous contacts"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// The lift-off test of two supports: with nearly parallel normals the 2x2 Gram matrix is singular in
// floating point and its inverse gave NaN loads, so a support that unloads was missed.

TEST(HotLoopCorners, LiftOffWithNearlyParallelNormalsIsFound) {
  for (double eps : {1e-3, 1e-6, 1e-9, 1e-12}) {
    const Vec3 a(std::sin(eps), 0, std::cos(eps)), b(-std::sin(eps), 0, std::cos(eps));
    // g = f_a a + f_b b by hand: f_a - f_b = gx / sin eps, f_a + f_b = gz / cos eps.
    for (const Vec3& g : {Vec3(-1, 0, 0.5), Vec3(1, 0, 0.5), Vec3(-1e-3, 0, 1)}) {
      const double fa = 0.5 * (g.x() / std::sin(eps) + g.z() / std::cos(eps));
      const double fb = 0.5 * (-g.x() / std::sin(eps) + g.z() / std::cos(eps));
      EXPECT_EQ(unloads(g, a, b), fa < 0.0) << "eps " << eps << " g " << g.transpose();
      EXPECT_EQ(unloads(g, b, a), fb < 0.0) << "eps " << eps << " g " << g.transpose();
    }
  }
}

TEST(HotLoopCorners, LiftOffAgreesWithTheSolvedLoadsWhenWellConditioned) {
  // Normals 60 degrees apart in the x-z plane; g = f_a a + f_b b with chosen loads.
  const Vec3 a(std::sin(0.5), 0, std::cos(0.5)), b(-std::sin(0.5), 0, std::cos(0.5));
  for (double fa : {-1.0, -1e-6, 1e-6, 2.0})
    for (double fb : {-0.5, 0.5}) {
      const Vec3 g = fa * a + fb * b;
      EXPECT_EQ(unloads(g, a, b), fa < 0.0);
      EXPECT_EQ(unloads(g, b, a), fb < 0.0);
    }
}

// ---------------------------------------------------------------------------------------------
// Obstacle keys: every periodic image of every grain has its own key, however many periods a query
// spans (the codes (kx + 4) * 9 + (ky + 4) collided beyond 4 periods).

TEST(HotLoopCorners, ImageKeysAreDistinctAcrossManyPeriods) {
  const double r_max = 0.5, period = 0.1;  // one cell of width 0.1 per axis: 21 images each way
  NeighbourGrid grid(3, test::periodic(period, period), r_max);
  grid.insert(0, Vec3(0.0, 0.0, 0.5), 0.05);
  grid.insert(1, Vec3(0.03, -0.02, 0.5), 0.05);
  std::map<std::int64_t, Vec3> centre_of_key;
  std::set<std::tuple<int, long, long>> images;
  int visits = 0;
  grid.visit_box(Vec3(-1.0, -1.0, 0.0), Vec3(1.0, 1.0, 1.0), [&](std::int32_t i, const Vec3& c, double, int image) {
    ++visits;
    const Vec3 base = i == 0 ? Vec3(0.0, 0.0, 0.5) : Vec3(0.03, -0.02, 0.5);
    const long kx = std::lround((c.x() - base.x()) / period), ky = std::lround((c.y() - base.y()) / period);
    images.insert({i, kx, ky});
    const auto [it, fresh] = centre_of_key.emplace(sphere_key(i, image), c);
    EXPECT_TRUE(fresh) << "grain " << i << " image (" << kx << ", " << ky << ") shares key " << it->first
                       << " with the image at " << it->second.transpose();
  });
  EXPECT_GT(visits, 2 * 81);  // more than the 9 x 9 images the old codes covered
  EXPECT_EQ(static_cast<int>(images.size()), visits);
  EXPECT_EQ(static_cast<int>(centre_of_key.size()), visits);
}

TEST(HotLoopCorners, PeriodTooSmallForImageCodesIsAnError) {
  // A property of the container, refused once when the engine is built (not re-checked per grain).
  EXPECT_THROW(Deposition(3, test::periodic(1e-4, 1.0), 1.0), std::invalid_argument);
  EXPECT_NO_THROW(Deposition(3, test::periodic(1.0 / 256.0, 1.0), 1.0));
}

// ---------------------------------------------------------------------------------------------
// The cylinder (and drum) contact along a tilted arc: the old 64-sample scan stepped over an exit
// shorter than a sample spacing.

TEST(HotLoopCorners, GrazingExitFromTheCylinderIsFound) {
  // The arc's horizontal part goes out to 0.9 + rho along x and back: it leaves the tube |x_h| = 1
  // for sin t > 0.1 / rho only, a window of ~0.009 rad about pi/2, between samples 33 and 34 of 64 over [0, 3].
  CircleArc arc;
  arc.C = Vec3(0.9, 0.0, 0.0);
  arc.rho = 0.1 + 1e-6;
  arc.u = Vec3::UnitZ();
  arc.v = Vec3::UnitX();
  arc.t_end = 3.0;
  const double expected = std::asin(0.1 / arc.rho);
  const double t = first_tube_exit(arc, Vec3::Zero(), 2, 1.0, arc.t_end);
  EXPECT_NEAR(t, expected, 1e-9);
  // The same window about the drum's axis (along y, through (0, 0, 5)).
  CircleArc drum_arc = arc;
  drum_arc.C = Vec3(0.0, 0.0, 5.0 - 0.9);
  drum_arc.u = Vec3::UnitY();  // along the axis: projected away
  drum_arc.v = -Vec3::UnitZ();
  EXPECT_NEAR(first_tube_exit(drum_arc, Vec3(0, 0, 5), 1, 1.0, arc.t_end), expected, 1e-9);
  // A rho a hair smaller stays inside: no exit.
  arc.rho = 0.1 - 1e-9;
  EXPECT_LT(first_tube_exit(arc, Vec3::Zero(), 2, 1.0, arc.t_end), 0.0);
}

TEST(HotLoopCorners, TubeExitAtTheEndOfAnArcIsFound) {
  // An arc of a drum3d redeposition (drum radius 15 mm) that leaves the drum's centre surface near its
  // end: an exit whose last bisection interval round-off made look inside throughout must still count.
  CircleArc arc;
  arc.C = Vec3(0.0027659932045600096, 0.00041907619787771128, 0.0012201761122908827);
  arc.rho = 0.0016221990761889921;
  arc.u = Vec3(0.51024963954380809, -0.066054279025745205, 0.85748594015750668);
  arc.v = Vec3(0.85038989471483428, -0.11008707705582818, -0.5145073978401058);
  arc.t_end = 1.030363249199471;
  const Vec3 axis(0, 0, 0.015);
  const double R = 0.014323112567822781;
  auto gap = [&](double t) {  // distance from the axis minus R, by hand
    const Vec3 p = arc.at(t);
    return std::hypot(p.x(), p.z() - axis.z()) - R;
  };
  ASSERT_LT(gap(0.0), 0.0);
  ASSERT_GT(gap(arc.t_end), 0.0);
  const double t = first_tube_exit(arc, axis, 1, R, arc.t_end);
  ASSERT_GE(t, 0.0);
  EXPECT_NEAR(gap(t), 0.0, 1e-12 * R);
  for (int k = 0; k < 1000; ++k) EXPECT_LE(gap(t * k / 1000), 1e-12 * R);
}

TEST(HotLoopCorners, TubeExitAgreesWithDenseSampling) {
  // Random arcs about a unit tube (axis z): the exit found is the first crossing that 20000 samples see,
  // to a sample spacing, and never later than it.
  btr_test::UniformDraws uniform{12345};
  int exits = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const CircleArc arc = btr_test::arc_about_unit_tube(uniform);
    auto f = [&](double t) { return std::hypot(arc.at(t).x(), arc.at(t).y()) - 1.0; };
    if (f(0.0) >= 0.0) continue;
    const int samples = 20000;
    double first = -1.0;
    for (int k = 1; k <= samples && first < 0.0; ++k)
      if (f(arc.t_end * k / samples) > 0.0) first = arc.t_end * k / samples;
    const double t = first_tube_exit(arc, Vec3::Zero(), 2, 1.0, arc.t_end);
    if (first >= 0.0) {
      ++exits;
      ASSERT_GE(t, 0.0) << "trial " << trial;
      EXPECT_LE(t, first) << "trial " << trial;
      EXPECT_GE(t, first - arc.t_end / samples - 1e-12) << "trial " << trial;
    } else if (t >= 0.0) {
      EXPECT_NEAR(f(t), 0.0, 1e-9) << "trial " << trial;  // an exit between samples: it must be real
    }
  }
  EXPECT_GT(exits, 30);
}

// ---------------------------------------------------------------------------------------------
// Along a cylinder (or drum) wall on one grain the path is followed in steps of 0.05 r of arc, and a step
// looked only at its ends: a grain it enters and leaves between two samples was passed through.
// first_graze (btr/placement/path_graze.h) proves every partner clear between two samples or finds a
// point inside one.

namespace graze {

// The cylinder of radius 20, grains of radius 1: the moving centre stays on |x_h| = Rc = 19. Support p on
// the floor against the wall at azimuth 0; pressed against the wall on p the centre follows
// P(f) = (Rc cos f, Rc sin f, 1 + sqrt(4 - q^2)), q = 2 Rc sin(|f| / 2), the section's distance from p's.
constexpr double kRc = 19.0, kDrop = 0.02, kStep = 0.05 / kRc;
Vec3 path(double f) {
  const double q = 2.0 * kRc * std::sin(0.5 * std::abs(f));
  return Vec3(kRc * std::cos(f), kRc * std::sin(f), 1.0 + std::sqrt(std::max(0.0, 4.0 - q * q)));
}
double spread(double f, double h) {
  const double q = 2.0 * kRc * std::sin(0.5 * std::abs(f));
  return tube_path_spread(kRc, h, q, 4.0 - q * q);
}

// Grain o of radius ro on the floor at azimuth fo whose contact sphere (radius 1 + ro) the path enters by
// `depth` at its nearest approach (depth < 0: passes that far clear). Its distance from the axis is set by
// bisection; the nearest approach, on [0.03, 0.1], by golden section. Returns o's centre and where the
// nearest approach lies.
std::pair<Vec3, double> grazed_grain(double fo, double ro, double depth) {
  double f_near = 0.0;
  auto nearest = [&](double rho) {
    const Vec3 o(rho * std::cos(fo), rho * std::sin(fo), ro);
    double a = 0.03, b = 0.1;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    while (b - a > 1e-13) {
      const double c = b - g * (b - a), d = a + g * (b - a);
      if ((path(c) - o).norm() < (path(d) - o).norm()) b = d;
      else a = c;
    }
    f_near = 0.5 * (a + b);
    return (path(f_near) - o).norm();
  };
  double lo = 12.0, hi = 18.0;  // o comes nearer the path as it moves out towards the wall
  for (int it = 0; it < 200; ++it) {
    const double m = 0.5 * (lo + hi);
    (nearest(m) > 1.0 + ro - depth ? lo : hi) = m;
  }
  const double near = nearest(lo);
  EXPECT_NEAR(near, 1.0 + ro - depth, 1e-12);
  return {Vec3(lo * std::cos(fo), lo * std::sin(fo), ro), f_near};
}

double between(btr_test::UniformDraws& u, double lo, double hi) { return lo + (hi - lo) * u(); }

Obstacle sphere_partner(const Vec3& c, double R) {
  Obstacle o;
  o.kind = Obstacle::Kind::Sphere;
  o.c = c;
  o.R = R;
  return o;
}

}  // namespace graze

TEST(HotLoopCorners, AGrainEnteredBetweenTwoSamplesOfTheWallPathIsFound) {
  const double ro = 2.5, tol = 1e-9;  // the engine's graze depth (kGrazeDepth, r = 1)
  const double none = -std::numeric_limits<double>::infinity();  // no partner left out at the first sample
  const auto [c, f_near] = graze::grazed_grain(0.0592, ro, 1e-7);
  const std::vector<Obstacle> partners{graze::sphere_partner(c, 1.0 + ro)};
  auto condition = [&](double f) { return partners[0].gap(graze::path(f)) < -tol ? 1 : 0; };
  // The samples of the walk from kDrop on either side of the nearest approach: both clear, so a step
  // that looks at its ends only passes o. The stretch inside o (~8e-5 rad) lies between them.
  const double k = std::floor((f_near - graze::kDrop) / graze::kStep);
  const double a = graze::kDrop + k * graze::kStep, b = a + graze::kStep;
  ASSERT_EQ(condition(a), 0);
  ASSERT_EQ(condition(b), 0);
  ASSERT_EQ(condition(f_near), 1);
  const double f = first_graze(a, b, graze::path(a), graze::path(b), partners, tol, none, graze::path, graze::spread);
  ASSERT_FALSE(std::isnan(f));
  EXPECT_GT(f, a);
  EXPECT_LT(f, b);
  EXPECT_EQ(condition(f), 1);
  // Inside o's stretch, whose half-width is about sqrt(2 depth (1 + ro) / curvature) well under 1e-3 rad.
  EXPECT_NEAR(f, f_near, 1e-3);
  // Passing 1e-9 clear of o, or entering it by less than the graze depth (a tangency): nothing found.
  for (const double depth : {-1e-9, 0.5e-9}) {
    const std::vector<Obstacle> near{graze::sphere_partner(graze::grazed_grain(0.0592, ro, depth).first, 1.0 + ro)};
    EXPECT_TRUE(std::isnan(first_graze(a, b, graze::path(a), graze::path(b), near, tol, none, graze::path, graze::spread)))
        << depth;
  }
}

TEST(HotLoopCorners, TubePathSpreadBoundsTheTravelAlongTheWallPath) {
  // The bound against the largest distance 2000 samples find from P(f) over [f, f + h].
  btr_test::UniformDraws uniform{777};
  const double f_max = 2.0 * std::asin(1.0 / graze::kRc);  // the path ends where q = 2
  for (int trial = 0; trial < 500; ++trial) {
    const double f = graze::between(uniform, -0.95 * f_max, 0.95 * f_max), h = graze::between(uniform, -0.01, 0.01);
    if (std::abs(f + h) >= f_max) continue;
    double far = 0.0;
    for (int j = 1; j <= 2000; ++j) far = std::max(far, (graze::path(f + h * j / 2000) - graze::path(f)).norm());
    EXPECT_LE(far, graze::spread(f, h) * (1.0 + 1e-12)) << "trial " << trial;
  }
}

TEST(HotLoopCorners, WallPathGrazesAgreeWithDenseSampling) {
  // Random grains about the wall path, some entered by up to 1e-4, some missed by as much: over one step
  // whose ends are clear, first_graze finds a point inside exactly when 20000 samples see one.
  btr_test::UniformDraws uniform{4242};
  const double tol = 1e-9, none = -std::numeric_limits<double>::infinity();
  int found = 0, clear = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double fc = graze::between(uniform, 0.0, 0.09), ro = graze::between(uniform, 0.2, 2.5), depth = graze::between(uniform, -1e-4, 1e-4);
    // o's centre off the path point at fc, along a random direction normal to the path there.
    const Vec3 T = (graze::path(fc + 1e-6) - graze::path(fc - 1e-6)).normalized();
    Vec3 n(graze::between(uniform, -1, 1), graze::between(uniform, -1, 1), graze::between(uniform, -1, 1));
    n = (n - n.dot(T) * T).normalized();
    const std::vector<Obstacle> partners{graze::sphere_partner(graze::path(fc) + n * (1.0 + ro - depth), 1.0 + ro)};
    auto condition = [&](double f) { return partners[0].gap(graze::path(f)) < -tol ? 1 : 0; };
    const double a = fc - graze::between(uniform, 0.0, graze::kStep), b = a + graze::kStep;
    if (condition(a) || condition(b)) continue;
    const int samples = 20000;
    double first = -1.0;
    for (int j = 1; j < samples && first < 0.0; ++j)
      if (condition(a + (b - a) * j / samples)) first = a + (b - a) * j / samples;
    const double f = first_graze(a, b, graze::path(a), graze::path(b), partners, tol, none, graze::path, graze::spread);
    if (first >= 0.0) {
      ++found;
      ASSERT_FALSE(std::isnan(f)) << "trial " << trial;
      EXPECT_EQ(condition(f), 1) << "trial " << trial;
      EXPECT_LE(f, first + 1e-12) << "trial " << trial;  // the leftmost: the entry, not a later point inside
    } else {
      ++clear;
      if (!std::isnan(f)) {
        EXPECT_EQ(condition(f), 1) << "trial " << trial;  // a stretch between samples: real
      }
    }
  }
  EXPECT_GT(found, 40);
  EXPECT_GT(clear, 40);
}

TEST(HotLoopCorners, AGrainGrazedAlongTheCylinderWallLeavesAValidPacking) {
  // The grain dropped against the wall at azimuth kDrop lands on p, rolls along the wall on it, touches
  // the grazed grain o on the way (above), and ends on the floor against the wall and p, at azimuth
  // 2 asin(1 / Rc) (|x - p| = 2 at z = 1).
  const double ro = 2.5;
  const Vec3 o = graze::grazed_grain(0.0592, ro, 1e-7).first;
  Container c;
  c.kind = ContainerKind::Cylinder;
  c.radius = 20.0;
  Deposition dep(3, c, ro);
  ASSERT_NEAR(drop(dep, graze::kRc, 0.0, 1.0).z(), 1.0, 1e-12);
  ASSERT_NEAR(drop(dep, o.x(), o.y(), ro).z(), ro, 1e-12);
  const Vec3 x = drop(dep, graze::kRc * std::cos(graze::kDrop), graze::kRc * std::sin(graze::kDrop), 1.0);
  EXPECT_NEAR(x.z(), 1.0, 1e-12);
  EXPECT_NEAR(std::atan2(x.y(), x.x()), 2.0 * std::asin(1.0 / graze::kRc), 1e-9);
  expect_valid(dep);
}

// ---------------------------------------------------------------------------------------------
// Round-off beyond the cylinder and the drum wall (drop_misfit lets a drop reach 1e-12 r past a wall):
// the grain is brought back inside, as for flat walls, instead of staying outside.

TEST(HotLoopCorners, GrainAHairBeyondTheCylinderEndsInside) {
  Container c;
  c.kind = ContainerKind::Cylinder;
  c.radius = 5.0;
  const double r = 1.0, R = c.radius - r;
  Deposition dep(3, c, r);
  const double a = 0.7, out = R + 0.5e-12 * r;
  const Vec3 p = drop(dep, out * std::cos(a), out * std::sin(a), r);
  EXPECT_LE(std::hypot(p.x(), p.y()), R);
  EXPECT_NEAR(std::hypot(p.x(), p.y()), R, 1e-12);
  EXPECT_NEAR(p.z(), r, 1e-12);
  expect_valid(dep);
}

TEST(HotLoopCorners, GrainAHairBeyondTheDrumWallEndsInside) {
  // Dropped at x a hair beyond R_drum - r: the drum wall below that column is at the axis height, so
  // the grain meets it there and rolls down the wall to the lowest line (x = 0, z = r). Before, it
  // missed the wall (no real root) and fell to the floor z = r outside the drum.
  Container c;
  c.kind = ContainerKind::Drum;
  c.radius = 10.0;
  c.size_y = 10.0;
  const double r = 1.0;
  Deposition dep(3, c, r);
  const Vec3 p = drop(dep, c.radius - r + 0.5e-12 * r, 0.0, r);
  const double from_axis = std::hypot(p.x(), p.z() - c.radius);
  EXPECT_LE(from_axis, c.radius - r + 1e-12 * r);
  EXPECT_NEAR(p.x(), 0.0, 1e-6 * r);
  EXPECT_NEAR(p.z(), r, 1e-9 * r);
  expect_valid(dep);
}

// ---------------------------------------------------------------------------------------------
// The neighbour grid: an escaped grain or a non-finite centre is an error (it was clamped into an edge
// column, or cast to an index), and an open floor grows towards a far grain on that side only, with a
// budget instead of an unbounded allocation.

TEST(HotLoopCorners, GridRefusesACentreOutsideABox) {
  NeighbourGrid grid(3, test::box(10.0, 10.0), 1.0);
  grid.insert(0, Vec3(4.0, 0.0, 1.0), 1.0);                       // inside
  grid.insert(1, Vec3(5.0, 0.0, 1.0), 1.0);                       // on the grid's edge (round-off territory)
  EXPECT_THROW(grid.insert(2, Vec3(7.5, 0.0, 1.0), 1.0), std::out_of_range);   // escaped
  EXPECT_THROW(grid.insert(3, Vec3(0.0, -9.0, 1.0), 1.0), std::out_of_range);  // escaped in y
}

TEST(HotLoopCorners, GridRefusesANonFiniteCentre) {
  NeighbourGrid grid(3, test::box(10.0, 10.0), 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(grid.insert(0, Vec3(nan, 0.0, 1.0), 1.0), std::out_of_range);
  EXPECT_THROW(grid.insert(0, Vec3(0.0, 0.0, nan), 1.0), std::out_of_range);
}

TEST(HotLoopCorners, NonFiniteDropIsAnErrorNamingTheGrain) {
  Deposition dep(3, test::box(10.0, 10.0), 1.0);
  drop(dep, 0.0, 0.0, 1.0);
  try {
    drop(dep, std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0);
    FAIL() << "a NaN drop was placed";
  } catch (const PlacementError& e) {
    EXPECT_EQ(e.grain_id(), 2);
  }
  EXPECT_EQ(dep.grains().size(), 1u);
}

TEST(HotLoopCorners, OpenFloorGrowsTowardsAFarGrainOnly) {
  // Cells 2 wide; the grid starts as 16 x 16 columns about the origin. A grain 200 cells out along +x
  // needs the columns from -8 to 200 in x: symmetric doubling held [-256, 256) (8192 columns).
  NeighbourGrid grid(3, Container{}, 1.0);
  grid.insert(0, Vec3(0.0, 0.0, 1.0), 1.0);
  grid.insert(1, Vec3(400.5, 0.0, 1.0), 1.0);
  EXPECT_LE(grid.column_count(), static_cast<std::size_t>((200 + 8 + 1) * 16));
  int seen = 0;
  grid.visit_box(Vec3(398, -2, 0), Vec3(403, 2, 2), [&](std::int32_t i, const Vec3&, double, int) { seen += i == 1; });
  EXPECT_EQ(seen, 1);
}

TEST(HotLoopCorners, FarDropOnAnOpenFloorIsAnErrorNotAnAllocation) {
  // 1e5 cells away diagonally: a dense grid would need 1e10 columns.
  Deposition dep(3, Container{}, 1.0);
  drop(dep, 0.0, 0.0, 1.0);
  try {
    drop(dep, 2e5, 2e5, 1.0);
    FAIL() << "a grid of 1e10 columns was built";
  } catch (const PlacementError& e) {
    EXPECT_EQ(e.grain_id(), 2);
    EXPECT_NE(std::string(e.what()).find("columns (budget"), std::string::npos) << e.what();  // refused, not failed
  }
}

}  // namespace
}  // namespace btr
