// The drum wall against hand geometry (a grain at the bottom, on the wall and one grain), the drum
// step's invariants, the self-check's own drum geometry, and the drum measures on hand cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "btr/dynamics/drum.h"
#include "btr/measures/metrics.h"
#include "btr/placement/deposition.h"
#include "btr/verify/check.h"

namespace btr {
namespace {

Container drum(double R, double length = 0.0) {
  Container c;
  c.kind = ContainerKind::Drum;
  c.radius = R;
  c.size_y = length;
  return c;
}

Container periodic_drum(double R, double length) {
  Container c = drum(R, length);
  c.periodic_ends = true;
  return c;
}

// 2D: a disk dropped anywhere in the empty drum falls onto the wall (or straight to the bottom) and
// rolls to the lowest point (0, r).
TEST(DrumWall, GrainComesToRestAtTheBottom2D) {
  for (double x0 : {0.0, 3.0, -7.5, 8.9}) {
    Deposition dep(2, drum(10.0), 1.0);
    const Vec3 p = dep.place(Drop{x0, 0.0, 1.0, 1}).x;
    EXPECT_NEAR(p.x(), 0.0, 1e-9) << x0;
    EXPECT_NEAR(p.z(), 1.0, 1e-9) << x0;
  }
}

// 3D: a sphere rolls round the drum at constant y (gravity has no component along the axis).
TEST(DrumWall, SphereRollsRoundAtConstantY3D) {
  Deposition dep(3, drum(10.0, 6.0), 1.0);
  const Vec3 p = dep.place(Drop{6.0, 1.5, 1.0, 1}).x;
  EXPECT_NEAR(p.x(), 0.0, 1e-9);
  EXPECT_NEAR(p.y(), 1.5, 1e-12);
  EXPECT_NEAR(p.z(), 1.0, 1e-9);
}

// 2D: grain B rests on the drum wall and on grain A at the bottom. Closed form: B's centre lies on the
// circle of radius R - r_B about the axis (0, R) and on the circle of radius r_A + r_B about A (0, r_A).
TEST(DrumWall, GrainOnTheWallAndOneGrainClosedForm2D) {
  const double R = 10.0, ra = 1.5, rb = 1.0;
  Deposition dep(2, drum(R), ra);
  const Vec3 a = dep.place(Drop{0.0, 0.0, ra, 1}).x;
  ASSERT_NEAR(a.z(), ra, 1e-12);
  const Vec3 b = dep.place(Drop{4.0, 0.0, rb, 1}).x;
  const double rho1 = R - rb, rho2 = ra + rb, D = R - ra;
  const double s = (rho1 * rho1 - rho2 * rho2 + D * D) / (2.0 * D);  // from the axis, downwards
  const double z = R - s, x = std::sqrt(rho1 * rho1 - s * s);
  EXPECT_NEAR(b.x(), x, 1e-9);
  EXPECT_NEAR(b.z(), z, 1e-9);
  // Mirror image from the other side.
  const Vec3 c = dep.place(Drop{-4.0, 0.0, rb, 1}).x;
  EXPECT_NEAR(c.x(), -x, 1e-9);
  EXPECT_NEAR(c.z(), z, 1e-9);
  EXPECT_TRUE(check_packing(dep.grains(), 2, drum(R)).ok());
}

// 3D: B comes down the wall onto A (lying on the drum's lowest line), rolls along the curve where the
// drum's and A's contact surfaces meet, and ends on the lowest line beside A, touching it: two spheres
// on a line in contact, |y_B - y_A| = 2 sqrt(r_A r_B) from their heights r_A and r_B.
TEST(DrumWall, SphereRollsAlongWallAndGrainToTheLowestLine3D) {
  const double R = 10.0, ra = 1.5, rb = 1.0;
  Deposition dep(3, drum(R, 12.0), ra);
  dep.place(Drop{0.0, 0.0, ra, 1});
  const Vec3 b = dep.place(Drop{5.0, 1.0, rb, 1}).x;
  EXPECT_NEAR(b.x(), 0.0, 1e-7);
  EXPECT_NEAR(b.z(), rb, 1e-7);
  EXPECT_NEAR(b.y(), 2.0 * std::sqrt(ra * rb), 1e-6);
  EXPECT_TRUE(check_packing(dep.grains(), 3, drum(R, 12.0)).ok());
}

// 3D end walls: a sphere dropped against an end wall rests there at the bottom.
TEST(DrumWall, EndWallHoldsTheSphere3D) {
  Deposition dep(3, drum(10.0, 4.0), 1.0);
  const Vec3 p = dep.place(Drop{3.0, 1.0, 1.0, 1}).x;  // y = L/2 - r
  EXPECT_NEAR(p.y(), 1.0, 1e-12);
  EXPECT_NEAR(p.x(), 0.0, 1e-9);
  EXPECT_NEAR(p.z(), 1.0, 1e-9);
  EXPECT_THROW(dep.place(Drop{3.0, 1.5, 1.0, 1}), PlacementError);  // through the end wall
  EXPECT_THROW(dep.place(Drop{9.5, 0.0, 1.0, 1}), PlacementError);  // through the drum wall
}

// 3D periodic ends: no end wall; a drop beyond y = L/2 wraps to the other end; a sphere close to an end
// rests there on the lowest line, which flat end walls would refuse.
TEST(DrumPeriodicEnds, NoEndWallAndDropsWrap3D) {
  const Container c = periodic_drum(10.0, 4.0);
  Deposition dep(3, c, 1.0);
  const Vec3 p = dep.place(Drop{3.0, 1.8, 1.0, 1}).x;  // |y| > L/2 - r: through an end wall if it had one
  EXPECT_NEAR(p.x(), 0.0, 1e-9);
  EXPECT_NEAR(p.y(), 1.8, 1e-12);
  EXPECT_NEAR(p.z(), 1.0, 1e-9);
  Deposition lone(3, c, 1.0);
  EXPECT_NEAR(lone.place(Drop{0.0, 2.5, 1.0, 1}).x.y(), -1.5, 1e-12);  // y = L/2 + 0.5 -> -L/2 + 0.5
  Deposition walled(3, drum(10.0, 4.0), 1.0);
  EXPECT_THROW(walled.place(Drop{3.0, 1.8, 1.0, 1}), PlacementError);
}

// 3D: A lies on the lowest line next to the end y = +L/2; B comes down the drum wall just past the
// other end, 1 from A's periodic image in y, meets the image and rolls along the wall and the image to
// the lowest line, as in the walled case: y_B = y_A + 2 sqrt(r_A r_B), wrapped into [-L/2, L/2).
TEST(DrumPeriodicEnds, SphereRestsAgainstTheImageAcrossTheEnd3D) {
  const double R = 10.0, L = 12.0, ra = 1.5, rb = 1.0;
  const Container c = periodic_drum(R, L);
  Deposition dep(3, c, ra);
  const Vec3 a = dep.place(Drop{0.0, 5.5, ra, 1}).x;
  ASSERT_NEAR(a.z(), ra, 1e-12);
  const Vec3 b = dep.place(Drop{5.0, -5.5, rb, 1}).x;  // 1 from A's image at y = 5.5 - 12
  const double y = 5.5 + 2.0 * std::sqrt(ra * rb) - L;
  EXPECT_NEAR(b.x(), 0.0, 1e-7);
  EXPECT_NEAR(b.z(), rb, 1e-7);
  EXPECT_NEAR(b.y(), y, 1e-6);
  EXPECT_TRUE(check_packing(dep.grains(), 3, c).ok());
  // With end walls A pokes through the wall at y = +6.
  EXPECT_GE(check_packing(dep.grains(), 3, drum(R, L)).outside, 1);
}

// The self-check wraps the drum's periodic ends: two spheres on the lowest line at opposite ends
// overlap through the period, and a sphere resting on one of them across the end is supported.
TEST(DrumPeriodicEnds, CheckWrapsTheAxis3D) {
  const Container c = periodic_drum(10.0, 8.0);
  Grains apart = {{Vec3(0, 3.5, 1.0), 1.0, 1}, {Vec3(0, -3.5, 1.0), 1.0, 1}};  // 1 apart through the end
  EXPECT_GE(check_packing(apart, 3, c).overlaps, 1);
  Grains touching = {{Vec3(0, 3.0, 1.0), 1.0, 1}, {Vec3(0, -3.0, 1.0), 1.0, 1}};  // 2 apart: contact
  EXPECT_TRUE(check_packing(touching, 3, c).ok());
  // Three spheres on the lowest line in a row of touching spheres, period 6: each touches both others;
  // a fourth on top of two of them across the end (x = 0, y = 3 = -3, z = 1 + sqrt(3)) rests there.
  const Container p6 = periodic_drum(10.0, 6.0);
  Grains row = {{Vec3(0, -2.0, 1.0), 1.0, 1}, {Vec3(0, 0.0, 1.0), 1.0, 1}, {Vec3(0, 2.0, 1.0), 1.0, 1},
                {Vec3(0, -3.0, 1.0 + std::sqrt(3.0)), 1.0, 1}};
  const CheckReport rep = check_packing(row, 3, p6);
  EXPECT_TRUE(rep.ok()) << rep.overlaps << " overlaps, " << rep.unsupported << " unsupported";
  // The same top sphere with end walls at +-3 has a single grain below it (and touches the wall).
  const CheckReport walled = check_packing(row, 3, drum(10.0, 6.0));
  EXPECT_GE(walled.unsupported + walled.outside, 1);
}

// Drum steps with periodic ends keep every grain valid and inside [-L/2, L/2), and are deterministic.
TEST(DrumPeriodicEnds, StepsKeepPackingsValid3D) {
  const Container c = periodic_drum(6.0, 3.0);
  DrumStepper stepper(3, c, 0.6);
  Deposition dep(3, c, 0.5);
  for (int i = 0; i < 150; ++i)
    dep.place(Drop{-4.5 + 0.06 * i, -1.5 + 0.37 * i, i % 3 ? 0.3 : 0.5, i % 3 ? 1 : 2});
  Grains g = dep.grains();
  ASSERT_TRUE(check_packing(g, 3, c).ok());
  bool near_end = false;
  for (int s = 0; s < 5; ++s) {
    g = stepper.step(g, 2.0 * M_PI / 20.0);
    const CheckReport rep = check_packing(g, 3, c);
    ASSERT_TRUE(rep.ok()) << "step " << s << ": " << rep.overlaps << " overlaps, " << rep.unsupported
                          << " unsupported, " << rep.outside << " outside";
    for (const Grain& x : g) {
      ASSERT_GE(x.x.y(), -1.5);
      ASSERT_LT(x.x.y(), 1.5);
      near_end = near_end || std::abs(x.x.y()) > 1.5 - x.r;  // would be through an end wall
    }
  }
  EXPECT_TRUE(near_end);
  const Grains a = stepper.step(g, 0.05), b = stepper.step(g, 0.05);
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i].x, b[i].x);
}

// Drum steps with flat end walls and a bidisperse fill (radii 1 and 2, half the solid in each, as the
// dynamic-vs-dem study's 3D drum): small spheres pile against the end walls, where a sphere rolling on the
// drum wall and on a sphere that touches the end wall too starts where its path's two branches meet (the
// case that once ended a hair inside the end wall or off the path). Every step stays valid.
TEST(DrumWall, BidisperseStepsAgainstEndWallsStayValid3D) {
  const Container c = drum(20.0, 12.0);
  DrumStepper stepper(3, c, 2.0);
  Deposition dep(3, c, 2.0);
  std::uint64_t state = 12345;
  auto uniform = [&state] {  // a fixed LCG: the same drops on every platform
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1p-53;
  };
  for (int i = 0; i < 550; ++i) {
    const double r = i % 9 == 0 ? 2.0 : 1.0;  // 8 small per large: equal solid
    dep.place(Drop{(uniform() - 0.5) * 2.0 * (20.0 - 2.0 * r), (uniform() - 0.5) * (12.0 - 2.0 * r), r, r > 1.5 ? 2 : 1});
  }
  Grains g = dep.grains();
  ASSERT_TRUE(check_packing(g, 3, c).ok());
  for (int s = 0; s < 60; ++s) {
    ASSERT_NO_THROW(g = stepper.step(g, 2.0 * M_PI / 100.0)) << "step " << s;
    const CheckReport rep = check_packing(g, 3, c);
    ASSERT_TRUE(rep.ok()) << "step " << s << ": " << rep.overlaps << " overlaps, " << rep.unsupported
                          << " unsupported, " << rep.outside << " outside";
  }
}

// The self-check's drum geometry is its own: a grain touching the wall is supported there, one pushed
// through the wall is outside, one floating in the middle is unsupported.
TEST(DrumCheck, CatchesGrainsThroughTheWallAndFloating) {
  const Container c = drum(10.0);
  const double th = 0.3;  // 0.3 rad from the lowest line, where the wall alone cannot hold a grain
  Grains bottom = {{Vec3(0.0, 0.0, 1.0), 1.0, 1}};
  EXPECT_TRUE(check_packing(bottom, 2, c).ok());
  Grains on_wall = {{Vec3(9.0 * std::sin(th), 0.0, 10.0 - 9.0 * std::cos(th)), 1.0, 1}};
  EXPECT_EQ(check_packing(on_wall, 2, c).unsupported, 1);  // one wall contact cannot hold it off the bottom
  Grains through = {{Vec3(9.2 * std::sin(th), 0.0, 10.0 - 9.2 * std::cos(th)), 1.0, 1}};
  const CheckReport rep = check_packing(through, 2, c);
  EXPECT_GE(rep.outside + rep.overlaps, 1);
  Grains floating = {{Vec3(0.0, 0.0, 5.0), 1.0, 1}};
  EXPECT_EQ(check_packing(floating, 2, c).unsupported, 1);
}

TEST(DrumStep, RotationKeepsDistanceFromTheAxisAndStepKeepsGrains) {
  const Container c = drum(20.0);
  DrumStepper stepper(2, c, 2.0);
  const Vec3 p(3.0, 0.0, 4.0), q = stepper.rotate(p, 0.5);
  EXPECT_NEAR(std::hypot(q.x(), q.z() - 20.0), std::hypot(p.x(), p.z() - 20.0), 1e-12);
  // The lowest point moves towards +x for a positive angle.
  EXPECT_GT(stepper.rotate(Vec3(0.0, 0.0, 0.0), 0.1).x(), 0.0);
  Deposition dep(2, c, 1.0);
  for (int i = 0; i < 120; ++i) dep.place(Drop{-15.0 + 0.25 * i, 0.0, i % 3 ? 0.5 : 1.0, i % 3 ? 1 : 2});
  Grains g = dep.grains();
  for (int s = 0; s < 10; ++s) {
    const Grains next = stepper.step(g, 2.0 * M_PI / 100.0);
    ASSERT_EQ(next.size(), g.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
      ASSERT_EQ(next[i].r, g[i].r);
      ASSERT_EQ(next[i].species, g[i].species);
    }
    const CheckReport rep = check_packing(next, 2, c);
    ASSERT_TRUE(rep.ok()) << "step " << s << ": " << rep.overlaps << " overlaps, " << rep.unsupported
                          << " unsupported, " << rep.outside << " outside";
    g = next;
  }
  // Same input, same step: the same result, bit for bit.
  const Grains a = stepper.step(g, 0.05), b = stepper.step(g, 0.05);
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i].x, b[i].x);
}

TEST(DrumMeasures, HandCases) {
  const Container c = drum(10.0);
  // Small grains at distance 2 from the axis, large ones at 8: index (8 - 2) / 10.
  Grains g = {{Vec3(2.0, 0, 10.0), 0.5, 1}, {Vec3(-2.0, 0, 10.0), 0.5, 1},
              {Vec3(0.0, 0, 2.0), 1.0, 2}, {Vec3(8.0, 0, 10.0), 1.0, 2}};
  const DrumMeasures m = drum_measures(g, 2, c);
  EXPECT_DOUBLE_EQ(m.split_radius, 1.0);  // the upper median of {0.5, 0.5, 1, 1}
  // With the split at the upper median every grain is "small": no index.
  EXPECT_EQ(m.segregation_index, 0.0);
  Grains h = {{Vec3(2.0, 0, 10.0), 0.5, 1}, {Vec3(-2.0, 0, 10.0), 0.5, 1}, {Vec3(0.0, 0, 10.0), 0.5, 1},
              {Vec3(0.0, 0, 2.0), 1.0, 2}, {Vec3(8.0, 0, 10.0), 1.0, 2}};
  const DrumMeasures n = drum_measures(h, 2, c);
  EXPECT_DOUBLE_EQ(n.split_radius, 0.5);
  EXPECT_NEAR(n.axis_small, 4.0 / 3.0, 1e-12);
  EXPECT_NEAR(n.axis_large, 8.0, 1e-12);
  EXPECT_NEAR(n.segregation_index, (8.0 - 4.0 / 3.0) / 10.0, 1e-12);
  // Free surface: a row of touching unit disks along z = 1 + 0.5 x (slope 0.5) gives atan(0.5).
  Grains slope;
  for (int i = -6; i <= 6; ++i) slope.push_back({Vec3(i * 1.0, 0, 5.0 + 0.5 * i), 0.5, 1});
  const DrumMeasures s = drum_measures(slope, 2, c);
  ASSERT_TRUE(s.surface_valid);
  EXPECT_NEAR(s.surface_angle_deg, std::atan(0.5) * 180.0 / M_PI, 1.0);
}

}  // namespace
}  // namespace btr
