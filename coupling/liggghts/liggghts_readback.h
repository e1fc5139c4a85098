#pragma once
// Reading a LIGGGHTS relaxation back: the log (thermo rows, BTR-STOP / BTR-FAILURE markers, ERROR
// lines) and the two final dumps written by the script of liggghts_script.h.
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "coupling/dem/engine_adapter.h"

namespace btr {

struct LiggghtsLog {
  std::vector<std::pair<double, double>> kinetic;  // (time, kinetic energy), one row per thermo output
  std::string stop_reason;                         // the rule that fired, "max-time", or "" (none printed)
  double stop_time = 0.0;
  double stop_value = std::numeric_limits<double>::quiet_NaN();  // "value = V" of the BTR-STOP line
  double final_unbalanced_force = std::numeric_limits<double>::quiet_NaN();  // BTR-FINAL line
  std::string failure;                             // first ERROR / BTR-FAILURE line, or a non-finite value
  FailureKind failure_kind = FailureKind::EngineError;  // of that line: blow_up, non_finite, lost_grains, ...
  nlohmann::json failure_values = nlohmann::json::object();  // its numbers, and the line as "log_line"
  RelaxResult::Compaction compaction;              // the BTR-COMPACTION-END line, if any
};

// Throws EngineFailure if the log cannot be read.
LiggghtsLog parse_liggghts_log(const std::string& path);

// Reads dir/log.liggghts, dir/btr_final.dump (positions, velocities) and dir/btr_contacts.dump; throws
// EngineFailure (with what is wrong) for a failed run, a missing or incomplete dump, missing ids or
// non-finite values. With plan.has_region (open floor), grains missing from the final dump were lost
// through the fixed lateral bounds: they are listed in RelaxResult::removed (and keep their input
// position in relaxed.grains), not a failure.
RelaxResult read_liggghts_result(const std::string& dir, const Packing& original, const Scene& scene,
                                 const RelaxPlan& plan);

// Tapping (plan.tap): the grains of dir/btr_tap_<k>.dump and the log's BTR-TAP-MOVED / BTR-TAP-RESTED lines of
// each tap k = 1..plan.tap.taps (liggghts_tapping.h). Throws EngineFailure for a missing tap, a missing or bad
// dump, or ids that are not the input's.
std::vector<TapSnapshot> read_liggghts_taps(const std::string& dir, const Packing& original, const RelaxPlan& plan);

// A rotating drum's snapshot k (1-based): dir/btr_rot_K.dump (liggghts_snapshot_file), original's grains at its
// positions. Throws EngineFailure for a missing or truncated dump, missing or repeated ids, non-finite values.
Grains read_liggghts_snapshot(const std::string& dir, std::size_t k, const Packing& original);

}  // namespace btr
