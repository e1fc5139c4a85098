// The engines' neighbour skin (coupling/dem/neighbour_skin.h): 0.5 r_min, except a pour at a coarse step
// (a softened calibration), whose skin follows the step up to a cap; both engines write the same skin.
#include <gtest/gtest.h>

#include <cmath>

#include "coupling/dem/neighbour_skin.h"
#include "coupling/dem/pour.h"
#include "coupling/dem/pour_plan.h"
#include "coupling/engines.h"
#include "relax_fixtures.h"
#include "relaxation_checks.h"

namespace btr {
namespace {

RelaxPlan pour_plan_with(double timestep, double drop_gap, double r_max) {
  RelaxPlan plan;
  plan.timestep = timestep;
  plan.pour.enabled = true;
  plan.pour.drop_gap = drop_gap;
  plan.pour.r_max = r_max;
  return plan;
}

// The number after `key` at the start of a line of text.
double number_after(const std::string& text, const std::string& key) {
  const std::size_t at = text.find("\n" + key);
  if (at == std::string::npos) return NAN;
  return std::stod(text.substr(at + 1 + key.size()));
}

}  // namespace

TEST(NeighbourSkin, ARelaxationKeepsHalfTheSmallestRadiusWhateverItsStep) {
  RelaxPlan plan;
  for (double dt : {1e-7, 1e-5, 1e-3}) {
    plan.timestep = dt;
    EXPECT_EQ(neighbour_skin(plan, 0.4e-3), 0.2e-3) << dt;
  }
}

// drop gap 1 mm, r_max 1 mm: a 3 mm fall, v = sqrt(2 * 9.81 * 0.003) = 0.242611 m/s; r_min 0.5 mm.
TEST(NeighbourSkin, APoursSkinFollowsItsStepBetweenHalfAndOneAndAHalfSmallestRadii) {
  const double v = std::sqrt(2.0 * 9.81 * 0.003);
  EXPECT_NEAR(pour_impact_speed(pour_plan_with(1e-5, 1e-3, 1e-3).pour), 0.2426108, 1e-7);
  // stiff: 40 v dt = 9.7e-5 m, under 0.25 mm
  EXPECT_EQ(neighbour_skin(pour_plan_with(1e-5, 1e-3, 1e-3), 0.5e-3), 0.25e-3);
  // between: 40 v dt = 4.85e-4 m, so a grain at the impact speed crosses half the skin in 20 steps
  const double skin = neighbour_skin(pour_plan_with(5e-5, 1e-3, 1e-3), 0.5e-3);
  EXPECT_NEAR(skin, 40.0 * v * 5e-5, 1e-15);
  EXPECT_NEAR(0.5 * skin / (v * 5e-5), 20.0, 1e-9);
  // coarse: capped at 1.5 r_min
  EXPECT_EQ(neighbour_skin(pour_plan_with(2e-4, 1e-3, 1e-3), 0.5e-3), 0.75e-3);
}

// A pour of a box scene, as written for LIGGGHTS and YADE: the grains of Young's modulus 5e7 Pa keep
// 0.5 r_min in both; the same grains 250x softer (a step 16x coarser; a heap calibration pour's is about 7x) get
// 40 v dt, v the speed of a fall from the batch's release height, dt each engine's own step.
TEST(NeighbourSkin, BothEnginesWriteThePoursSkin) {
  Container c;
  c.kind = ContainerKind::Box, c.size_x = 0.012, c.size_y = 0.012;
  Scene scene = btr_test::make_scene("skin", 3, c);
  const Grains grains = btr_test::layered_packing(scene, 60, 7).grains;
  double r_min = 1.0;
  for (const Grain& g : grains) r_min = std::min(r_min, g.r);
  double skins[2][2];  // [stiff, soft][liggghts, yade]
  for (int soft = 0; soft < 2; ++soft) {
    Scene s = scene;
    if (soft) s.grains.components[0].material.young *= 0.004;
    PourSettings settings;
    const Scene pour = pour_scene(s, settings);
    const PourLattice lattice = pour_lattice(grains, pour, 1, settings.max_batches, pour_drop_gap(grains, settings));
    for (int e = 0; e < 2; ++e) {
      const std::string engine = e == 0 ? "liggghts" : "yade";
      const RelaxPlan plan = make_pour_plan(lattice, pour, settings, engine);
      const std::string dir = btr_test::fresh_dir("skin_" + engine + std::to_string(soft));
      write_pour_inputs(lattice, pour, *make_adapter(engine), settings, plan, dir);
      skins[soft][e] = e == 0 ? number_after(btr_test::read_text(dir + "/in.btr"), "neighbor")
                              : number_after(btr_test::read_text(dir + "/relax_yade.py"), "VERLET_DIST = ");
      const double fall = plan.pour.drop_gap + 2.0 * plan.pour.r_max;
      const double by_hand = std::min(1.5 * r_min, std::max(0.5 * r_min, 40.0 * std::sqrt(2.0 * 9.81 * fall) * plan.timestep));
      EXPECT_NEAR(skins[soft][e], by_hand, 1e-15) << engine << soft;
    }
  }
  for (int e = 0; e < 2; ++e) {
    EXPECT_EQ(skins[0][e], 0.5 * r_min) << e;
    EXPECT_GT(skins[1][e], 0.6 * r_min) << e;
    EXPECT_LE(skins[1][e], 1.5 * r_min * (1 + 1e-15)) << e;
  }
}

}  // namespace btr
