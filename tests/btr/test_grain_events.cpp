// The exact grain events of a roll (btr/placement/grain_arc_event.h, the analytic engine's and the mesh hybrid's): a straight
// segment and a circular arc against fixed grains, in radii.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "btr/placement/grain_arc_event.h"
#include "btr/placement/neighbour_grid.h"
#include "containers.h"

using namespace btr;

TEST(GrainEvents, SegmentMeetsTheFirstGrainAtItsEnteringRoot) {
  NeighbourGrid grid(3, test::box(20.0, 20.0), 1.0);
  grid.insert(0, Vec3(0.0, 0.0, 1.0), 1.0);   // met at s = 6 - sqrt(4 - 0.25)
  grid.insert(1, Vec3(3.0, 2.5, 1.0), 1.0);   // beside the line (2.5 > 2): never met
  grid.insert(2, Vec3(-8.0, 0.5, 1.0), 1.0);  // touching at the start, behind it: not met
  std::vector<Obstacle> hits;
  const Vec3 x0(-6.0, 0.5, 1.0), g(1.0, 0.0, 0.0);
  const double s = first_grain_on_segment(grid, 1.0, 1.0, x0, g, 30.0, nullptr, 0, hits);
  EXPECT_NEAR(s, 6.0 - std::sqrt(4.0 - 0.25), 1e-13);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_LT((hits[0].c - Vec3(0.0, 0.0, 1.0)).norm(), 1e-15);
  EXPECT_NEAR((x0 + s * g - hits[0].c).norm(), 2.0, 1e-13);
  // Shorter than the way to it: nothing met, the segment's end.
  EXPECT_EQ(first_grain_on_segment(grid, 1.0, 1.0, x0, g, 2.0, nullptr, 0, hits), 2.0);
  EXPECT_TRUE(hits.empty());
}

TEST(GrainEvents, ArcOverOneGrainMeetsTheNextWhereTheirSpheresCross) {
  // On grain 0 (at the origin, radius 1) a grain of radius 1 rolls from its top down the meridian in +x;
  // grain 1 at (3, 0, 0.5) is met where 12 sin t + 2 cos t = 9.25 (|P(t) - c1| = 2, P(t) = 2 (sin t, 0, cos t)).
  NeighbourGrid grid(3, test::box(20.0, 20.0), 1.0);
  grid.insert(0, Vec3(0.0, 0.0, 0.0), 1.0);
  grid.insert(1, Vec3(3.0, 0.0, 0.5), 1.0);
  Obstacle support;
  support.key = sphere_key(0, 0);
  support.c = Vec3::Zero();
  support.R = 2.0;
  CircleArc arc;
  arc.rho = 2.0, arc.u = Vec3::UnitZ(), arc.v = Vec3::UnitX(), arc.t_end = M_PI / 2;
  Contacts supports;
  supports.add(support);
  const Event ev = first_grain_event(grid, 1.0, 1.0, supports, arc);
  const double A = std::hypot(12.0, 2.0), phi = std::atan2(12.0, 2.0);
  EXPECT_NEAR(ev.t, phi - std::acos(9.25 / A), 1e-12);
  ASSERT_EQ(ev.hits.n, 1);
  EXPECT_NEAR((arc.at(ev.t) - ev.hits.item[0].c).norm(), 2.0, 1e-12);
  EXPECT_EQ(ev.lift_off, -1);
}
