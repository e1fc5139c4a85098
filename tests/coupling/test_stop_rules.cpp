// Stop rules (kinetic-energy, unbalanced-force, displacement), damping and the open floor's removal region,
// run for real in both engines on tiny packings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "coupling/dem/check_schedule.h"
#include "coupling/dem/relax.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/timestep.h"
#include "coupling/engines.h"
#include "coupling/liggghts/liggghts_compaction.h"
#include "coupling/liggghts/liggghts_script.h"
#include "coupling/yade/yade_script.h"
#include "relax_fixtures.h"
#include "relaxation_checks.h"

namespace {

using btr_test::have_engine;
std::string read(const std::string& path) { return btr_test::read_text(path); }

nlohmann::json relaxed_meta(const std::string& dir) { return nlohmann::json::parse(read(dir + "/relaxed.json")); }

// Two equal grains: A on the floor at x = 0, B resting on A alone, 25 degrees off its top. B rolls off A,
// drops to the floor and rolls away; A is pushed the other way. Without rolling friction nothing stops
// them rolling on a flat floor: the kinetic energy stays up, while the forces balance.
btr::Packing rolling_pair(const btr::Scene& scene) {
  const double r = 1e-3, a = 25.0 * M_PI / 180.0;
  btr::Packing p;
  btr::Grain g;
  g.r = r;
  g.species = 1;
  g.x = btr::Vec3(0, 0, r);
  p.grains.push_back(g);
  g.x = btr::Vec3(2 * r * std::sin(a), 0, r + 2 * r * std::cos(a));
  p.grains.push_back(g);
  p.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", 3}};
  return p;
}

btr::Scene rolling_scene(const std::string& name, btr::ContainerKind kind) {
  btr::Scene s = btr_test::make_scene(name, 3, btr_test::container(kind, 0.02, 0.02));
  s.relax.max_time = 0.3;
  return s;
}

class StopRules : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (!have_engine(GetParam())) FAIL() << "scripts/setup.sh installs it: " << GetParam() << " not installed";
  }
  std::string dir(const std::string& name) { return btr_test::fresh_dir("stop_" + GetParam() + "_" + name); }
};

// The rolling pair never satisfies the kinetic rule (runs to max-time) but its forces balance: the
// unbalanced-force rule must fire, before max_time, with the engine's ratio below the threshold.
TEST_P(StopRules, UnbalancedForceStopsGrainsThatRollForever) {
  btr::Scene scene = rolling_scene("unbalanced", btr::ContainerKind::Periodic);
  const btr::Packing pair = rolling_pair(scene);

  const btr::RelaxResult kinetic = btr::relax(pair, scene, GetParam(), {}, dir("kinetic"));
  EXPECT_EQ(kinetic.stop_reason, "max-time") << "the case must defeat the kinetic rule";
  ASSERT_FALSE(kinetic.kinetic_history.empty());
  EXPECT_GT(kinetic.kinetic_history.back().second, 10 * btr::kinetic_threshold(pair.grains, scene));

  scene.relax.stop_rule = "unbalanced-force";
  scene.relax.stop_unbalanced_force = 1e-2;
  const std::string d = dir("unbalanced");
  const btr::RelaxResult r = btr::relax(pair, scene, GetParam(), {}, d);
  EXPECT_EQ(r.stop_reason, "unbalanced-force");
  EXPECT_LT(r.simulated_time, 0.9 * scene.relax.max_time);
  ASSERT_TRUE(std::isfinite(r.stop_value));
  EXPECT_LT(r.stop_value, 1e-2);
  EXPECT_GE(r.stop_value, 0.0);
  // Both grains still roll: the rule stopped a moving bed, not a resting one.
  double speed = 0;
  for (const btr::Vec3& v : r.velocities) speed = std::max(speed, v.norm());
  EXPECT_GT(speed, 1e-3);
  const nlohmann::json m = relaxed_meta(d)["relax"];
  EXPECT_EQ(m["stop_rule"], "unbalanced-force");
  EXPECT_EQ(m["stop_reason"], "unbalanced-force");
  EXPECT_DOUBLE_EQ(m["stop_threshold"].get<double>(), 1e-2);
}

// The rolling pair keeps moving, so the displacement rule must not fire; a bed with rolling friction
// comes to rest, and there it must fire, its last window's largest displacement below the threshold.
TEST_P(StopRules, DisplacementFiresOnlyWhenGrainsStop) {
  btr::Scene rolling = rolling_scene("displacement_rolling", btr::ContainerKind::Periodic);
  rolling.relax.stop_rule = "displacement";
  rolling.relax.max_time = 0.15;
  const btr::RelaxResult moving = btr::relax(rolling_pair(rolling), rolling, GetParam(), {}, dir("disp_rolling"));
  EXPECT_EQ(moving.stop_reason, "max-time");

  btr::Scene scene = btr_test::settling_scene("displacement", 3, btr_test::container(btr::ContainerKind::Box, 0.01, 0.01));
  scene.relax.stop_rule = "displacement";
  scene.relax.stop_displacement = 1e-3;
  scene.relax.max_time = 1.0;
  const btr::Packing bed = btr_test::layered_packing(scene, 12, 5);
  const std::string d = dir("displacement");
  const btr::RelaxResult r = btr::relax(bed, scene, GetParam(), {}, d);
  EXPECT_EQ(r.stop_reason, "displacement");
  EXPECT_LT(r.simulated_time, scene.relax.max_time);
  const double threshold = 1e-3 * 2 * 0.8e-3;  // at most: the smallest radius is >= 0.8 mm
  ASSERT_TRUE(std::isfinite(r.stop_value));
  EXPECT_LT(r.stop_value, threshold);
  // At rest: no grain is moving faster than the threshold per check window allows (within 10x).
  const btr::RelaxPlan plan = btr::make_plan(bed, scene, {}, GetParam());
  const btr::CheckSchedule sched = btr::check_schedule(bed.grains, scene, plan);
  double speed = 0;
  for (const btr::Vec3& v : r.velocities) speed = std::max(speed, v.norm());
  EXPECT_LT(speed * sched.steps_per_check * plan.timestep, 10 * threshold);
  EXPECT_EQ(relaxed_meta(d)["relax"]["stop_reason"], "displacement");
}

// The same bed stops on the kinetic rule as before (the default).
TEST_P(StopRules, KineticEnergyIsTheDefault) {
  btr::Scene scene = btr_test::settling_scene("kinetic", 3, btr_test::container(btr::ContainerKind::Box, 0.01, 0.01));
  scene.relax.max_time = 1.0;
  const btr::Packing bed = btr_test::layered_packing(scene, 12, 5);
  const std::string d = dir("kinetic_default");
  const btr::RelaxResult r = btr::relax(bed, scene, GetParam(), {}, d);
  EXPECT_EQ(r.stop_reason, "kinetic-energy");
  ASSERT_TRUE(std::isfinite(r.stop_value));
  EXPECT_LT(r.stop_value, btr::kinetic_threshold(bed.grains, scene));
  const nlohmann::json m = relaxed_meta(d)["relax"];
  EXPECT_EQ(m["stop_rule"], "kinetic-energy");
  EXPECT_EQ(m["damping"], 0.0);
  EXPECT_TRUE(m["final_unbalanced_force"].is_number());
}

// Open floor: B rolls off A and away; once its centre leaves the region (the footprint + open_margin
// largest diameters) it is removed, counted and reported; the outputs hold the other grain only.
TEST_P(StopRules, OpenFloorRemovesAndCountsRunawayGrains) {
  btr::Scene scene = rolling_scene("open_floor", btr::ContainerKind::Open);
  scene.relax.open_margin = 1.0;
  scene.relax.open_heap_angle = 89.0;  // the two grains' heap (0.65 mm across) lies inside the footprint
  const btr::Packing pair = rolling_pair(scene);
  const std::string d = dir("open_floor");
  const btr::RelaxResult r = btr::relax(pair, scene, GetParam(), {}, d);
  ASSERT_FALSE(r.removed.empty());
  EXPECT_TRUE(std::find(r.removed.begin(), r.removed.end(), 2) != r.removed.end()) << "the rolling grain 2";
  EXPECT_EQ(r.relaxed.grains.size(), pair.grains.size() - r.removed.size());
  const nlohmann::json m = relaxed_meta(d)["relax"];
  EXPECT_EQ(m["removed"]["count"].get<std::size_t>(), r.removed.size());
  // Region: footprint [-r, 2r sin 25 + r] in x, [-r, r] in y, grown by one diameter (2 mm).
  const double r0 = 1e-3, x_hi = 2 * r0 * std::sin(25.0 * M_PI / 180.0) + r0;
  EXPECT_NEAR(m["removed"]["region"]["x"][0].get<double>(), -r0 - 2e-3, 1e-12);
  EXPECT_NEAR(m["removed"]["region"]["x"][1].get<double>(), x_hi + 2e-3, 1e-12);
  EXPECT_NEAR(m["removed"]["region"]["y"][1].get<double>(), r0 + 2e-3, 1e-12);
  for (const btr::Grain& g : r.relaxed.grains) {
    EXPECT_GE(g.x.x(), -r0 - 2e-3);
    EXPECT_LE(g.x.x(), x_hi + 2e-3);
  }
  // relaxed.csv: a header and one row per grain left.
  const std::string csv = read(d + "/relaxed.csv");
  EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')), 1 + r.relaxed.grains.size());
}

INSTANTIATE_TEST_SUITE_P(BothEngines, StopRules, ::testing::Values("liggghts", "yade"),
                         [](const auto& info) { return info.param; });

// The LIGGGHTS equivalent of YADE's damping: gamma = 2 (lambda / pi) sqrt(k m), by hand for one species
// of equal grains (Hertz stiffness at one grain's weight); the scripts carry it only when asked.
TEST(Damping, ViscousCoefficientByHandAndOffByDefault) {
  btr::Scene scene = btr_test::make_scene("damping", 3, btr_test::container(btr::ContainerKind::Box, 0.01, 0.01));
  btr::Packing p;
  for (int i = 0; i < 3; ++i) {
    btr::Grain g;
    g.r = 1e-3;
    g.x = btr::Vec3(-3e-3 + 3e-3 * i, 0, 1e-3);
    p.grains.push_back(g);
  }
  p.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", 3}};
  const double m = 2500.0 * 4.0 / 3.0 * M_PI * 1e-9;
  const double e_star = 5e7 / (2 * (1 - 0.3 * 0.3));  // like grains
  const double r_star = 0.5e-3;
  const double delta = std::pow(3 * m * 9.81 / (4 * e_star * std::sqrt(r_star)), 2.0 / 3.0);
  const double k = 2 * e_star * std::sqrt(r_star * delta);
  const double gamma = 2 * 0.3 / M_PI * std::sqrt(k * m);
  const std::vector<double> got = btr::liggghts_damping_gamma(p.grains, scene, 0.3);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_NEAR(got[0], gamma, 1e-3 * gamma);

  const std::string off = btr_test::fresh_dir("damping_off");
  btr::export_inputs(p, scene, "liggghts", {}, off);
  EXPECT_EQ(read(off + "/in.btr").find("viscous"), std::string::npos);
  btr::export_inputs(p, scene, "yade", {}, off);
  EXPECT_NE(read(off + "/relax_yade.py").find("DAMPING = 0  #"), std::string::npos);

  btr::RelaxSettings on;
  on.damping = 0.3;
  const std::string d = btr_test::fresh_dir("damping_on");
  btr::export_inputs(p, scene, "liggghts", on, d);
  EXPECT_NE(read(d + "/in.btr").find("fix btr_damping all viscous "), std::string::npos);
  btr::export_inputs(p, scene, "yade", on, d);
  EXPECT_NE(read(d + "/relax_yade.py").find("DAMPING = 0.29999999999999999"), std::string::npos);

  on.damping = 1.0;
  EXPECT_THROW(btr::export_inputs(p, scene, "liggghts", on, d), btr::RelaxRefused);
}

// The compaction's drag is F = -c m v with one rate c for every grain, so grains of every size fall through the
// pores alike: c = gamma / m of the bed's mean grain, by hand (Hertz stiffness at its weight, as above), for a
// bed of grains of two sizes; the script's three variables carry c times each grain's own mass.
TEST(Damping, CompactionDragIsOneRateForEveryGrainByHand) {
  btr::Scene scene = btr_test::make_scene("drag", 3, btr_test::container(btr::ContainerKind::Box, 0.01, 0.01));
  btr::Packing p;
  for (int i = 0; i < 3; ++i) {
    btr::Grain g;
    g.r = i == 2 ? 0.5e-3 : 1e-3;
    g.x = btr::Vec3(-3e-3 + 3e-3 * i, 0, g.r);
    p.grains.push_back(g);
  }
  p.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", 3}};
  const double r = 2.5e-3 / 3.0, m = 2500.0 * 4.0 / 3.0 * M_PI * r * r * r;
  const double e_star = 5e7 / (2 * (1 - 0.3 * 0.3)), r_star = 0.5 * r;
  const double delta = std::pow(3 * m * 9.81 / (4 * e_star * std::sqrt(r_star)), 2.0 / 3.0);
  const double rate = 2 * 0.15 / M_PI * std::sqrt(2 * e_star * std::sqrt(r_star * delta) * m) / m;
  EXPECT_NEAR(btr::liggghts_compaction_drag_rate(p.grains, scene, 0.15), rate, 1e-9 * rate);
  const std::string fix = btr::liggghts_compaction_drag_fix(p.grains, scene, 0.15);
  for (const char* k : {"x", "y", "z"}) {
    const std::string head = std::string("variable btr_drag_") + k + " atom -";
    const std::size_t at = fix.find(head);
    ASSERT_NE(at, std::string::npos) << fix;
    std::size_t used = 0;
    EXPECT_NEAR(std::stod(fix.substr(at + head.size()), &used), rate, 1e-12 * rate);
    EXPECT_EQ(fix.substr(at + head.size() + used, 8 + std::strlen(k)), std::string("*mass*v") + k + "\n");
  }
  EXPECT_NE(fix.find("fix btr_compaction_damping all addforce v_btr_drag_x v_btr_drag_y v_btr_drag_z\n"),
            std::string::npos);
  EXPECT_EQ(fix.find("viscous "), std::string::npos) << "not a coefficient per species";
}

TEST(StopRuleSettings, BadValuesAreRefusedBeforeTheEngine) {
  btr::Scene scene = btr_test::make_scene("refused", 3, btr_test::container(btr::ContainerKind::Box, 0.01, 0.01));
  const btr::Packing p = btr_test::layered_packing(scene, 4, 1);
  const std::string d = btr_test::fresh_dir("stop_refused");
  btr::Scene bad = scene;
  bad.relax.stop_rule = "energy";
  try {
    btr::export_inputs(p, bad, "liggghts", {}, d);
    FAIL() << "unknown stop rule accepted";
  } catch (const btr::RelaxRefused& e) {
    EXPECT_NE(std::string(e.what()).find("relax.stop_rule"), std::string::npos) << e.what();
  }
  bad = scene;
  bad.relax.stop_unbalanced_force = 0.0;
  EXPECT_THROW(btr::export_inputs(p, bad, "yade", {}, d), btr::RelaxRefused);
  bad = scene;
  bad.relax.stop_displacement = 1.5;
  EXPECT_THROW(btr::export_inputs(p, bad, "yade", {}, d), btr::RelaxRefused);
}

}  // namespace
