// Whether a settled bed stands where its calibration asked (coupling/dem/settle_verdict.h), on hand-made numbers
// around the limits of 2 standard errors: a material that pours looser than BTR, a compaction that came to rest
// short of the target within and beyond the target's precision, a bed with no window to judge.
#include <gtest/gtest.h>

#include <cmath>

#include "coupling/dem/settle_verdict.h"

namespace btr {
namespace {

const nlohmann::json kCellZ = 4.95;

TEST(SettleVerdict, ACompactionThatReachedItsTargetIsOnTarget) {
  const TargetVerdict v = settle_target_verdict(0.590, 0.6251, true, true, 0.6245, 0.0021, kCellZ);
  EXPECT_FALSE(v.off_target);
  EXPECT_TRUE(v.looser_than_btr.is_null());
  EXPECT_TRUE(v.short_of_target.is_null());
}

TEST(SettleVerdict, ABtrBedDenserThanTheTargetBeyondTwoErrorsIsALooserMaterial) {
  // target 0.5799 +- 0.0021: the limit is 0.5841; BTR placed the grains at 0.5848
  const TargetVerdict v = settle_target_verdict(0.5848, 0.5860, false, true, 0.5799, 0.0021, kCellZ);
  EXPECT_TRUE(v.off_target);
  ASSERT_TRUE(v.looser_than_btr.is_object());
  EXPECT_NEAR(v.looser_than_btr["limit"].get<double>(), 0.5799 + 2 * 0.0021, 1e-15);
  EXPECT_EQ(v.looser_than_btr["calibration_bulk_coordination"], kCellZ);
  EXPECT_TRUE(v.short_of_target.is_null());
  // within two errors above the target it is as close as the target is known
  EXPECT_FALSE(settle_target_verdict(0.5838, 0.5850, false, true, 0.5799, 0.0021, kCellZ).off_target);
}

TEST(SettleVerdict, ACompactionShortOfTheTargetIsJudgedByTheSettledBedAgainstTheTargetsPrecision) {
  // the stiff low-friction cylinder: came to rest under 0.6495 +- 0.0019, settled at 0.6467 (0.0028 under; limit 0.0038)
  const TargetVerdict within = settle_target_verdict(0.6001, 0.6467, true, false, 0.6495, 0.0019, kCellZ);
  EXPECT_FALSE(within.off_target);
  ASSERT_TRUE(within.short_of_target.is_object());
  EXPECT_TRUE(within.short_of_target["within_precision"].get<bool>());
  EXPECT_NEAR(within.short_of_target["limit"].get<double>(), 0.6495 - 2 * 0.0019, 1e-15);
  EXPECT_TRUE(within.looser_than_btr.is_null());

  const TargetVerdict beyond = settle_target_verdict(0.6001, 0.6450, true, false, 0.6495, 0.0019, kCellZ);
  EXPECT_TRUE(beyond.off_target);
  EXPECT_FALSE(beyond.short_of_target["within_precision"].get<bool>());

  // a settled bed with no bulk window cannot be shown to be near the target
  const TargetVerdict unknown = settle_target_verdict(0.6001, std::nan(""), true, false, 0.6495, 0.0019, kCellZ);
  EXPECT_TRUE(unknown.off_target);
  EXPECT_TRUE(unknown.short_of_target["settled_bulk_packing_fraction"].is_null());
}

TEST(SettleVerdict, ARelaxationThatRanToItsMaxTimeIsReportedWithItsFastestGrain) {
  const Grains grains = {{Vec3(0.0, 0.0, 0.0005), 0.0005}, {Vec3(-0.02, 0.006, 0.0005), 0.0005},
                         {Vec3(0.0, 0.0, 0.0015), 0.0005}};
  // the second grain rolls at 5 mm/s (3-4-0), the others creep
  const std::vector<Vec3> v = {Vec3(1e-5, 0.0, 0.0), Vec3(0.003, -0.004, 0.0), Vec3(0.0, 0.0, -2e-4)};
  const nlohmann::json yade_heap = {{"stop_reason", "max-time"}, {"stop_rule", "unbalanced-force"},
                                    {"stop_threshold", 1e-3},      {"final_unbalanced_force", 0.0056},
                                    {"final_kinetic_energy", 4e-10}, {"simulated_time", 1.0046}};
  const nlohmann::json r = relaxation_not_at_rest(yade_heap, grains, v, true);
  ASSERT_TRUE(r.is_object());
  EXPECT_EQ(r["fastest_grain"]["id"], 2);
  EXPECT_NEAR(r["fastest_grain"]["speed"].get<double>(), 0.005, 1e-15);
  EXPECT_EQ(r["fastest_grain"]["x"][1].get<double>(), 0.006);
  EXPECT_EQ(r["final_value"].get<double>(), 0.0056) << "the rule's own measure, not the kinetic energy";
  EXPECT_EQ(r["threshold"].get<double>(), 1e-3);
  const std::string why = r["why"];
  EXPECT_NE(why.find("heap"), std::string::npos) << why;
  EXPECT_NE(why.find("0.0056"), std::string::npos) << why;

  // a rule that fired is no record; a bed's record does not speak of heaps; no velocities, no fastest grain
  nlohmann::json fired = yade_heap;
  fired["stop_reason"] = "unbalanced-force";
  EXPECT_TRUE(relaxation_not_at_rest(fired, grains, v, true).is_null());
  nlohmann::json by_energy = yade_heap;
  by_energy["stop_rule"] = "kinetic-energy";
  by_energy.erase("final_unbalanced_force");
  const nlohmann::json bed = relaxation_not_at_rest(by_energy, grains, {}, false);
  EXPECT_EQ(bed["why"].get<std::string>().find("heap"), std::string::npos);
  EXPECT_EQ(bed["final_value"].get<double>(), 4e-10) << "the kinetic-energy rule's measure";
  EXPECT_FALSE(bed.contains("fastest_grain"));
}

}  // namespace
}  // namespace btr
