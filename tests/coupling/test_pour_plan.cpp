// The reference pour's plan (coupling/dem/pour_plan.h): lattice sites inside the container, batches covering
// every grain once, the relaxation's time-step rule, determinism, refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "coupling/dem/check_schedule.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/pour_plan.h"
#include "coupling/dem/relax_plan.h"

namespace btr {
namespace {

Scene scene_in(const Container& c, int dimension, SourceSpec::Kind source = SourceSpec::Kind::Rain) {
  Scene s;
  s.name = "pour_plan";
  s.file = "pour_plan.toml";
  s.dimension = dimension;
  Component a;
  a.species = 1;
  a.density = 2500.0;
  a.material.young = 5e7;
  a.material.poisson = 0.3;
  a.material.restitution = 0.6;
  Component b = a;  // a second species: denser, softer, lower restitution
  b.species = 2;
  b.density = 7800.0;
  b.material.young = 2e7;
  b.material.poisson = 0.25;
  b.material.restitution = 0.4;
  s.grains.components = {a, b};
  s.container = c;
  s.source.kind = source;
  return s;
}

// n grains of radii in [0.8, 1.2] mm (species 2 from 0.5 mm), alternating species.
Grains some_grains(std::size_t n, std::uint64_t seed = 3) {
  std::mt19937_64 rng(seed);
  Grains g(n);
  for (std::size_t i = 0; i < n; ++i) {
    g[i].species = 1 + static_cast<int>(i % 2);
    const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    g[i].r = g[i].species == 1 ? 0.8e-3 + 0.4e-3 * u : 0.5e-3 + 0.7e-3 * u;
    g[i].x = Vec3::Zero();
  }
  return g;
}

Container box(double sx, double sy) {
  Container c;
  c.kind = ContainerKind::Box, c.size_x = sx, c.size_y = sy;
  return c;
}

struct Case {
  const char* name;
  Container container;
  int dimension;
  SourceSpec::Kind source;
};

std::vector<Case> cases() {
  Container per;
  per.kind = ContainerKind::Periodic, per.size_x = 0.012, per.size_y = 0.01;
  Container cyl;
  cyl.kind = ContainerKind::Cylinder, cyl.radius = 0.007;
  Container hs;
  hs.kind = ContainerKind::HeleShaw, hs.size_x = 0.03, hs.gap = 0.0026;  // under 2 (r_max + jitter): mid-plane
  Container open;
  return {{"box3d", box(0.012, 0.01), 3, SourceSpec::Kind::Rain},
          {"box2d", box(0.02, 0.0), 2, SourceSpec::Kind::Rain},
          {"periodic3d", per, 3, SourceSpec::Kind::Rain},
          {"periodic_point", per, 3, SourceSpec::Kind::Point},
          {"cylinder", cyl, 3, SourceSpec::Kind::Rain},
          {"hele_shaw", hs, 3, SourceSpec::Kind::Rain},
          {"hele_shaw_point", hs, 3, SourceSpec::Kind::Point},
          {"open_point", open, 3, SourceSpec::Kind::Point},
          {"open_region2d", open, 2, SourceSpec::Kind::Region}};
}

double wrap(double x, double period) { return x - period * std::floor(x / period + 0.5); }

TEST(PourPlan, LatticeSitesLieInsideTheContainerWithoutOverlap) {
  for (const Case& k : cases()) {
    SCOPED_TRACE(k.name);
    Scene s = scene_in(k.container, k.dimension, k.source);
    s.source.x_min = -0.004, s.source.x_max = 0.004;  // region sources
    const Grains grains = some_grains(230);
    const PourLattice L = pour_lattice(grains, s, 7, 10, 2e-3);
    ASSERT_EQ(L.grains.size(), grains.size());
    const std::vector<DemWall> walls = dem_walls(k.container, k.dimension);
    for (std::size_t i = 0; i < grains.size(); ++i) {
      const Grain& g = L.grains[i];
      EXPECT_EQ(g.r, grains[i].r);
      EXPECT_EQ(g.species, grains[i].species);
      for (const DemWall& w : walls) EXPECT_GE(w.distance(g.x), g.r) << "grain " << i + 1 << " against " << w.name;
      if (k.dimension == 2) {
        EXPECT_EQ(g.x.y(), 0.0);
      }
      if (k.container.kind == ContainerKind::Periodic) {
        EXPECT_LT(std::abs(g.x.x()), 0.5 * k.container.size_x + 1e-15);
        EXPECT_LT(std::abs(g.x.y()), 0.5 * k.container.size_y + 1e-15);
      }
      EXPECT_GE(g.x.z(), L.hold_base - kPourJitter * L.spacing);
    }
    double closest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < grains.size(); ++i)
      for (std::size_t j = i + 1; j < grains.size(); ++j) {
        Vec3 d = L.grains[i].x - L.grains[j].x;
        if (k.container.kind == ContainerKind::Periodic) {
          d.x() = wrap(d.x(), k.container.size_x);
          d.y() = wrap(d.y(), k.container.size_y);
        }
        closest = std::min(closest, d.norm() - L.grains[i].r - L.grains[j].r);
      }
    EXPECT_GT(closest, 0.0);
  }
}

TEST(PourPlan, BatchesCoverEveryGrainOnceInWholeLayers) {
  const Scene s = scene_in(box(0.012, 0.01), 3);
  for (int max_batches : {1, 3, 10, 1000}) {
    const PourLattice L = pour_lattice(some_grains(230), s, 1, max_batches, 2e-3);
    ASSERT_FALSE(L.batches.empty());
    EXPECT_LE(L.batches.size(), static_cast<std::size_t>(max_batches));
    std::size_t next = 0;
    for (const PourRelease::Batch& b : L.batches) {
      EXPECT_EQ(b.first, next);
      EXPECT_LE(b.first, b.last);
      EXPECT_EQ(b.first % L.sites_per_layer, 0u);  // a batch starts a layer
      next = b.last + 1;
    }
    EXPECT_EQ(next, 230u);
    EXPECT_EQ(L.layers, (230 + L.sites_per_layer - 1) / L.sites_per_layer);
    // ids fill the layers from the bottom: layer k / sites_per_layer
    for (std::size_t k = 0; k + 1 < 230; ++k) {
      const double layer_k = std::round((L.grains[k].x.z() - L.hold_base) / L.spacing);
      const double layer_next = std::round((L.grains[k + 1].x.z() - L.hold_base) / L.spacing);
      EXPECT_LE(layer_k, layer_next);
    }
  }
}

TEST(PourPlan, SameSeedSameLatticeOtherSeedAnother) {
  const Scene s = scene_in(box(0.012, 0.01), 3);
  const Grains g = some_grains(100);
  const PourLattice a = pour_lattice(g, s, 5, 10, 2e-3), b = pour_lattice(g, s, 5, 10, 2e-3);
  const PourLattice c = pour_lattice(g, s, 6, 10, 2e-3);
  bool differs = false;
  for (std::size_t i = 0; i < g.size(); ++i) {
    EXPECT_EQ(a.grains[i].x, b.grains[i].x);  // bit for bit
    differs = differs || a.grains[i].x != c.grains[i].x;
  }
  EXPECT_TRUE(differs);
}

// The Rayleigh time of the smallest grain of each species, by hand: pi R sqrt(rho / G) / (0.1631 nu + 0.8766),
// G = E / (2 (1 + nu)); times the fraction and sqrt(1 + zeta^2) - zeta for the lowest restitution 0.4
// (LIGGGHTS: the normal damping ratio; YADE: that ratio times sqrt(7 / (2 kappa)), kappa = 2 (1 - nu) / (2 - nu)
// the smallest over the species).
TEST(PourPlan, TimeStepIsTheRelaxationsRuleComputedByHand) {
  Scene s = scene_in(box(0.012, 0.01), 3);
  s.relax.timestep_fraction = 0.2;
  const Grains g = some_grains(120);
  double r1 = 1.0, r2 = 1.0;
  for (const Grain& x : g) (x.species == 1 ? r1 : r2) = std::min(x.species == 1 ? r1 : r2, x.r);
  const double t1 = M_PI * r1 * std::sqrt(2500.0 / (5e7 / (2.0 * 1.3))) / (0.1631 * 0.3 + 0.8766);
  const double t2 = M_PI * r2 * std::sqrt(7800.0 / (2e7 / (2.0 * 1.25))) / (0.1631 * 0.25 + 0.8766);
  const double zeta = -std::log(0.4) / std::sqrt(M_PI * M_PI + std::log(0.4) * std::log(0.4));
  const double kappa = std::min(2.0 * 0.7 / 1.7, 2.0 * 0.75 / 1.75);
  const double zeta_yade = zeta * std::sqrt(7.0 / (2.0 * kappa));
  const double by_hand[2] = {0.2 * std::min(t1, t2) * (std::sqrt(1.0 + zeta * zeta) - zeta),
                             0.2 * std::min(t1, t2) * (std::sqrt(1.0 + zeta_yade * zeta_yade) - zeta_yade)};
  const char* engines[2] = {"liggghts", "yade"};
  for (int e = 0; e < 2; ++e) {
    SCOPED_TRACE(engines[e]);
    PourSettings settings;
    const Scene pour = pour_scene(s, settings);
    const PourLattice L = pour_lattice(g, pour, 1, 10, pour_drop_gap(g, settings));
    const RelaxPlan plan = make_pour_plan(L, pour, settings, engines[e]);
    EXPECT_NEAR(plan.timestep, by_hand[e], 1e-12 * by_hand[e]);
    Packing p;
    p.grains = L.grains;
    EXPECT_EQ(plan.timestep, make_plan(p, s, RelaxSettings{}, engines[e]).timestep);  // relax's, same grains
  }
  // A fraction asked for replaces the scene's; the step scales with it.
  PourSettings half;
  half.timestep_fraction = 0.1;
  const Scene pour = pour_scene(s, half);
  const RelaxPlan plan = make_pour_plan(pour_lattice(g, pour, 1, 10, 1e-3), pour, half, "liggghts");
  EXPECT_NEAR(plan.timestep, 0.5 * by_hand[0], 1e-12 * by_hand[0]);
}

TEST(PourPlan, ReleaseStepsFollowTheFreeFallAndEndOnACheck) {
  const Scene s = scene_in(box(0.012, 0.01), 3);
  PourSettings settings;
  settings.pace = 0.5;
  settings.max_batches = 4;
  const Grains g = some_grains(200);
  const Scene pour = pour_scene(s, settings);
  const PourLattice L = pour_lattice(g, pour, 2, settings.max_batches, pour_drop_gap(g, settings));
  const RelaxPlan plan = make_pour_plan(L, pour, settings, "liggghts");
  ASSERT_TRUE(plan.pour.enabled);
  ASSERT_EQ(plan.pour.batches.size(), L.batches.size());
  long total = 0;
  for (const PourRelease::Batch& b : plan.pour.batches) {
    double lo = 1.0, hi = 0.0;
    for (std::size_t i = b.first; i <= b.last; ++i) lo = std::min(lo, L.grains[i].x.z()), hi = std::max(hi, L.grains[i].x.z());
    const double fall = std::sqrt(2.0 * (plan.pour.drop_gap + hi - lo + 2.0 * plan.pour.r_max) / kGravity);
    EXPECT_GE(b.steps * plan.timestep, 0.5 * fall * (1.0 - 1e-12));
    total += b.steps;
  }
  const CheckSchedule sched = check_schedule(L.grains, pour, plan);
  EXPECT_EQ(total % sched.steps_per_check, 0);  // the settle's checks fall on the window's multiples
  EXPECT_NEAR(plan.pour.release_time, total * plan.timestep, 1e-12);
  EXPECT_GT(plan.arming_time, plan.pour.release_time);
  EXPECT_EQ(plan.stop_rule, "kinetic-energy");
  EXPECT_DOUBLE_EQ(plan.max_time, s.relax.max_time);
  double gap = 0.0;
  for (const Grain& x : g) gap += 2.0 * x.r;
  EXPECT_NEAR(plan.pour.drop_gap, gap / g.size(), 1e-15);  // one mean diameter
}

TEST(PourPlan, OpenFloorRegionHoldsTheLatticeAndTheFootprint) {
  Container open;
  Scene s = scene_in(open, 3, SourceSpec::Kind::Point);
  s.relax.open_margin = 2.0;
  const Grains g = some_grains(60);
  PourSettings settings;
  const PourLattice L = pour_lattice(g, s, 1, 10, 1e-3);
  const RelaxPlan alone = make_pour_plan(L, s, settings, "liggghts");
  ASSERT_TRUE(alone.has_region);
  for (const Grain& x : L.grains)
    for (int a = 0; a < 2; ++a) {
      EXPECT_LT(alone.region_lo[a], x.x[a] - x.r);
      EXPECT_GT(alone.region_hi[a], x.x[a] + x.r);
    }
  Grains wide = g;
  wide[0].x = Vec3(0.05, -0.02, 0.0);  // an earlier packing reaching farther
  const RelaxPlan with = make_pour_plan(L, s, settings, "liggghts", &wide);
  EXPECT_GE(with.region_hi[0], 0.05 + wide[0].r);
  EXPECT_LE(with.region_lo[1], -0.02 - wide[0].r);
}

TEST(PourPlan, RefusesWhatCannotBePoured) {
  Container open;
  const Scene rain_on_open = scene_in(open, 3, SourceSpec::Kind::Rain);
  try {
    pour_lattice(some_grains(10), rain_on_open, 1, 10, 1e-3);
    FAIL() << "rain on an open floor was accepted";
  } catch (const RelaxRefused& e) {
    EXPECT_NE(std::string(e.what()).find("pour_plan.toml: source.kind"), std::string::npos) << e.what();
  }
  Scene narrow = scene_in(box(0.0015, 0.01), 3);  // narrower than a grain
  EXPECT_THROW(pour_lattice(some_grains(10), narrow, 1, 10, 1e-3), RelaxRefused);
  const Scene s = scene_in(box(0.012, 0.01), 3);
  PourSettings bad;
  bad.pace = 0.0;
  EXPECT_THROW(make_pour_plan(pour_lattice(some_grains(10), s, 1, 10, 1e-3), s, bad, "liggghts"), RelaxRefused);
  EXPECT_THROW(pour_lattice(some_grains(10), s, 1, 0, 1e-3), RelaxRefused);
}

}  // namespace
}  // namespace btr
