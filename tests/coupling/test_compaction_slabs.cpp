// Deep beds compacted slab by slab (CompactionPlan::slabs, settle's beds deeper than kDeepBedDepth): the plan's
// slabs and windows, the LIGGGHTS script's twin types and slab loop, the YADE script's slabs, settle's choice of the
// slab count, and the slab compaction run for real in both engines on a small deep BTR bed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "btr/measures/metrics.h"
#include "btr/placement/run_scene.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/relax_target.h"
#include "coupling/dem/settle_plan.h"
#include "coupling/engines.h"
#include "rained_bed.h"
#include "relax_fixtures.h"
#include "relaxation_checks.h"

namespace {

// 800 grains: about 18 largest diameters deep, room for two slabs with a bulk window each.
using Bed = btr_test::RainedBed;
Bed deep_bed() { return btr_test::rained_bed("slabs", 800); }

btr::RelaxSettings slabs(double phi, int count) {
  btr::RelaxSettings s;
  s.target_phi = phi;
  s.friction_scales = std::vector<double>{0.0};
  s.compaction_damping = 0.075;
  s.target_margin = 2.0;
  s.compaction_slabs = count;
  return s;
}

// A real run of deep_bed in 2 slabs (either engine, settle's settle): each slab reached the target in turn and
// the compaction ended with the last; the settled bed lands near the target, keeps its grains (same radii, in
// order) and overlaps only as the contact law does; relaxed.json records both slabs.
void expect_two_slabs_landed(const btr::RelaxResult& r, const Bed& b, double goal, const std::string& dir) {
  ASSERT_EQ(r.compaction.slabs.size(), 2u);
  for (const auto& slab : r.compaction.slabs) {
    EXPECT_TRUE(slab.reached);
    EXPECT_GE(slab.packing_fraction, goal);
  }
  EXPECT_LT(r.compaction.slabs[0].time, r.compaction.slabs[1].time);
  EXPECT_EQ(r.compaction.time, r.compaction.slabs[1].time) << "the compaction ends with its last slab";
  EXPECT_TRUE(r.compaction.reached);
  EXPECT_EQ(r.stop_reason, "unbalanced-force");
  EXPECT_NEAR(btr::bulk_packing_fraction(r.relaxed.grains, b.scene, 2.0), goal, 0.015);
  ASSERT_EQ(r.relaxed.grains.size(), b.packing.grains.size());
  for (std::size_t i = 0; i < r.relaxed.grains.size(); ++i) EXPECT_EQ(r.relaxed.grains[i].r, b.packing.grains[i].r);
  EXPECT_LT(btr_test::largest_pair_overlap(r.relaxed.grains, b.scene.container, 3), 0.05);
  const nlohmann::json meta = nlohmann::json::parse(btr_test::read_text(dir + "/relaxed.json"));
  ASSERT_EQ(meta["target_phi"]["slabs"].size(), 2u);
  for (const auto& slab : meta["target_phi"]["slabs"]) EXPECT_EQ(slab["reached"], true);
}

double top_centre(const btr::Grains& g, std::size_t last) {
  double top = 0.0;
  for (std::size_t i = 0; i <= last; ++i) top = std::max(top, g[i].x.z());
  return top;
}

TEST(CompactionSlabs, PlanCutsTheBedInDropOrderWithWindowsFromTheFloorUp) {
  const Bed b = deep_bed();
  const double goal = btr::bulk_packing_fraction(b.packing.grains, b.scene, 2.0) + 0.03;
  const btr::CompactionPlan whole = btr::plan_compaction(b.packing, b.scene, slabs(goal, 1), 1e-5, 1e-9);
  ASSERT_TRUE(whole.enabled);
  EXPECT_TRUE(whole.slabs.empty()) << "one slab is the bed at once";
  const double cross_section = 0.012 * 0.012;
  for (int count : {2, 3}) {
    const btr::CompactionPlan c = btr::plan_compaction(b.packing, b.scene, slabs(goal, count), 1e-5, 1e-9);
    ASSERT_EQ(c.slabs.size(), static_cast<std::size_t>(count));
    EXPECT_DOUBLE_EQ(c.window_lo.z(), whole.window_lo.z());
    EXPECT_DOUBLE_EQ(c.slabs.front().window_lo_z, whole.window_lo.z()) << "the first slab's window: the floor margin";
    EXPECT_DOUBLE_EQ(c.slabs.back().window_hi_z, whole.window_hi.z()) << "the last slab's top: the bed's window";
    EXPECT_EQ(c.slabs.back().last, b.packing.grains.size() - 1);
    for (std::size_t k = 0; k < c.slabs.size(); ++k) {
      const btr::CompactionPlan::Slab& s = c.slabs[k];
      EXPECT_EQ(s.last + 1, b.packing.grains.size() * (k + 1) / c.slabs.size()) << "equal grain counts";
      EXPECT_LT(s.window_lo_z, s.window_hi_z);
      EXPECT_NEAR(s.window_measure, cross_section * (s.window_hi_z - s.window_lo_z), 1e-18);
      if (k > 0) {
        EXPECT_DOUBLE_EQ(s.window_lo_z, c.slabs[k - 1].window_hi_z) << "the windows tile the bed";
      }
      // Inside the bed of the slab's drops: at least a largest diameter below its highest centre.
      EXPECT_LT(s.window_hi_z, top_centre(b.packing.grains, s.last) - 2.4e-3);
    }
  }
  EXPECT_THROW(btr::plan_compaction(b.packing, b.scene, slabs(goal, 12), 1e-5, 1e-9), btr::RelaxRefused)
      << "slabs too thin for a window each";
  btr::RelaxSettings two_scales = slabs(goal, 2);
  two_scales.friction_scales = std::vector<double>{0.5, 0.0};
  EXPECT_THROW(btr::plan_compaction(b.packing, b.scene, two_scales, 1e-5, 1e-9), btr::RelaxRefused);
  btr::Packing few = b.packing;
  few.grains.resize(600);
  EXPECT_THROW(btr::compaction_slabs(few.grains, b.scene, 2.0, whole, 601), btr::RelaxRefused);
}

// Types 1 (the species), 2 (walls), 3 (its twin): only the twin's pairs frictionless during the compaction; the
// slab's grains take type 3 while it runs; the integrator follows the released grains; friction back for all.
TEST(CompactionSlabs, LiggghtsScriptGivesTheSlabItsTwinTypeAndHoldsTheGrainsAbove) {
  const Bed b = deep_bed();
  const double goal = btr::bulk_packing_fraction(b.packing.grains, b.scene, 2.0) + 0.03;
  const std::string dir = btr_test::fresh_dir("slabs_script");
  btr::export_inputs(b.packing, b.scene, "liggghts", slabs(goal, 2), dir);
  const std::string in = btr_test::read_text(dir + "/in.btr");
  const std::string data = btr_test::read_text(dir + "/btr.data");
  EXPECT_NE(data.find("800 atoms\n3 atom types"), std::string::npos);
  const std::size_t compaction =
      in.find("coefficientFriction peratomtypepair 3 0.5 0.5 0 0.5 0.5 0 0 0 0\n");
  const std::size_t restored = in.find("coefficientFriction peratomtypepair 3 0.5 0.5 0.5 0.5 0.5 0.5 0.5 0.5 0.5\n");
  ASSERT_NE(compaction, std::string::npos) << in;
  ASSERT_NE(restored, std::string::npos) << in;
  EXPECT_EQ(in.find("fix btr_integrate all nve/sphere"), std::string::npos) << "held grains are not integrated";
  const std::size_t first = in.find("group btr_released id <> 1 400\n");
  const std::size_t integrate = in.find("fix btr_integrate btr_released nve/sphere");
  const std::size_t twin1 = in.find("group btr_slab id <> 1 400\n");
  const std::size_t second = in.find("group btr_released id <> 1 800\n");
  const std::size_t twin2 = in.find("group btr_slab id <> 401 800\n");
  const std::size_t end = in.find("label btr_compaction_done");
  for (std::size_t at : {first, integrate, twin1, second, twin2, end}) ASSERT_NE(at, std::string::npos) << in;
  EXPECT_LT(first, integrate);
  EXPECT_LT(integrate, twin1);
  EXPECT_LT(twin1, second);
  EXPECT_LT(second, twin2);
  EXPECT_LT(twin2, end);
  EXPECT_LT(end, restored);
  // the held grains' pairs among themselves leave the pair list while they are held, and come back after
  const std::size_t held = in.find("group btr_held id > 400\n"), excluded = in.find("neigh_modify exclude group btr_held btr_held\n");
  const std::size_t back = in.find("neigh_modify exclude none\n");
  for (std::size_t at : {held, excluded, back}) ASSERT_NE(at, std::string::npos) << in;
  EXPECT_LT(first, held);
  EXPECT_LT(held, excluded);
  EXPECT_LT(excluded, second);
  EXPECT_LT(back, twin2);
  EXPECT_EQ(in.find("group btr_held id", held + 1), std::string::npos) << "the last slab holds nothing";
  EXPECT_NE(in.find("set group btr_slab_1 type 3", twin1), std::string::npos);
  EXPECT_NE(in.find("set group btr_slab_1 type 1", twin1), std::string::npos);
  EXPECT_NE(in.find("variable btr_phi equal c_btr_bulk_volume/v_btr_wmeasure"), std::string::npos);
  EXPECT_NE(in.find("BTR-COMPACTION-SLAB 2 2 reached"), std::string::npos);
}

TEST(CompactionSlabs, SettleCompactsBedsDeeperThanItsMeasuredDepthInSlabs) {
  EXPECT_EQ(btr::settle_compaction_slabs(14.1), 1);
  EXPECT_EQ(btr::settle_compaction_slabs(btr::kDeepBedDepth), 1);
  EXPECT_EQ(btr::settle_compaction_slabs(28.0), 2) << "ceil(28 / 14.1): each slab at most 14.1 deep";
  EXPECT_EQ(btr::settle_compaction_slabs(39.0), 3);
  EXPECT_EQ(btr::settle_compaction_slabs(145.0), 11);
  btr::Scene s = btr_test::make_scene("deep", 3, btr_test::container(btr::ContainerKind::Periodic, 0.03, 0.03));
  s.source.kind = btr::SourceSpec::Kind::Rain;
  const btr::SettleChoices deep = btr::settle_choices(s, 0.63, {}, 50.0, {});
  EXPECT_EQ(deep.settings.compaction_slabs, 4);
  EXPECT_EQ(deep.record["compaction_slabs"]["value"], 4);
  EXPECT_NE(deep.record["compaction_damping"]["warning"].get<std::string>().find("4 slabs"), std::string::npos);
  EXPECT_EQ(btr::settle_choices(s, 0.63, {}, 14.1, {}).settings.compaction_slabs, 1);
  const std::string liggghts_warning = deep.record["compaction_damping"]["warning"];
  EXPECT_EQ(liggghts_warning.find("YADE"), std::string::npos) << liggghts_warning;
  s.relax.engine = "yade";
  const btr::SettleChoices yade = btr::settle_choices(s, 0.63, {}, 50.0, {});
  EXPECT_EQ(yade.settings.compaction_slabs, 4) << "the same rule in YADE";
  const std::string yade_warning = yade.record["compaction_damping"]["warning"];
  EXPECT_NE(yade_warning.find("4 slabs"), std::string::npos) << yade_warning;
  EXPECT_NE(yade_warning.find("measured in YADE on two such beds"), std::string::npos) << yade_warning;
  EXPECT_EQ(yade_warning.find("LIGGGHTS"), std::string::npos) << "YADE's warning names YADE's measurements only";
  // YADE's slabs take the slabs' value at any depth (50 in 4 slabs, 26.9 in 2), not the depth rule's; a bed in one
  // compaction up to 21.15 takes the rule's value at its own depth (19.7: the deepest measured, 0.75).
  EXPECT_DOUBLE_EQ(yade.settings.compaction_damping.value(), 0.5);
  EXPECT_DOUBLE_EQ(btr::settle_choices(s, 0.63, {}, 26.9, {}).settings.compaction_damping.value(), 0.5);
  EXPECT_NEAR(btr::settle_choices(s, 0.63, {}, 19.7, {}).settings.compaction_damping.value(), 0.75, 1e-12)
      << "one slab up to 21.15: the bed's own depth";
  EXPECT_EQ(btr::settle_choices(s, 0.63, {}, 14.1, {}).settings.compaction_slabs, 1);
}

// The slabs of COMPACTION in the YADE script, as read back from its text: the plan's ids (1-based) and windows,
// to the last digit; the bed at once has none.
TEST(CompactionSlabs, YadeScriptCarriesThePlansSlabs) {
  const Bed b = deep_bed();
  const double goal = btr::bulk_packing_fraction(b.packing.grains, b.scene, 2.0) + 0.03;
  const btr::CompactionPlan plan = btr::plan_compaction(b.packing, b.scene, slabs(goal, 2), 1e-5, 1e-9);
  ASSERT_EQ(plan.slabs.size(), 2u);
  const std::string dir = btr_test::fresh_dir("slabs_yade");
  btr::export_inputs(b.packing, b.scene, "yade", slabs(goal, 2), dir);
  const std::string script = btr_test::read_text(dir + "/relax_yade.py");
  const std::size_t at = script.find("    slabs=[");
  ASSERT_NE(at, std::string::npos) << script.substr(script.find("COMPACTION = "), 800);
  EXPECT_LT(script.find("COMPACTION = dict("), at);
  EXPECT_NE(script.find("friction_scales=[0]"), std::string::npos);
  std::size_t pos = script.find('\n', at);
  for (std::size_t k = 0; k < plan.slabs.size(); ++k) {
    ASSERT_EQ(script.compare(pos, 10, "\n        ("), 0) << script.substr(at, 400);
    std::size_t first = 0, last = 0;
    double lo = 0, hi = 0, measure = 0;
    ASSERT_EQ(std::sscanf(script.c_str() + pos + 10, "%zu, %zu, %lf, %lf, %lf)", &first, &last, &lo, &hi, &measure), 5);
    EXPECT_EQ(first, k == 0 ? 1 : plan.slabs[k - 1].last + 2);
    EXPECT_EQ(last, plan.slabs[k].last + 1);
    EXPECT_EQ(lo, plan.slabs[k].window_lo_z);
    EXPECT_EQ(hi, plan.slabs[k].window_hi_z);
    EXPECT_EQ(measure, plan.slabs[k].window_measure);
    pos = script.find('\n', pos + 1);
  }
  EXPECT_EQ(script.compare(pos - 2, 2, "])"), 0) << "two slabs, no more: " << script.substr(at, 400);
  const std::string once_dir = btr_test::fresh_dir("slabs_yade_once");
  btr::export_inputs(b.packing, b.scene, "yade", slabs(goal, 1), once_dir);
  EXPECT_EQ(btr_test::read_text(once_dir + "/relax_yade.py").find("slabs=["), std::string::npos);
}

// Run for real in YADE, as in LIGGGHTS below: each slab reaches the target in turn (read back from the log's
// BTR-COMPACTION-SLAB lines), the settled bed lands near it, no pair overlaps beyond the law's small overlaps.
TEST(CompactionSlabs, YadeCompactsTheBedSlabBySlab) {
  if (!btr_test::have_engine("yade")) FAIL() << "scripts/setup.sh installs it: yade not installed";
  Bed b = deep_bed();
  const double goal = btr::bulk_packing_fraction(b.packing.grains, b.scene, 2.0) + 0.025;
  // settle's choices for YADE, which keep the run short: its damping, steps and stop rule
  btr::RelaxSettings s = slabs(goal, 2);
  s.compaction_damping = btr::kYadeSlabCompactionDamping;
  s.compaction_timestep_fraction = btr::kSettleCompactionTimestepFraction;
  s.damping = 0.5;
  b.scene.relax.stop_rule = "unbalanced-force";
  const std::string dir = btr_test::fresh_dir("slabs_yade_run");
  const btr::RelaxResult r = btr::relax(b.packing, b.scene, "yade", s, dir);
  expect_two_slabs_landed(r, b, goal, dir);
}

// Run for real: each slab reaches the target in turn, the settled bed lands near it (as the bed at once does,
// TargetPhiEngine), its grains keep their ids and no pair overlaps beyond the contact law's small overlaps. The
// settle after it is settle's (local damping 0.5 to the unbalanced-force rule): left undamped, this bed's last
// rattlers took 0.90 s of the 1 s allowed to fall below the kinetic-energy threshold.
TEST(CompactionSlabs, LiggghtsCompactsTheBedSlabBySlab) {
  if (!btr_test::have_engine("liggghts")) FAIL() << "scripts/setup.sh installs it: liggghts not installed";
  Bed b = deep_bed();
  b.scene.relax.stop_rule = "unbalanced-force";
  const double phi0 = btr::bulk_packing_fraction(b.packing.grains, b.scene, 2.0);
  const double goal = phi0 + 0.025;
  const std::string dir = btr_test::fresh_dir("slabs_run");
  btr::RelaxSettings s = slabs(goal, 2);
  s.damping = 0.5;
  const btr::RelaxResult r = btr::relax(b.packing, b.scene, "liggghts", s, dir);
  expect_two_slabs_landed(r, b, goal, dir);
  const nlohmann::json meta = nlohmann::json::parse(btr_test::read_text(dir + "/relaxed.json"));
  EXPECT_EQ(meta["target_phi"]["slabs"][0]["grains"], 400);
}

}  // namespace
