// Target packing fraction (btr relax --target-phi): reduced-friction stages, then the settle at full
// friction, run for real in both engines on a small BTR bed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "btr/run_scene.h"
#include "coupling/relax_plan.h"
#include "coupling/relax_target.h"
#include "coupling/yade_script.h"
#include "relax_fixtures.h"
#include "relaxation_checks.h"

namespace {

using btr_test::have_engine;
std::string read(const std::string& path) { return btr_test::read_text(path); }

// 400 grains rained by BTR into a 12 mm periodic cell: deep enough (about 9 largest diameters) for a
// bulk window 3 largest diameters from the floor and the surface.
struct Bed {
  btr::Scene scene;
  btr::Packing packing;
};

Bed btr_bed() {
  Bed b;
  b.scene = btr_test::make_scene("target_phi", 3, btr_test::container(btr::ContainerKind::Periodic, 0.012, 0.012));
  b.scene.source.kind = btr::SourceSpec::Kind::Rain;
  b.scene.grains.components[0].material.young = 5e6;
  b.scene.relax.max_time = 1.0;
  b.packing.grains = btr::run_scene(b.scene, 3, 400, {}).grains;
  b.packing.meta = {{"scene", btr::scene_to_json(b.scene)}, {"dimension", 3}};
  return b;
}

TEST(TargetPhi, ScalesEveryFrictionAndRefusesBadSchedules) {
  btr::Scene s = btr_test::settling_scene("scaled", 3, btr_test::container(btr::ContainerKind::Periodic));
  const btr::Scene half = btr::with_friction_scaled(s, 0.25);
  EXPECT_DOUBLE_EQ(half.grains.components[0].material.friction, 0.125);
  EXPECT_DOUBLE_EQ(half.grains.components[0].material.rolling_friction, 0.025);
  EXPECT_DOUBLE_EQ(half.grains.components[0].material.young, s.grains.components[0].material.young);
  const std::vector<double> sched = btr::target_phi_schedule();
  EXPECT_EQ(sched.back(), 0.0);  // the last resort is frictionless
  const Bed b = btr_bed();
  const std::string dir = btr_test::fresh_dir("target_refused");
  EXPECT_THROW(btr::relax_to_target_phi(b.packing, b.scene, "liggghts", {}, 1.2, dir), btr::RelaxRefused);
  EXPECT_THROW(btr::relax_to_target_phi(b.packing, b.scene, "liggghts", {}, 0.6, dir, {0.5, 0.5}), btr::RelaxRefused);
  EXPECT_THROW(btr::relax_to_target_phi(b.packing, b.scene, "liggghts", {}, 0.6, dir, {1.0}), btr::RelaxRefused);
  EXPECT_THROW(btr::relax_to_target_phi(b.packing, b.scene, "liggghts", {}, 0.6, dir, {}), btr::RelaxRefused);
}

class TargetPhiEngine : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (!have_engine(GetParam())) GTEST_SKIP() << GetParam() << " not installed";
  }
};

// An unreachable target (0.9): the frictionless stage runs, the target is reported as not reached, the
// settle runs at full friction, and the engines' inputs carry the scaled and the restored friction.
// Removing friction lets the bed compact: the frictionless stage's bulk phi exceeds a plain relaxation's.
TEST_P(TargetPhiEngine, FrictionlessStageCompactsThenFrictionIsRestored) {
  const Bed b = btr_bed();
  const std::string dir = btr_test::fresh_dir("target_" + GetParam());
  const double phi_btr = btr::bulk_packing_fraction(b.packing.grains, b.scene);
  ASSERT_TRUE(std::isfinite(phi_btr));
  const btr::TargetPhiResult t = btr::relax_to_target_phi(b.packing, b.scene, GetParam(), {}, 0.9, dir, {0.0});
  EXPECT_FALSE(t.reached);
  ASSERT_EQ(t.stages.size(), 2u);
  EXPECT_EQ(t.stages[0].friction_scale, 0.0);
  EXPECT_EQ(t.stages[1].friction_scale, 1.0);
  EXPECT_GT(t.stages[0].packing_fraction, phi_btr + 0.005) << "a frictionless bed compacts";
  EXPECT_NEAR(t.stages[1].packing_fraction, btr::bulk_packing_fraction(t.settled.relaxed.grains, b.scene), 1e-12);
  EXPECT_NE(t.settled.stop_reason, "max-time");
  EXPECT_NEAR(t.wall_seconds, t.stages[0].wall_seconds + t.stages[1].wall_seconds, 1e-9);

  const btr::RelaxResult plain = btr::relax(b.packing, b.scene, GetParam(), {}, dir + "/plain");
  EXPECT_GT(t.stages[1].packing_fraction, btr::bulk_packing_fraction(plain.relaxed.grains, b.scene) + 0.005);

  // The engine inputs: friction 0 in the reduced stage, the scene's 0.5 in the settle.
  const std::string stage_in = GetParam() == "liggghts" ? dir + "/friction_1/in.btr" : dir + "/friction_1/relax_yade.py";
  const std::string settle_in = GetParam() == "liggghts" ? dir + "/in.btr" : dir + "/relax_yade.py";
  ASSERT_TRUE(std::filesystem::exists(stage_in)) << stage_in;
  const std::string a = read(stage_in), s = read(settle_in);
  if (GetParam() == "liggghts") {
    EXPECT_NE(a.find("coefficientFriction peratomtypepair 2 0 0 0 0"), std::string::npos) << a;
    EXPECT_NE(s.find("coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5"), std::string::npos) << s;
  }
  const nlohmann::json meta = nlohmann::json::parse(read(dir + "/relaxed.json"));
  EXPECT_EQ(meta["target_phi"]["reached"], false);
  EXPECT_EQ(meta["target_phi"]["stages"].size(), 2u);
}

// A target the BTR bed already has: no reduced-friction stage, only the settle.
TEST_P(TargetPhiEngine, TargetAlreadyMetOnlySettles) {
  const Bed b = btr_bed();
  const std::string dir = btr_test::fresh_dir("target_met_" + GetParam());
  const btr::TargetPhiResult t = btr::relax_to_target_phi(b.packing, b.scene, GetParam(), {}, 0.3, dir);
  EXPECT_TRUE(t.reached);
  ASSERT_EQ(t.stages.size(), 1u);
  EXPECT_EQ(t.stages[0].friction_scale, 1.0);
  EXPECT_FALSE(std::filesystem::exists(dir + "/friction_1"));
}

INSTANTIATE_TEST_SUITE_P(Engines, TargetPhiEngine, ::testing::Values("liggghts", "yade"));

}  // namespace
