// Drops over a heap's surface (btr/placement/heap_surface.h): the apex height solved against cone, triangle and
// ramp volumes by hand, the drops' radii those of the scene's own drop sequence, their spread against the cone's
// volume distribution, containment, determinism, refusals; and a BTR heap built from them keeps the angle asked.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "btr/measures/metrics.h"
#include "btr/placement/drops.h"
#include "btr/placement/heap_surface.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"

namespace btr {
namespace {

constexpr double kDeg = M_PI / 180.0;

Scene heap(int dim, std::int64_t count, double r) {
  Scene s;
  s.name = "heap";
  s.dimension = dim;
  s.grains.count = count;
  Component c;
  c.radius.kind = RadiusSpec::Kind::Constant;
  c.radius.value = r;
  s.grains.components = {c};
  s.container.kind = ContainerKind::Open;
  s.source.kind = SourceSpec::Kind::Point;
  return s;
}

double solid(const std::vector<Drop>& drops, int dim) {
  double v = 0.0;
  for (const Drop& d : drops) v += dim == 3 ? 4.0 / 3.0 * M_PI * std::pow(d.r, 3) : M_PI * d.r * d.r;
  return v;
}

TEST(HeapSurface, ConeOnAnOpenFloorHasTheApexOfItsVolume) {
  const Scene s = heap(3, 2000, 0.5e-3);
  const HeapSurfaceSampler sampler(s, 1, 2000, 25.0 * kDeg, 0.6);
  const HeapSurface& h = sampler.surface();
  const auto drops = sampler.draw(0);
  const double v = solid(drops, 3) / 0.6, t = std::tan(25.0 * kDeg);
  EXPECT_NEAR(h.volume, v, 1e-12 * v);
  // V = pi/3 H^3 / tan^2: the grid's cells (a quarter radius) sample it to well within 1 %.
  EXPECT_NEAR(h.apex_height, std::cbrt(3.0 * v * t * t / M_PI), 0.01 * h.apex_height);
  EXPECT_NEAR(h.reach, h.apex_height / t, 1e-12 * h.reach);
}

TEST(HeapSurface, TriangleIn2dAndRampAgainstAHeleShawEndWall) {
  {
    const Scene s = heap(2, 500, 0.5e-3);
    const HeapSurfaceSampler sampler(s, 1, 500, 30.0 * kDeg, 0.8);
    const HeapSurface& h = sampler.surface();
    const auto drops = sampler.draw(0);
    const double v = solid(drops, 2) / 0.8;
    EXPECT_NEAR(h.apex_height, std::sqrt(v * std::tan(30.0 * kDeg)), 0.01 * h.apex_height);  // V = H^2 / tan
  }
  Scene s = heap(3, 3000, 0.5e-3);
  s.container.kind = ContainerKind::HeleShaw;
  s.container.size_x = 0.1;
  s.container.gap = 5e-3;
  s.source.kind = SourceSpec::Kind::Region;
  s.source.x_min = -0.0495, s.source.x_max = -0.045;
  s.source.y_min = -2e-3, s.source.y_max = 2e-3;
  const HeapSurfaceSampler sampler(s, 1, 3000, 20.0 * kDeg, 0.6);
  const HeapSurface& h = sampler.surface();
  const auto drops = sampler.draw(0);
  // A plateau from the wall (x = -0.05) to the source's far edge, then the ramp: V / w = H a + H^2 / (2 tan).
  const double t = std::tan(20.0 * kDeg), a = 0.005, area = solid(drops, 3) / 0.6 / 5e-3;
  const double expected = (-a + std::sqrt(a * a + 2.0 * area / t)) * t;
  EXPECT_NEAR(h.apex_height, expected, 0.01 * expected);
  for (const Drop& d : drops) {
    ASSERT_LE(std::abs(d.y), 2.5e-3 - d.r);
    ASSERT_GE(d.x, -0.05 + d.r);
    ASSERT_LE(d.x, -0.045 + h.reach + 1e-4);  // nothing beyond the ramp's foot (one grid cell of slack)
  }
}

TEST(HeapSurface, DropsKeepTheSceneRadiiAndSpreadAsTheConesVolume) {
  Scene s = heap(3, 20000, 0.5e-3);
  s.grains.components[0].radius.kind = RadiusSpec::Kind::Uniform;
  s.grains.components[0].radius.min = 0.4e-3, s.grains.components[0].radius.max = 0.6e-3;
  const HeapSurfaceSampler sampler(s, 3, 20000, 30.0 * kDeg, 0.6);
  const HeapSurface& h = sampler.surface();
  const auto drops = sampler.draw(0);
  DropSequence sequence(s, 3);
  std::int64_t inner = 0;
  for (const Drop& d : drops) {
    const Drop own = sequence.next();
    ASSERT_EQ(d.r, own.r);
    ASSERT_EQ(d.species, own.species);
    if (std::hypot(d.x, d.y) < 0.5 * h.reach) ++inner;
  }
  // A cone's volume within u = rho / R of its axis is 3 u^2 - 2 u^3 of the whole: a half at u = 1/2.
  EXPECT_NEAR(static_cast<double>(inner) / 20000.0, 0.5, 0.02);
}

TEST(HeapSurface, SameArgumentsSameDropsAndPeriodicCellsWrap) {
  Scene s = heap(3, 400, 0.5e-3);
  s.container.kind = ContainerKind::Periodic;
  s.container.size_x = s.container.size_y = 0.012;  // narrower than the heap: its flanks wrap
  const auto a = HeapSurfaceSampler(s, 5, 400, 20.0 * kDeg, 0.6).draw(0);
  const auto b = HeapSurfaceSampler(s, 5, 400, 20.0 * kDeg, 0.6).draw(0);
  const auto c = HeapSurfaceSampler(s, 6, 400, 20.0 * kDeg, 0.6).draw(0);
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].x, b[i].x);
    ASSERT_EQ(a[i].y, b[i].y);
    ASSERT_GE(a[i].x, -0.006);
    ASSERT_LT(a[i].x, 0.006);
    ASSERT_GE(a[i].y, -0.006);
    ASSERT_LT(a[i].y, 0.006);
    differs = differs || a[i].x != c[i].x;
  }
  EXPECT_TRUE(differs);
  // Another draw of the same surface: the same grains, other positions.
  const HeapSurfaceSampler sampler(s, 5, 400, 20.0 * kDeg, 0.6);
  const auto d0 = sampler.draw(0), d1 = sampler.draw(1);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < d0.size(); ++i) {
    ASSERT_EQ(d0[i].r, d1[i].r);
    ASSERT_EQ(d0[i].x, a[i].x);
    moved += d0[i].x != d1[i].x;
  }
  EXPECT_GT(moved, d0.size() / 2);
  // The nearest image: a point just across the cell's edge is close to a source near the other edge.
  s.source.x = 0.0055;
  EXPECT_NEAR(distance_to_source(s, -0.0055, 0.0), 0.001, 1e-12);
}

TEST(HeapSurface, RefusesASourceWithoutAFootprintAndAnglesOutOfRange) {
  Scene s = heap(3, 10, 0.5e-3);
  s.source.kind = SourceSpec::Kind::Rain;
  s.container.kind = ContainerKind::Box;
  s.container.size_x = s.container.size_y = 0.01;
  EXPECT_THROW(HeapSurfaceSampler(s, 1, 10, 20.0 * kDeg, 0.6), SceneError);
  s = heap(3, 10, 0.5e-3);
  EXPECT_THROW(HeapSurfaceSampler(s, 1, 10, 0.0, 0.6), std::invalid_argument);
  EXPECT_THROW(HeapSurfaceSampler(s, 1, 10, 90.0 * kDeg, 0.6), std::invalid_argument);
  EXPECT_THROW(HeapSurfaceSampler(s, 1, 10, 20.0 * kDeg, 0.0), std::invalid_argument);
}

// The premise of settle's heaps: BTR keeps a surface whose slope is below its own limit (a point-source BTR
// heap stands near 57 deg), so the built heap's fitted flank is the angle asked, within the fit's scatter.
TEST(HeapSurface, ABtrHeapRainedOverTheSurfaceKeepsItsAngle) {
  const Scene s = heap(3, 3000, 0.5e-3);
  for (double angle : {15.0, 30.0}) {
    const auto drops = HeapSurfaceSampler(s, 2, 3000, angle * kDeg, 0.58).draw(0);
    const Grains grains = run_drops(s, drops, nullptr).grains;
    const HeapMeasures m = heap_measures(grains, 3, 0.0, 0.0);
    ASSERT_TRUE(m.valid) << m.note;
    EXPECT_NEAR(m.angle_deg, angle, 3.0);
  }
}

}  // namespace
}  // namespace btr
