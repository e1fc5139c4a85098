#pragma once
// Reading a LIGGGHTS relaxation back: the log (thermo rows, BTR-STOP / BTR-FAILURE markers, ERROR
// lines) and the two final dumps written by the script of liggghts_script.h.
#include <string>
#include <utility>
#include <vector>

#include "coupling/engine_adapter.h"

namespace btr {

struct LiggghtsLog {
  std::vector<std::pair<double, double>> kinetic;  // (time, kinetic energy), one row per thermo output
  std::string stop_reason;                         // "kinetic-energy" | "max-time" | "" (none printed)
  double stop_time = 0.0;
  std::string failure;                             // first ERROR / BTR-FAILURE line, or a non-finite value
};

// Throws EngineFailure if the log cannot be read.
LiggghtsLog parse_liggghts_log(const std::string& path);

// Reads dir/log.liggghts, dir/btr_final.dump (positions, velocities) and dir/btr_contacts.dump; throws
// EngineFailure (with what is wrong) for a failed run, a missing or incomplete dump, missing ids or
// non-finite values.
RelaxResult read_liggghts_result(const std::string& dir, const Packing& original, const Scene& scene);

}  // namespace btr
