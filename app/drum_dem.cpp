#include "drum_dem.h"

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "btr/measures/metrics.h"
#include "btr/placement/run_scene.h"
#include "command_support.h"
#include "coupling/dem/drum_rotation.h"
#include "coupling/engines.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "drum_table.h"
#include "series_files.h"

namespace btr_app {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr double kRotationMaxOverlap = 0.2;  // of the smaller radius, at the rotation's start

int run_drum_dem(btr::Scene scene, const DrumDemOptions& o) {
  const std::string name = output_name(o.name, scene);
  const double R = scene.container.radius;
  btr::drum_speed(scene);  // a bad speed is refused before anything runs
  const json scene_json = btr::scene_to_json(scene);
  btr::RelaxSettings settings;
  settings.np = o.np;
  settings.wall_time_limit = o.time_limit;

  // 1. The BTR fill, as `btr drum` without --engine makes it.
  btr::Packing fill;
  fill.grains = btr::run_scene(scene, o.seed, scene.grains.count, {}).grains;
  fill.meta = snapshot_meta("drum", scene, scene_json, o.seed, fill.grains.size());

  // 2. A short relaxation in the still drum (btr relax's machinery).
  btr::Scene settle = scene;
  if (o.settle_max_time > 0) settle.relax.max_time = o.settle_max_time;
  btr::RelaxResult relaxed = btr::relax(fill, settle, o.engine, settings, (fs::path(o.out) / "relax").string());

  // 3. The rotation.
  btr::Packing start;
  start.grains = relaxed.relaxed.grains;
  start.meta = fill.meta;
  const std::unique_ptr<btr::EngineAdapter> adapter = btr::make_adapter(o.engine);
  // The relaxed packing's overlaps are the engine's own contacts under load (a short settle of soft grains can
  // leave several percent), not a BTR packing's error: the BTR bound (5 %) is widened to 20 %.
  btr::RelaxSettings rotation_settings = settings;
  rotation_settings.max_overlap = kRotationMaxOverlap;
  const btr::DrumRotationResult rot = btr::rotate_drum(start, scene, *adapter, o.engine, rotation_settings, o.revolutions,
                                                       (fs::path(o.out) / "rotation").string());

  // 4. The series and the table, as `btr drum` writes them (same columns, measures from btr::drum_measures).
  SeriesWriter series(o.out, name, "step");
  std::string table = drum_table_header();
  const double total_time = rot.snapshots.back().time;
  auto write = [&](std::int64_t step, double angle_deg, double time, const btr::Grains& grains) {
    // The engine's processor (and wall) time so far: its whole run's, in proportion to the simulated time.
    const double share = total_time > 0 ? time / total_time : 0.0;
    table += drum_table_row(step, angle_deg, share * rot.run.wall_seconds, share * rot.run.cpu_seconds,
                            btr::drum_measures(grains, scene.dimension, scene.container), R);
    json meta = snapshot_meta("drum", scene, scene_json, o.seed, grains.size());
    meta["step"] = step;
    meta["angle_deg"] = angle_deg;
    meta["engine"] = o.engine;
    meta["simulated_time"] = time;
    series.write(step, angle_deg, grains, meta);
    btr::write_text_file((fs::path(o.out) / (name + "_steps.csv")).string(), table);
  };
  write(0, 0.0, 0.0, start.grains);
  for (const btr::DrumSnapshot& s : rot.snapshots) write(s.step, s.angle_deg, s.time, s.grains);

  json record = btr::drum_rotation_record(rot, scene, o.engine, settings, o.revolutions);
  record["settle"] = {{"folder", "relax"},
                      {"max_time", settle.relax.max_time},
                      {"stop_reason", relaxed.stop_reason},
                      {"simulated_time", relaxed.simulated_time},
                      {"engine_cpu_seconds", relaxed.cpu_seconds},
                      {"engine_wall_seconds", relaxed.wall_seconds}};
  record["seed"] = o.seed;
  record["grains"] = start.grains.size();
  record["snapshots"] = series.count();
  btr::write_text_file((fs::path(o.out) / "drum_dem.json").string(), record.dump(1) + "\n");
  if (!o.quiet) {
    std::printf("%s: %zu grains, %s drum at %.4g rpm (Froude %.3g, %s): %.4g revolution(s) in %.4g s simulated, "
                "engine %.1f s processor time (%.1f s per revolution)\n",
                scene.name.c_str(), start.grains.size(), o.engine.c_str(), rot.speed.rpm, rot.speed.froude,
                rot.speed.source.c_str(), rot.snapshots.back().angle_deg / 360.0, total_time, rot.run.cpu_seconds,
                record["engine_cpu_seconds_per_revolution"].get<double>());
    std::printf("  wrote %s/%s.pvd (%d snapshots), %s_steps.csv and drum_dem.json\n", o.out.c_str(), name.c_str(),
                series.count(), name.c_str());
  }
  return 0;
}

}  // namespace btr_app
