#pragma once
// Pieces `btr settle` runs for beds and heaps alike (cmd_settle.cpp, settle_heap.cpp): the step clock of
// settle.json, the terminal line, and the calibration pour.
#include <chrono>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "btr/measures/metrics.h"
#include "btr/scene/scene.h"
#include "coupling/dem/pour.h"
#include "packing_meta.h"

namespace btr_app {

// One step's record in settle.json: processor time of btr itself (own_cpu_seconds' growth) plus that of the
// engine it ran, and wall time.
class StepClock {
 public:
  StepClock() : cpu0_(own_cpu_seconds()), wall0_(std::chrono::steady_clock::now()) {}
  nlohmann::json finish(const std::string& step, double engine_cpu_seconds, nlohmann::json details) const {
    const double own = own_cpu_seconds() - cpu0_;
    details["step"] = step;
    details["btr_cpu_seconds"] = own;
    details["engine_cpu_seconds"] = engine_cpu_seconds;
    details["cpu_seconds"] = own + engine_cpu_seconds;
    details["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
    return details;
  }

 private:
  double cpu0_;
  std::chrono::steady_clock::time_point wall0_;
};

inline void say(const std::string& line) { std::cout << "btr settle: " << line << std::endl; }

// What every engine run of one settle takes from its command line.
struct SettleRunOptions {
  std::uint64_t seed = 0;
  int np = 1;
  double time_limit = 7200.0;
};

// Simulated seconds a calibration pour may settle after its last batch, at least (a bed of ten largest diameters
// comes to rest in a few tenths of a second).
constexpr double kCalibrationSettleTime = 1.0;

// `btr pour` of the calibration scene's drops into `dir` (poured.csv/json/vtp, pour.json), measured in
// `measure_scene` with `window`; the measures are stored in poured.json.
struct CalibrationPour {
  btr::PourResult result;
  btr::PackingMeasures measures;
  double engine_cpu_seconds = 0.0;
};
CalibrationPour calibration_pour(const btr::Scene& scene, const std::string& engine, const SettleRunOptions& o,
                                 const std::string& dir, const btr::MetricsOptions& window);

}  // namespace btr_app
