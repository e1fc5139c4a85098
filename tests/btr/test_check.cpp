// The self-check itself, on configurations built by hand (no placement engine involved).
#include <gtest/gtest.h>

#include <cmath>

#include "btr/verify/check.h"
#include "containers.h"

namespace btr {
namespace {

using test::box;
using test::periodic;

Grain grain(double x, double y, double z, double r, int species = 1) {
  Grain g;
  g.x = Vec3(x, y, z);
  g.r = r;
  g.species = species;
  return g;
}

Container open() { return Container{}; }



// Three touching spheres of radius r on the floor, centroid at the origin.
Grains triangle(double r) {
  const double R = 2 * r / std::sqrt(3.0);  // circumradius of the triangle of side 2r
  Grains g;
  for (int k = 0; k < 3; ++k) {
    const double a = 2 * M_PI * k / 3;
    g.push_back(grain(R * std::cos(a), R * std::sin(a), r, r));
  }
  return g;
}

TEST(Check, EmptyPackingIsOk) {
  EXPECT_TRUE(check_packing({}, 3, open()).ok());
}

TEST(Check, SpheresOnTheFloorAreSupported) {
  const CheckReport rep = check_packing({grain(0, 0, 1, 1), grain(5, 0, 2, 2)}, 3, open());
  EXPECT_TRUE(rep.ok());
  EXPECT_NEAR(rep.max_overlap, 0.0, 1e-15);
}

TEST(Check, TwoOverlappingSpheresGiveOneOverlap) {
  // Radii 1 and 0.5, centres 1.3 apart: overlap 0.2, relative to the smaller radius 0.4.
  const CheckReport rep = check_packing({grain(0, 0, 1, 1), grain(1.3, 0, 1, 0.5)}, 3, open());
  EXPECT_EQ(rep.overlaps, 1);
  EXPECT_NEAR(rep.max_overlap, 0.4, 1e-12);
  EXPECT_EQ(rep.outside, 0);
  EXPECT_FALSE(rep.ok());
  ASSERT_EQ(rep.examples.size(), 2u);
}

TEST(Check, OverlapBelowToleranceIsAccepted) {
  const double r = 1e-3;
  Grains g = {grain(0, 0, r, r), grain(2 * r * (1 - 1e-12), 0, r, r)};
  EXPECT_EQ(check_packing(g, 3, open()).overlaps, 0);
  g[1].x.x() = 2 * r * (1 - 1e-6);
  EXPECT_EQ(check_packing(g, 3, open()).overlaps, 1);
}

TEST(Check, SphereOnThreeTouchingSpheresIsSupported) {
  const double r = 0.7;
  Grains g = triangle(r);
  g.push_back(grain(0, 0, r + 2 * r * std::sqrt(2.0 / 3.0), r));
  const CheckReport rep = check_packing(g, 3, open());
  EXPECT_TRUE(rep.ok()) << rep.overlaps << " " << rep.unsupported << " " << rep.outside;
  EXPECT_LT(rep.max_overlap, 1e-12);
}

TEST(Check, SphereMovedSidewaysOntoOneSphereIsUnsupported) {
  const double r = 0.7;
  Grains g = triangle(r);
  // Rest it on the first sphere only, on the side away from the others, 45 degrees up.
  const Vec3 out = Vec3(g[0].x.x(), g[0].x.y(), 0).normalized();
  const Vec3 dir = (out + Vec3(0, 0, 1)).normalized();
  g.push_back(grain(0, 0, 0, r));
  g.back().x = g[0].x + 2 * r * dir;
  const CheckReport rep = check_packing(g, 3, open());
  EXPECT_EQ(rep.unsupported, 1);
  EXPECT_EQ(rep.overlaps, 0);
  ASSERT_EQ(rep.examples.size(), 1u);
  EXPECT_EQ(rep.examples[0], 4);
}

TEST(Check, SphereJustAboveItsSupportsIsUnsupported) {
  // A gap of 1e-4 radii is not a contact.
  const double r = 0.7;
  Grains g = triangle(r);
  g.push_back(grain(0, 0, r + 2 * r * std::sqrt(2.0 / 3.0) + 1e-4 * r, r));
  EXPECT_EQ(check_packing(g, 3, open()).unsupported, 1);
}

TEST(Check, SphereInTheSaddleOfTwoSpheresIsSupported3D) {
  // Two touching spheres along x; a third sits on both at the lowest point of their circle.
  const double r = 1.0;
  Grains g = {grain(-r, 0, r, r), grain(r, 0, r, r), grain(0, 0, r + std::sqrt(3.0) * r, r)};
  EXPECT_TRUE(check_packing(g, 3, open()).ok());
  // Shifted along y (still touching both) it would roll down: unsupported.
  const double y = 0.5 * r, h = std::sqrt(4 * r * r - r * r - y * y);
  g[2].x = Vec3(0, y, r + h);
  EXPECT_EQ(check_packing(g, 3, open()).unsupported, 1);
}

// A sphere of radius 1 touching three spheres of radius 0.5 that stand on the floor around it, each
// contact normal 30 degrees above the horizontal at the given azimuths (degrees).
Grains on_three_supports(double a0, double a1, double a2) {
  const double r = 1.0, q = 0.5, theta = M_PI / 3;  // normal's angle from the vertical
  const Vec3 top(0, 0, q + (r + q) * std::cos(theta));
  Grains g;
  for (double deg : {a0, a1, a2}) {
    const double a = deg * M_PI / 180;
    const Vec3 n(std::cos(a) * std::sin(theta), std::sin(a) * std::sin(theta), std::cos(theta));
    const Vec3 c = top - (r + q) * n;
    g.push_back(grain(c.x(), c.y(), c.z(), q));
  }
  g.push_back(grain(top.x(), top.y(), top.z(), r));
  return g;
}

TEST(Check, ThreeContactsAllOnOneSideDoNotSupport) {
  // Normals at azimuths 0, 120, 240: gravity is balanced.
  CheckReport rep = check_packing(on_three_supports(0, 120, 240), 3, open());
  EXPECT_TRUE(rep.ok()) << rep.overlaps << " " << rep.unsupported << " " << rep.outside;
  // At 0, 90, 170 the horizontal parts of the normals all lie on one side: it topples.
  rep = check_packing(on_three_supports(0, 90, 170), 3, open());
  EXPECT_EQ(rep.unsupported, 1);
  EXPECT_EQ(rep.overlaps, 0);
  ASSERT_EQ(rep.examples.size(), 1u);
  EXPECT_EQ(rep.examples[0], 4);
}

TEST(Check, DiskBetweenTwoDisksIsSupported2D) {
  const double r = 0.25;
  Grains g = {grain(-r, 0, r, r), grain(r, 0, r, r), grain(0, 0, r + std::sqrt(3.0) * r, r)};
  EXPECT_TRUE(check_packing(g, 2, open()).ok());
}

TEST(Check, DiskOnOneSideOfADiskIsUnsupported2D) {
  const double r = 0.25;
  // Two separated disks; the third touches only the left one, on its outer side.
  const double a = M_PI / 3;  // 60 degrees above the horizontal
  Grains g = {grain(-1.5 * r, 0, r, r), grain(1.5 * r, 0, r, r),
              grain(-1.5 * r - 2 * r * std::cos(a), 0, r + 2 * r * std::sin(a), r)};
  const CheckReport rep = check_packing(g, 2, open());
  EXPECT_EQ(rep.unsupported, 1);
  EXPECT_EQ(rep.overlaps, 0);
  // Even touching both sides' grains is not enough if its centre is not between the contacts:
  // a disk on the inner side of the left disk, not reaching the right one, still rolls.
  g[2].x = Vec3(-1.5 * r + 2 * r * std::cos(a), 0, r + 2 * r * std::sin(a));
  EXPECT_EQ(check_packing(g, 2, open()).unsupported, 1);
}

TEST(Check, DiskNotInThePlaneIsOutside2D) {
  EXPECT_EQ(check_packing({grain(0, 1e-3, 1, 1)}, 2, open()).outside, 1);
}

TEST(Check, PeriodicImageContactCounts) {
  // 2D, period L: disks at both ends of the domain touch through the boundary; a third disk sits on
  // both right on the boundary.
  const double r = 1.0, L = 10.0;
  Grains g = {grain(-L / 2 + r, 0, r, r), grain(L / 2 - r, 0, r, r),
              grain(-L / 2, 0, r + std::sqrt(3.0) * r, r)};
  const CheckReport per = check_packing(g, 2, periodic(L, 0));
  EXPECT_TRUE(per.ok()) << per.overlaps << " " << per.unsupported << " " << per.outside;
  // Without the periodic image the top disk has a single contact and is not supported.
  EXPECT_EQ(check_packing(g, 2, open()).unsupported, 1);
}

TEST(Check, PeriodicImageContactCounts3D) {
  // The triangle of supports straddles the x and y boundaries.
  const double r = 0.7, L = 6.0;
  Grains g = triangle(r);
  g.push_back(grain(0, 0, r + 2 * r * std::sqrt(2.0 / 3.0), r));
  for (Grain& q : g) {
    q.x.x() += L / 2;
    q.x.y() += L / 2;
    q.x.x() -= L * std::floor(q.x.x() / L + 0.5);
    q.x.y() -= L * std::floor(q.x.y() / L + 0.5);
  }
  EXPECT_TRUE(check_packing(g, 3, periodic(L, L)).ok());
  EXPECT_EQ(check_packing(g, 3, open()).unsupported, 1);
}

TEST(Check, PeriodicImageOverlapCounts) {
  const double r = 1.0, L = 10.0;
  Grains g = {grain(-L / 2 + 0.5 * r, 0, r, r), grain(L / 2 - 0.5 * r, 0, r, r)};
  EXPECT_EQ(check_packing(g, 2, periodic(L, 0)).overlaps, 1);
  EXPECT_EQ(check_packing(g, 2, open()).overlaps, 0);
  // In 3D only x and y wrap: the same pair is also an overlap through y.
  g = {grain(0, -L / 2 + 0.5 * r, r, r), grain(0, L / 2 - 0.5 * r, r, r)};
  EXPECT_EQ(check_packing(g, 3, periodic(L, L)).overlaps, 1);
}

TEST(Check, SmallPeriodWithFewCellsCountsEachPairOnce) {
  // A period of barely more than two diameters: the grid has fewer than three cells per period.
  const double r = 1.0, L = 4.5;
  Grains g = {grain(-1.0, 0, r, r), grain(0.9, 0, r, r)};
  const CheckReport rep = check_packing(g, 2, periodic(L, 0));
  EXPECT_EQ(rep.overlaps, 1);
  EXPECT_NEAR(rep.max_overlap, 0.1, 1e-12);
}

TEST(Check, GrainThroughABoxWallIsOutside) {
  const double r = 1.0;
  const Container c = box(10, 8);
  EXPECT_TRUE(check_packing({grain(5 - r, 0, r, r)}, 3, c).ok());  // touching the wall
  CheckReport rep = check_packing({grain(5 - 0.5 * r, 0, r, r)}, 3, c);
  EXPECT_EQ(rep.outside, 1);
  EXPECT_NEAR(rep.max_overlap, 0.5, 1e-12);
  EXPECT_EQ(check_packing({grain(0, -4 + 0.9 * r, r, r)}, 3, c).outside, 1);  // y wall (3D)
  EXPECT_EQ(check_packing({grain(0, -4 + 0.9 * r, r, r)}, 2, c).outside, 1);  // y != 0 in 2D
  EXPECT_EQ(check_packing({grain(-5 + 0.9 * r, 0, r, r)}, 2, c).outside, 1);  // x wall (2D)
}

TEST(Check, GrainThroughTheFloorIsOutside) {
  const CheckReport rep = check_packing({grain(0, 0, 0.9, 1.0)}, 3, open());
  EXPECT_EQ(rep.outside, 1);
  EXPECT_EQ(rep.overlaps, 1);
}

TEST(Check, HeleShawPlatesAndEndWalls) {
  Container c;
  c.kind = ContainerKind::HeleShaw;
  c.size_x = 20;
  c.gap = 2.5;
  const double r = 1.0;
  EXPECT_TRUE(check_packing({grain(0, 0.25, r, r)}, 3, c).ok());  // touching the plate y = 1.25
  EXPECT_EQ(check_packing({grain(0, 0.5, r, r)}, 3, c).outside, 1);
  EXPECT_EQ(check_packing({grain(9.5, 0, r, r)}, 3, c).outside, 1);
  // A grain wedged between a plate and a smaller grain (on the floor against the other plate) is
  // held: the plate pushes it along -y, the small grain up and along +y.
  const double small = 0.4;
  Grains g = {grain(0, -1.25 + small, small, small)};
  // Grain of radius r touching the plate y = +1.25 and the small grain.
  const double dy = 1.25 - r - g[0].x.y();
  const double dz = std::sqrt((r + small) * (r + small) - dy * dy);
  g.push_back(grain(0, 1.25 - r, small + dz, r));
  EXPECT_TRUE(check_packing(g, 3, c).ok());
  // Open container: the same pair is not stable.
  EXPECT_EQ(check_packing(g, 3, open()).unsupported, 1);
}

TEST(Check, GrainBesideTheCylinderWall) {
  Container c;
  c.kind = ContainerKind::Cylinder;
  c.radius = 5;
  const double r = 1.0;
  const double s = std::sqrt(0.5);
  EXPECT_TRUE(check_packing({grain(4 * s, 4 * s, r, r)}, 3, c).ok());
  EXPECT_EQ(check_packing({grain(4.2 * s, 4.2 * s, r, r)}, 3, c).outside, 1);
  // Big grain against the wall resting on a smaller grain: held by wall + grain.
  const double R = 1.0, q = 0.5;
  Grains g = {grain(-(5 - R) + 0.3, 0, q, q)};  // small grain near the wall at -x
  // Big grain touching the wall at -x: centre at x = -(5 - R) (on the x axis), and the small grain.
  const double dx = g[0].x.x() + (5 - R);
  const double dz = std::sqrt((R + q) * (R + q) - dx * dx);
  g.push_back(grain(-(5 - R), 0, q + dz, R));
  EXPECT_TRUE(check_packing(g, 3, c).ok());
  EXPECT_EQ(check_packing(g, 3, open()).unsupported, 1);
}

TEST(Check, GrainHeldByABoxWallAndAGrain2D) {
  // Big disk on the floor against the wall x = L/2; small disk touching the wall and the big disk.
  const double L = 10, R = 1.0, r = 0.5;
  Grains g = {grain(L / 2 - R, 0, R, R), grain(L / 2 - r, 0, R + 2 * std::sqrt(R * r), r)};
  EXPECT_TRUE(check_packing(g, 2, box(L, 0)).ok());
  EXPECT_EQ(check_packing(g, 2, open()).unsupported, 1);
}

TEST(Check, ExtremeSizeRatioContactsAreFound) {
  // A grain 100 times smaller resting on top of a big one, and another one sunk into its side.
  const double R = 1.0, r = 0.01;
  Grains g = {grain(0, 0, R, R), grain(0, 0, 2 * R + r, r)};
  EXPECT_TRUE(check_packing(g, 3, open()).ok());
  g[1].x.z() += 1e-3 * r;  // no longer touching: unsupported
  EXPECT_EQ(check_packing(g, 3, open()).unsupported, 1);
  g.push_back(grain(R + 0.5 * r, 0, R, r));  // centre 0.5 r outside the big sphere's surface
  const CheckReport rep = check_packing(g, 3, open());
  EXPECT_EQ(rep.overlaps, 1);
  EXPECT_NEAR(rep.max_overlap, 0.5, 1e-9);
}

TEST(Check, GrainsFarApartAreHandled) {
  // Coordinates spanning 2e9 radii: the grid must neither overflow nor miss the close pair.
  Grains g = {grain(-1e9, 0, 1, 1), grain(1e9, 5, 1, 1), grain(1e9 + 1.5, 5, 1, 1)};
  const CheckReport rep = check_packing(g, 3, open());
  EXPECT_EQ(rep.overlaps, 1);
  EXPECT_EQ(rep.unsupported, 0);
}

TEST(Check, NonFiniteOrEmptyGrainsAreOutside) {
  Grains g = {grain(0, 0, 1, 1), grain(NAN, 0, 1, 1), grain(5, 0, 1, 0)};
  const CheckReport rep = check_packing(g, 3, open());
  EXPECT_EQ(rep.outside, 2);
  EXPECT_EQ(rep.overlaps, 0);
}

TEST(Check, LargeCubicStackIsFastAndOk) {
  // A simple cubic stack (each sphere on the one below) of 64^3 grains, shuffled, plus one broken
  // grain: the check must find exactly that one (its speed is measured by btr bench, not asserted here).
  const int n = 64;
  const double r = 1e-3;
  Grains g;
  g.reserve(n * n * n + 1);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) g.push_back(grain(2 * r * i, 2 * r * j, r + 2 * r * k, r));
  g.push_back(grain(2 * r * 10.5, 2 * r * 10, r + 2 * r * n + 1e-3 * r, r));  // hovering
  const CheckReport rep = check_packing(g, 3, open());
  EXPECT_EQ(rep.overlaps, 0);
  EXPECT_EQ(rep.outside, 0);
  EXPECT_EQ(rep.unsupported, 1);
  ASSERT_FALSE(rep.examples.empty());
  EXPECT_EQ(rep.examples[0], std::int64_t(g.size()));
}

}  // namespace
}  // namespace btr
