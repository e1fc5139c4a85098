#include "settle_steps.h"

#include <algorithm>
#include <filesystem>

#include "coupling/dem/pour_plan.h"
#include "coupling/engines.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/packing_io.h"
#include "measures_json.h"

namespace btr_app {

CalibrationPour calibration_pour(const btr::Scene& scene, const std::string& engine, const SettleRunOptions& o,
                                 const std::string& dir, const btr::MetricsOptions& window) {
  const btr::Grains grains = btr::scene_drop_grains(scene, o.seed);
  btr::PourSettings settings;
  settings.seed = o.seed;
  settings.np = o.np;
  settings.wall_time_limit = o.time_limit;
  // At rest, not cut short by a max time chosen for the user's own relaxation.
  settings.settle_max_time = std::max(scene.relax.max_time, kCalibrationSettleTime);
  CalibrationPour out;
  out.result = btr::pour(grains, scene, engine, settings, dir,
                         scene_packing_meta(scene, grains, o.seed, "settle calibration pour"));
  out.measures = measure_in_scene(out.result.poured.grains, scene, window);
  out.result.poured.meta["measures"] = measures_to_json(out.measures);
  btr::write_packing_meta(dir, "poured", out.result.poured.meta);
  const nlohmann::json& record = out.result.poured.meta["pour"];
  btr::write_text_file((std::filesystem::path(dir) / "pour.json").string(), record.dump(1) + "\n");
  out.engine_cpu_seconds = record.value("engine_cpu_seconds", out.result.run.cpu_seconds);
  return out;
}

}  // namespace btr_app
