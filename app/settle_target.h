#pragma once
// A bed's target for `btr settle` (cmd_settle.cpp): the calibration pour's bulk packing fraction with its standard
// error (btr/measures/block_error.h); with a target error asked for, more pours of the same cell at the next seeds
// until the standard error of their mean is at most that.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "coupling/dem/settle_plan.h"
#include "settle_steps.h"

namespace btr_app {

// Most calibration pours one settle runs for --target-error (the error falls as 1/sqrt(pours)).
constexpr int kMaxCalibrationPours = 16;

struct CalibratedTarget {
  double phi = 0.0;             // the pours' mean bulk packing fraction
  double standard_error = 0.0;  // of that mean: sqrt(sum of the pours' block errors squared) / pours
  bool error_met = true;        // false when --target-error was not reached within kMaxCalibrationPours
  nlohmann::json from;          // settle.json chosen.target_phi.from
  std::vector<nlohmann::json> steps;  // one "calibration" step per pour
};

// Pour k (k = 0, 1, ...) uses seed o.seed + k and the folder `out`/calibration (k = 0) or calibration_<k+1>.
// target_error <= 0: one pour. Throws SceneError when a pour's bulk window is empty (too few grains).
CalibratedTarget calibrated_target(const btr::CalibrationPlan& cal, int dimension, const std::string& engine,
                                   const SettleRunOptions& o, const std::string& out, double target_error);

}  // namespace btr_app
