#pragma once
// Whether a settled bed stands where its calibration asked, judged against the target's own precision (its
// standard error): `btr settle` exits with 6 when it does not (app/cmd_settle.cpp; docs/guide/settle.md).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "btr/model/grain.h"

namespace btr {

// A bed counts as off its target when it is further from it than this many of the target's standard errors.
inline constexpr double kTargetPrecisionErrors = 2.0;

struct TargetVerdict {
  bool off_target = false;  // settle exits with 6
  // settle.json target_phi.looser_than_btr: the BTR bed was already denser than the target beyond its precision
  // (settle compacts, it cannot loosen); null otherwise
  nlohmann::json looser_than_btr;
  // settle.json target_phi.short_of_target: the compaction came to rest below the target; whether the settled bed
  // is still within the target's precision; null when the compaction reached the target or did not run
  nlohmann::json short_of_target;
};

// btr_phi: the BTR bed's bulk packing fraction before the relaxation; settled_phi: the settled bed's (NaN when it
// has no bulk window); compaction_ran / compaction_reached as in the relaxation's target_phi record; target and
// standard_error: the calibration's; calibration_coordination: the calibration pour's bulk coordination (recorded
// beside a looser material's verdict, to compare with the settled bed's).
TargetVerdict settle_target_verdict(double btr_phi, double settled_phi, bool compaction_ran, bool compaction_reached,
                                    double target, double standard_error,
                                    const nlohmann::json& calibration_coordination);

// settle.json's not_at_rest (the relax step's): the relaxation ran to its max time without its stop rule firing, so
// the packing was still moving when it was written (a heap's toe without rolling resistance rolls out for as long as
// it runs: docs/settle/heaps/README.md). Null when the rule fired. relax: the relaxed packing's "relax" record (its
// stop_reason, stop_rule, stop_threshold, simulated_time, final values); velocities: each grain's at the end, in the
// order of grains (grain k has id k + 1).
nlohmann::json relaxation_not_at_rest(const nlohmann::json& relax, const Grains& grains,
                                      const std::vector<Vec3>& velocities, bool heap);

}  // namespace btr
