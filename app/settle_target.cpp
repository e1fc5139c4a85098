#include "settle_target.h"

#include <cmath>
#include <filesystem>

#include "btr/measures/block_error.h"
#include "btr/model/number_text.h"
#include "btr/scene/scene_toml.h"

namespace btr_app {

using nlohmann::json;

CalibratedTarget calibrated_target(const btr::CalibrationPlan& cal, int dimension, const std::string& engine,
                                   const SettleRunOptions& o, const std::string& out, double target_error) {
  btr::MetricsOptions window;
  window.margin_diameters = btr::kCalibrationMargin;
  CalibratedTarget t;
  const bool asked = target_error > 0.0;
  json pours = json::array();
  std::string blocks;  // how the first pour's window was cut
  double sum = 0.0, squares = 0.0;
  // A previous settle into this folder may have poured more cells: its extra folders would sit beside this run's
  // as if they were part of it.
  for (int k = 1; k < kMaxCalibrationPours; ++k)
    std::filesystem::remove_all(std::filesystem::path(out) / ("calibration_" + std::to_string(k + 1)));
  for (int k = 0; k < kMaxCalibrationPours; ++k) {
    const StepClock clock;
    SettleRunOptions run = o;
    run.seed = o.seed + static_cast<std::uint64_t>(k);
    const std::string folder = k == 0 ? "calibration" : "calibration_" + std::to_string(k + 1);
    const CalibrationPour pour =
        calibration_pour(cal.scene, engine, run, (std::filesystem::path(out) / folder).string(), window);
    const btr::PackingMeasures& m = pour.measures;
    if (!m.bulk.valid)
      throw btr::SceneError("--calibration-grains: the calibration pour's bulk window is empty (" + m.bulk.note +
                            "): its bed of " + std::to_string(cal.grains) + " grains is too shallow; give more");
    const btr::BlockError e =
        btr::bulk_phi_block_error(pour.result.poured.grains, dimension, cal.scene.container, m.bulk);
    sum += m.bulk.packing_fraction;
    squares += e.standard_error * e.standard_error;
    const double n = k + 1.0;
    t.phi = sum / n;
    t.standard_error = std::sqrt(squares) / n;
    pours.push_back({{"seed", run.seed},
                     {"bulk_packing_fraction", m.bulk.packing_fraction},
                     {"standard_error", e.standard_error},
                     {"bulk_grains", m.bulk.grains_in_window},
                     {"bulk_coordination", m.bulk.mean_coordination},
                     {"output", folder + "/poured.csv"}});
    t.steps.push_back(clock.finish("calibration", pour.engine_cpu_seconds,
                                   {{"what", "periodic pour of the scene's grains and material"},
                                    {"grains", cal.grains},
                                    {"seed", run.seed},
                                    {"bulk_packing_fraction", m.bulk.packing_fraction},
                                    {"simulated_seconds", pour.result.run.simulated_time},
                                    {"stop_reason", pour.result.run.stop_reason}}));
    if (k == 0) blocks = e.note;
    if (asked)
      say("calibration pour " + std::to_string(k + 1) + ": " + btr::g6(m.bulk.packing_fraction) + "; mean " +
          btr::g6(t.phi) + " +- " + btr::g6(t.standard_error) + " (asked: " + btr::g6(target_error) + ")");
    if (!asked || t.standard_error <= target_error) break;
  }
  t.error_met = !asked || t.standard_error <= target_error;
  t.from = {{"source", "calibration pour"},
            {"grains", cal.grains},
            {"cell", {{"kind", "periodic"}, {"width", cal.width}, {"dimension", dimension}, {"chosen", cal.record}}},
            {"seed", o.seed},
            {"engine", engine},
            {"bulk_window_margin_largest_diameters", btr::kCalibrationMargin},
            {"bulk_grains", pours[0]["bulk_grains"]},
            {"bulk_coordination", pours[0]["bulk_coordination"]},
            {"standard_error",
             {{"value", t.standard_error},
              {"from", blocks + ": the blocks' standard deviation / sqrt(blocks)" +
                           std::string(pours.size() > 1 ? ", combined over the pours: sqrt(sum e^2) / pours" : "")}}},
            {"output", "calibration/poured.csv"}};
  if (asked)
    t.from["target_error"] = {{"asked", target_error},
                              {"met", t.error_met},
                              {"pours", pours.size()},
                              {"most_pours", kMaxCalibrationPours},
                              {"each", pours}};
  return t;
}

}  // namespace btr_app
