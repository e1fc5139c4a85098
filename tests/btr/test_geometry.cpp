// The placement engine against hand-computed cases, through the public API only. Fixtures are
// built by dropping grains onto the empty floor (they land at z = r below the drop point); every
// expected position is computed here in closed form from the fixtures' positions.
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <string>

#include <Eigen/Geometry>

#include "btr/placement/deposition.h"
#include "btr/verify/check.h"
#include "containers.h"

namespace btr {
namespace {

using test::box;
using test::periodic;

constexpr double kRel = 1e-9;  // tolerance relative to the largest radius of the case

Vec3 drop(Deposition& dep, double x, double y, double r, int species = 1) {
  return dep.place(Drop{x, y, r, species}).x;  // copy: the reference dies with the next place()
}

// A fixture grain: dropped on the empty floor it lands right below the drop point.
Vec3 fixture(Deposition& dep, double x, double y, double r) {
  const Vec3 p = drop(dep, x, y, r);
  const double y_expected = dep.dimension() == 2 ? 0.0 : y;
  EXPECT_NEAR(p.x(), x, kRel * r);
  EXPECT_NEAR(p.y(), y_expected, kRel * r);
  EXPECT_NEAR(p.z(), r, kRel * r);
  return p;
}

// Within kRel * scale of the expected point, with both points in the failure message.
::testing::AssertionResult at_point(const Vec3& got, const Vec3& expected, double scale) {
  const double dist = (got - expected).norm();
  if (dist < kRel * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << std::setprecision(17) << "got " << got.transpose()
                                       << ", expected " << expected.transpose() << ", distance "
                                       << dist;
}
#define EXPECT_AT(got, expected, scale) EXPECT_TRUE(at_point((got), (expected), (scale)))

void expect_valid(const Deposition& dep) {
  const CheckReport rep = check_packing(dep.grains(), dep.dimension(), dep.container());
  EXPECT_TRUE(rep.ok()) << "overlaps " << rep.overlaps << " (max " << rep.max_overlap
                        << "), unsupported " << rep.unsupported << ", outside " << rep.outside;
}

// The point at distance d1 from c1 and d2 from c2 in the x-z plane, with the larger z.
Vec3 upper_intersection_2d(const Vec3& c1, double d1, const Vec3& c2, double d2) {
  const Eigen::Vector2d a(c1.x(), c1.z()), b(c2.x(), c2.z());
  const double d = (b - a).norm();
  const double along = (d1 * d1 - d2 * d2 + d * d) / (2 * d);
  const double h = std::sqrt(d1 * d1 - along * along);
  const Eigen::Vector2d u = (b - a) / d, n(-u.y(), u.x());
  Eigen::Vector2d p = a + along * u + h * n;
  if (n.y() < 0) p = a + along * u - h * n;
  return Vec3(p.x(), 0, p.y());
}

// The point at distances d1, d2, d3 from c1, c2, c3, with the larger z (trilateration).
Vec3 upper_trilateration(const Vec3& c1, double d1, const Vec3& c2, double d2, const Vec3& c3, double d3) {
  const Vec3 ex = (c2 - c1).normalized();
  const double i = ex.dot(c3 - c1);
  const Vec3 ey = (c3 - c1 - i * ex).normalized();
  const Vec3 ez = ex.cross(ey);
  const double d = (c2 - c1).norm(), j = ey.dot(c3 - c1);
  const double x = (d1 * d1 - d2 * d2 + d * d) / (2 * d);
  const double y = (d1 * d1 - d3 * d3 + i * i + j * j - 2 * i * x) / (2 * j);
  const double z = std::sqrt(d1 * d1 - x * x - y * y);
  const Vec3 p1 = c1 + x * ex + y * ey + z * ez, p2 = c1 + x * ex + y * ey - z * ez;
  return p1.z() > p2.z() ? p1 : p2;
}


// ---------------------------------------------------------------------------------------------
// Fall

TEST(Geometry, FallToTheFloor) {
  Deposition d3(3, Container{}, 1.0);
  EXPECT_AT(drop(d3, 0.25, -0.5, 0.75), Vec3(0.25, -0.5, 0.75), 1.0);
  Deposition d2(2, Container{}, 1.0);
  EXPECT_AT(drop(d2, -0.5, 7.0, 0.5), Vec3(-0.5, 0, 0.5), 1.0);  // y is ignored in 2D
  EXPECT_EQ(d2.grains().size(), 1u);
  EXPECT_EQ(d2.grains()[0].x.y(), 0.0);
}

TEST(Geometry, FallBetweenTwoDisksStopsAtFirstContact2D) {
  // Symmetric: both contacts at the same instant, at z = R + sqrt((R + r)^2 - a^2).
  const double R = 1.0, r = 0.7, a = 1.4;
  Deposition dep(2, Container{}, R);
  fixture(dep, -a, 0, R);
  fixture(dep, a, 0, R);
  EXPECT_AT(drop(dep, 0, 0, r), Vec3(0, 0, R + std::sqrt((R + r) * (R + r) - a * a)), R);
  expect_valid(dep);
}

TEST(Geometry, SphereOnThreeTouchingSpheres) {
  // Dropped at the centroid (three contacts at once) or off it (falls on one, rolls over two to
  // the third): the same rest point, z = r + 2 r sqrt(2/3) above the centroid.
  const double r = 0.5, R = 2 * r / std::sqrt(3.0);
  for (const Eigen::Vector2d& off : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.07, 0.02),
                                     Eigen::Vector2d(-0.03, -0.11)}) {
    Deposition dep(3, Container{}, r);
    for (int k = 0; k < 3; ++k)
      fixture(dep, R * std::cos(2 * M_PI * k / 3), R * std::sin(2 * M_PI * k / 3), r);
    const Vec3 centroid = (dep.grains()[0].x + dep.grains()[1].x + dep.grains()[2].x) / 3;
    const Vec3 got = drop(dep, off.x(), off.y(), r);
    EXPECT_AT(got, Vec3(centroid.x(), centroid.y(), r + 2 * r * std::sqrt(2.0 / 3.0)), r)
        << " drop offset " << off.transpose();
    expect_valid(dep);
  }
}

TEST(Geometry, SphereInAPocketOfThreeUnequalSpheres) {
  // Radii 1.0, 0.8, 1.2 around a gap the grain cannot pass: it rests touching all three.
  const double r = 0.9;
  Deposition dep(3, Container{}, 1.2);
  const Vec3 a = fixture(dep, -1.1, -0.7, 1.0);
  const Vec3 b = fixture(dep, 1.0, -0.6, 0.8);
  const Vec3 c = fixture(dep, 0.0, 1.2, 1.2);
  const Vec3 expected = upper_trilateration(a, 1.0 + r, b, 0.8 + r, c, 1.2 + r);
  EXPECT_AT(drop(dep, 0.05, -0.1, r), expected, 1.2);
  expect_valid(dep);
}

// ---------------------------------------------------------------------------------------------
// Roll on one grain

TEST(Geometry, SmallGrainRollsOffABigOne2D) {
  // Leaves the big disk at its equator and falls to the floor at horizontal distance R + r.
  const double R = 1.0, r = 0.3;
  for (double side : {1.0, -1.0}) {
    Deposition dep(2, Container{}, R);
    fixture(dep, 0, 0, R);
    EXPECT_AT(drop(dep, 0.1 * side, 0, r), Vec3(side * (R + r), 0, r), R);
    expect_valid(dep);
  }
}

TEST(Geometry, BigGrainRollsDownASmallOneToTheFloor2D) {
  // Touches the floor at horizontal distance 2 sqrt(R r) while still on the small disk.
  const double rs = 0.5, rb = 2.0;
  Deposition dep(2, Container{}, rb);
  fixture(dep, 0, 0, rs);
  EXPECT_AT(drop(dep, 0.1, 0, rb), Vec3(2 * std::sqrt(rs * rb), 0, rb), rb);
  expect_valid(dep);
}

TEST(Geometry, SmallGrainRollsOffABigOne3D) {
  const double R = 1.0, r = 0.3;
  Deposition dep(3, Container{}, R);
  fixture(dep, 0, 0, R);
  // Rolls in the vertical plane through both centres: direction (0.6, 0.8).
  EXPECT_AT(drop(dep, 0.06, 0.08, r), Vec3(0.6 * (R + r), 0.8 * (R + r), r), R);
  expect_valid(dep);
}

TEST(Geometry, BigGrainRollsDownASmallOneToTheFloor3D) {
  const double rs = 0.5, rb = 2.0;
  Deposition dep(3, Container{}, rb);
  fixture(dep, 0, 0, rs);
  const double h = 2 * std::sqrt(rs * rb);
  EXPECT_AT(drop(dep, -0.06, 0.08, rb), Vec3(-0.6 * h, 0.8 * h, rb), rb);
  expect_valid(dep);
}

TEST(Geometry, DiskRollsIntoThePocketOfTwoUnequalDisks2D) {
  // Lands on the left disk (its contact is higher), rolls right onto the second one and stops.
  const double r = 0.5;
  Deposition dep(2, Container{}, 1.0);
  const Vec3 a = fixture(dep, -1.2, 0, 1.0);
  const Vec3 b = fixture(dep, 0.9, 0, 0.6);
  const Vec3 expected = upper_intersection_2d(a, 1.0 + r, b, 0.6 + r);
  ASSERT_GT(expected.x(), a.x());
  ASSERT_LT(expected.x(), b.x());
  EXPECT_AT(drop(dep, 0.2, 0, r), expected, 1.0);
  expect_valid(dep);
}

TEST(Geometry, PyramidOfThreeDisks2D) {
  const double r = 0.25;
  for (double x : {0.0, 0.3 * r, -0.45 * r}) {
    Deposition dep(2, Container{}, r);
    fixture(dep, -r, 0, r);
    fixture(dep, r, 0, r);
    EXPECT_AT(drop(dep, x, 0, r), Vec3(0, 0, r + std::sqrt(3.0) * r), r) << " dropped at " << x;
    expect_valid(dep);
  }
}

// ---------------------------------------------------------------------------------------------
// Roll on two grains (3D): A and B of radius R at x = -+a on the floor, the grain rolls on A into
// B, then along the circle of radius rho = sqrt((R + r)^2 - a^2) about their axis, in the plane
// x = 0. Both loads are cos(psi) (R + r) / (2 rho): they vanish at the axis height z = R.

TEST(Geometry, RollOnTwoSpheresLeavesAtTheirAxisAndFalls) {
  const double R = 1.0, a = 1.5, r = 0.8;  // r < R: the axis height comes before the floor
  Deposition dep(3, Container{}, R);
  fixture(dep, -a, 0, R);
  fixture(dep, a, 0, R);
  const double rho = std::sqrt((R + r) * (R + r) - a * a);
  EXPECT_AT(drop(dep, -0.5, 0.05, r), Vec3(0, rho, r), R);
  expect_valid(dep);
}

TEST(Geometry, RollOnTwoSpheresReachesTheFloor) {
  const double R = 1.0, a = 1.5, r = 1.5;  // a^2 < 4 R r: the floor comes first
  Deposition dep(3, Container{}, r);
  fixture(dep, -a, 0, R);
  fixture(dep, a, 0, R);
  EXPECT_AT(drop(dep, -0.5, 0.05, r), Vec3(0, std::sqrt(4 * R * r - a * a), r), r);
  expect_valid(dep);
}

TEST(Geometry, RollOnTwoSpheresStopsOnTheThird) {
  // A third sphere C at (0, c) on the floor: the grain stops touching A, B and C at
  // y = (c^2 - a^2) / (2c), z = R + sqrt(rho^2 - y^2).
  const double R = 1.0, a = 1.5, r = 1.0, c = 2.2;
  Deposition dep(3, Container{}, R);
  fixture(dep, -a, 0, R);
  fixture(dep, a, 0, R);
  fixture(dep, 0, c, R);
  const double rho2 = (R + r) * (R + r) - a * a;
  const double y = (c * c - a * a) / (2 * c);
  EXPECT_AT(drop(dep, -0.5, 0.05, r), Vec3(0, y, R + std::sqrt(rho2 - y * y)), R);
  expect_valid(dep);
}

// ---------------------------------------------------------------------------------------------
// Degenerate cases: they must end, with a valid packing.

TEST(Geometry, DropExactlyAboveACentre) {
  // Balanced on top (the forces balance exactly), or rolled off in some direction down to the
  // floor, touching the fixture's equator-level circle: both are supported endings.
  const double R = 1.0;
  for (int dim : {2, 3}) {
    Deposition dep(dim, Container{}, R);
    fixture(dep, 0, 0, R);
    const Vec3 got = drop(dep, 0, 0, R);
    const bool on_top = (got - Vec3(0, 0, 3 * R)).norm() < kRel * R;
    const bool rolled_off = std::abs(std::hypot(got.x(), got.y()) - 2 * R) < kRel * R &&
                            std::abs(got.z() - R) < kRel * R;
    EXPECT_TRUE(on_top || rolled_off) << "dim " << dim << " got " << got.transpose();
    expect_valid(dep);
  }
}

TEST(Geometry, CollinearSupports) {
  // Three touching spheres on a line along x. A grain of the same radius dropped exactly on the
  // line between two of them lands on both at once (balanced on top of their circle, or rolled
  // sideways to the floor); dropped slightly off the line it rolls down their circle to y = sqrt(3) R
  // where the floor and the loss of both loads coincide.
  const double R = 1.0;
  auto make = [&](Deposition& dep) {
    for (double x : {-2 * R, 0.0, 2 * R}) fixture(dep, x, 0, R);
  };
  {
    Deposition dep(3, Container{}, R);
    make(dep);
    const Vec3 got = drop(dep, R, 0, R);
    const bool on_top = (got - Vec3(R, 0, R + std::sqrt(3.0) * R)).norm() < kRel * R;
    const bool rolled = (got - Vec3(R, std::sqrt(3.0) * R, R)).norm() < kRel * R ||
                        (got - Vec3(R, -std::sqrt(3.0) * R, R)).norm() < kRel * R;
    EXPECT_TRUE(on_top || rolled) << got.transpose();
    expect_valid(dep);
  }
  {
    Deposition dep(3, Container{}, R);
    make(dep);
    EXPECT_AT(drop(dep, 1.1 * R, 0.001 * R, R), Vec3(R, std::sqrt(3.0) * R, R), R);
    expect_valid(dep);
  }
  {
    // Smaller grain: leaves the pair at the axis height and falls, at y = sqrt((R + r)^2 - R^2).
    const double r = 0.6;
    Deposition dep(3, Container{}, R);
    make(dep);
    EXPECT_AT(drop(dep, 1.1 * R, -0.001 * R, r), Vec3(R, -std::sqrt((R + r) * (R + r) - R * R), r), R);
    expect_valid(dep);
  }
}

// ---------------------------------------------------------------------------------------------
// Walls

TEST(Geometry, DiskOnADiskAgainstABoxWall2D) {
  // Big disk on the floor against the wall x = L/2; the small disk, dropped touching the wall
  // (a wall and a grain at once) or dropped onto the big disk and rolling into the wall, rests at
  // x = L/2 - r, z = R + 2 sqrt(R r).
  const double L = 10, R = 1.0, r = 0.5;
  for (double side : {1.0, -1.0})
    for (double x : {L / 2 - r, L / 2 - R + 0.3 * R}) {
      Deposition dep(2, box(L), R);
      fixture(dep, side * (L / 2 - R), 0, R);
      EXPECT_AT(drop(dep, side * x, 0, r), Vec3(side * (L / 2 - r), 0, R + 2 * std::sqrt(R * r)), R)
          << "side " << side << " drop " << x;
      expect_valid(dep);
    }
}

TEST(Geometry, SphereOnTwoSpheresAgainstABoxWall3D) {
  // Two spheres against the wall x = L/2 at y = -+b; the grain comes to rest touching both and the
  // wall: x = L/2 - r, y = 0, z = R + sqrt((R + r)^2 - (R - r)^2 - b^2).
  const double L = 10, W = 8, R = 1.0, r = 0.5, b = 1.25;
  for (double x : {L / 2 - r, L / 2 - R + 0.3}) {
    Deposition dep(3, box(L, W), R);
    fixture(dep, L / 2 - R, -b, R);
    fixture(dep, L / 2 - R, b, R);
    const double z = R + std::sqrt((R + r) * (R + r) - (R - r) * (R - r) - b * b);
    EXPECT_AT(drop(dep, x, 0.1, r), Vec3(L / 2 - r, 0, z), R) << "drop x " << x;
    expect_valid(dep);
  }
}

TEST(Geometry, SphereAgainstABoxWallRollsDownAlongIt3D) {
  // On one sphere and the wall: the circle in the plane x = L/2 - r of radius 2 sqrt(R r) about the
  // sphere's centre; both loads vanish at z = R, then the grain falls along the wall.
  const double L = 10, W = 8, R = 1.0, r = 0.5;
  Deposition dep(3, box(L, W), R);
  fixture(dep, L / 2 - R, 0, R);
  EXPECT_AT(drop(dep, L / 2 - r, 0.001, r), Vec3(L / 2 - r, 2 * std::sqrt(R * r), r), R);
  expect_valid(dep);
}

TEST(Geometry, HeleShawPlates) {
  // Plates at y = -+w/2. A sphere against one plate; a smaller one dropped against the other plate
  // rolls on the first along that plate (circle of radius rho in the plane y = w/2 - r), leaves it at
  // z = R and falls to the floor at x = rho.
  Container c;
  c.kind = ContainerKind::HeleShaw;
  c.size_x = 20;
  c.gap = 2.2;
  const double R = 1.0, r = 0.6;
  Deposition dep(3, c, R);
  fixture(dep, 0, -c.gap / 2 + R, R);
  const double dy = c.gap - R - r;
  const double rho = std::sqrt((R + r) * (R + r) - dy * dy);
  EXPECT_AT(drop(dep, 0.3, c.gap / 2 - r, r), Vec3(rho, c.gap / 2 - r, r), R);
  // A grain dropped at the middle of the gap falls onto the floor between the plates.
  EXPECT_AT(drop(dep, -5, 0, r), Vec3(-5, 0, r), R);
  expect_valid(dep);
}

TEST(Geometry, GrainBesideTheCylinderWall) {
  // Two spheres against the wall at azimuths -+phi; a smaller grain dropped against the wall near
  // azimuth 0 rests on both and the wall: at distance Rc - r from the axis, azimuth 0.
  Container c;
  c.kind = ContainerKind::Cylinder;
  c.radius = 5;
  const double R = 1.0, r = 0.5, phi = 0.3;
  const double in = 1 - 1e-13;  // drop points a hair inside, so no rounding puts them outside
  // Dropped against the wall onto the empty floor: lands there, touching the wall.
  Deposition dep(3, c, R);
  EXPECT_AT(drop(dep, (c.radius - R) * in, 0, R), Vec3((c.radius - R) * in, 0, R), R);
  Deposition dep2(3, c, R);
  const Vec3 a = fixture(dep2, (c.radius - R) * in * std::cos(phi), (c.radius - R) * in * std::sin(phi), R);
  const Vec3 b = fixture(dep2, (c.radius - R) * in * std::cos(phi), -(c.radius - R) * in * std::sin(phi), R);
  const double x = c.radius - r;
  const double z = a.z() + std::sqrt((R + r) * (R + r) - (x - a.x()) * (x - a.x()) - a.y() * a.y());
  EXPECT_NEAR(std::abs(a.y()), std::abs(b.y()), 1e-15);
  EXPECT_AT(drop(dep2, x * in * std::cos(0.02), x * in * std::sin(0.02), r), Vec3(x, 0, z), R);
  expect_valid(dep);
  expect_valid(dep2);
}

// ---------------------------------------------------------------------------------------------
// Periodic boundaries

TEST(Geometry, PeriodicRollOverTheImageWraps2D) {
  // Period 10: a disk at x = -4.5 has an image at 5.5. A disk dropped at 4.9 lands on the image and
  // rolls off to 5.5 - 2 = 3.5; dropped at -4.9 it rolls left across the boundary to -6.5 = 3.5.
  Container c;
  c.kind = ContainerKind::Periodic;
  c.size_x = 10;
  const double R = 1.0;
  for (double x : {4.9, -4.9}) {
    Deposition dep(2, c, R);
    fixture(dep, -4.5, 0, R);
    EXPECT_AT(drop(dep, x, 0, R), Vec3(3.5, 0, R), R) << "drop " << x;
    expect_valid(dep);
  }
}

TEST(Geometry, PeriodicRollOverTheImage3D) {
  // Period 10 x 8: a sphere at (0, -3.5) has an image at (0, 4.5). A sphere dropped at (0.03, 3.9)
  // lands on the image and rolls off away from it, to horizontal distance 2R.
  Container c;
  c.kind = ContainerKind::Periodic;
  c.size_x = 10;
  c.size_y = 8;
  const double R = 1.0;
  Deposition dep(3, c, R);
  fixture(dep, 0, -3.5, R);
  const Eigen::Vector2d image(0, 4.5), from(0.03, 3.9);
  const Eigen::Vector2d end = image + 2 * R * (from - image).normalized();
  EXPECT_AT(drop(dep, from.x(), from.y(), R), Vec3(end.x(), end.y(), R), R);
  expect_valid(dep);
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST(Geometry, PlacementErrorIsCatchableAndNamesTheGrain) {
  const PlacementError e(7, "event budget exhausted");
  try {
    throw e;
  } catch (const std::runtime_error& caught) {
    EXPECT_NE(std::string(caught.what()).find("grain 7"), std::string::npos);
  }
  EXPECT_EQ(e.grain_id(), 7);
}

TEST(Geometry, EventBudgetExhaustedIsAnErrorNotAPlacement) {
  // The grain of RollOnTwoSpheresStopsOnTheThird needs a fall, a roll on one sphere and a roll on
  // two before it rests: with a budget of 2 events it must throw, naming grain 4, and not be placed.
  Deposition dep(3, Container{}, 1.0, 2);
  fixture(dep, -1.5, 0, 1.0);
  fixture(dep, 1.5, 0, 1.0);
  fixture(dep, 0, 2.2, 1.0);
  try {
    dep.place(Drop{-0.5, 0.05, 1.0, 1});
    ADD_FAILURE() << "no PlacementError";
  } catch (const PlacementError& e) {
    EXPECT_EQ(e.grain_id(), 4);
    EXPECT_NE(std::string(e.what()).find("grain 4"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dep.grains().size(), 3u);
}

TEST(Geometry, DropOutsideTheBoxIsAnError) {
  Deposition dep(3, box(10, 8), 1.0);
  EXPECT_THROW(dep.place(Drop{6.0, 0, 1.0, 1}), PlacementError);
  EXPECT_EQ(dep.grains().size(), 0u);
}

}  // namespace
}  // namespace btr
