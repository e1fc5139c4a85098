// The DEM tapping plan (coupling/dem/tapping.h) without an engine: amplitude from Gamma and frequency, the time
// step a whole fraction of the period and never above the stable one, the rest's window, the blow-up bound's
// extra energy, the intruder's component for the engines, and the refusals that name the scene field.
#include <gtest/gtest.h>

#include <cmath>

#include "coupling/dem/relax_plan.h"
#include "coupling/dem/tapping.h"
#include "relax_fixtures.h"

namespace btr {
namespace {

Scene tapped_scene(ContainerKind kind) {
  Scene s = btr_test::make_scene("tapped", 3, btr_test::container(kind, 0.01, 0.01));
  s.relax.max_time = 0.2;
  s.shaking = ShakingSpec{};
  s.shaking->cycles = 3;
  s.shaking->lift = 1e-3;
  s.shaking->snapshot_every = 1;
  return s;
}

TEST(TappingPlan, AmplitudeIsGammaGOverOmegaSquared) {
  const double omega = 2.0 * M_PI * 30.0;
  EXPECT_NEAR(tap_amplitude(3.0, 30.0), 3.0 * 9.81 / (omega * omega), 1e-15);
  EXPECT_NEAR(tap_amplitude(3.0, 30.0) * 1e3, 0.828, 1e-3);  // the guide's 0.83 mm
  EXPECT_NEAR(tap_amplitude(6.0, 60.0), tap_amplitude(3.0, 30.0) / 2.0, 1e-15);
}

TEST(TappingPlan, WholeStepsPerPeriodNoFasterThanTheRuleAndTheScenesValues) {
  Scene s = tapped_scene(ContainerKind::Periodic);
  s.shaking->gamma = 2.0;
  s.shaking->frequency = 45.0;
  const Packing p = btr_test::layered_packing(s, 60, 7);
  TapSettings ts;
  ts.taps = 4;
  const RelaxPlan plan = make_tap_plan(p, s, ts, "liggghts");
  const TapSchedule& t = plan.tap;
  ASSERT_TRUE(t.enabled);
  EXPECT_EQ(t.taps, 4);
  EXPECT_EQ(t.gamma, 2.0);
  EXPECT_EQ(t.frequency, 45.0);
  EXPECT_DOUBLE_EQ(t.amplitude, tap_amplitude(2.0, 45.0));
  EXPECT_NEAR(plan.timestep * static_cast<double>(t.steps_per_tap), 1.0 / 45.0, 1e-15);
  EXPECT_LE(plan.timestep, plan.stable_timestep);
  EXPECT_GT(plan.timestep, plan.stable_timestep * (1.0 - 1.0 / static_cast<double>(t.steps_per_tap)) * 0.999);
  EXPECT_NE(plan.timestep_rule.find("lowered to the tap period"), std::string::npos) << plan.timestep_rule;
  EXPECT_GE(t.steps_per_check, 1000);
  EXPECT_GE(t.max_rest_checks, 1);
  // the longest rest is the default rest time, to within one window
  const double window = t.steps_per_check * plan.timestep;
  EXPECT_NEAR((t.max_rest_checks + 1) * window, kDefaultTapRestTime, window);
  TapSettings short_rest = ts;
  short_rest.max_rest_time = 0.05;
  EXPECT_LT(make_tap_plan(p, s, short_rest, "liggghts").tap.max_rest_checks, t.max_rest_checks);
  EXPECT_GT(t.energy_input, 0.0);
  EXPECT_EQ(plan.damping, 0.0);
  EXPECT_FALSE(plan.compaction.enabled);
}

TEST(TappingPlan, DefaultsAreGamma3At30Hz) {
  const Scene s = tapped_scene(ContainerKind::Box);
  const Packing p = btr_test::layered_packing(s, 30, 3);
  const RelaxPlan plan = make_tap_plan(p, s, TapSettings{}, "liggghts");
  EXPECT_EQ(plan.tap.gamma, kDefaultTapGamma);
  EXPECT_EQ(plan.tap.frequency, kDefaultTapFrequency);
  EXPECT_EQ(kDefaultTapGamma, 3.0);
  EXPECT_EQ(kDefaultTapFrequency, 30.0);
}

TEST(TappingPlan, RefusalsNameTheField) {
  Scene s = tapped_scene(ContainerKind::Cylinder);
  const Packing p = btr_test::layered_packing(s, 20, 5);
  try {
    make_tap_plan(p, s, TapSettings{}, "liggghts");
    FAIL() << "a cylinder was tapped";
  } catch (const RelaxRefused& e) {
    EXPECT_NE(std::string(e.what()).find("tapped.toml: container.kind"), std::string::npos) << e.what();
  }
  s = tapped_scene(ContainerKind::Periodic);
  TapSettings none;
  none.taps = 0;
  EXPECT_THROW(make_tap_plan(p, s, none, "liggghts"), RelaxRefused);
  TapSettings no_rest;
  no_rest.max_rest_time = 0.0;
  EXPECT_THROW(make_tap_plan(p, s, no_rest, "liggghts"), RelaxRefused);
  s.shaking.reset();
  try {
    make_tap_plan(p, s, TapSettings{}, "liggghts");
    FAIL() << "tapped without [shaking]";
  } catch (const RelaxRefused& e) {
    EXPECT_NE(std::string(e.what()).find("[shaking]"), std::string::npos) << e.what();
  }
}

TEST(TappingPlan, TheIntruderBecomesAComponentOfTheBedsMaterial) {
  Scene s = tapped_scene(ContainerKind::Periodic);
  EXPECT_EQ(engine_scene(s).grains.components.size(), 1u);  // no intruder: unchanged
  s.intruder = IntruderSpec{};
  s.intruder->diameter_ratio = 3.0;
  s.intruder->species = 2;
  const Scene e = engine_scene(s);
  ASSERT_EQ(e.grains.components.size(), 2u);
  EXPECT_EQ(e.grains.components[1].species, 2);
  EXPECT_EQ(e.grains.components[1].density, s.grains.components[0].density);
  EXPECT_EQ(e.grains.components[1].material.young, s.grains.components[0].material.young);
  EXPECT_EQ(e.grains.components[1].fraction, 0.0);
  EXPECT_EQ(engine_scene(e).grains.components.size(), 2u);  // already there: not added twice
}

}  // namespace
}  // namespace btr
