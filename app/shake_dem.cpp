// `btr shake --engine liggghts|yade` (shake_dem.h): BTR packing -> relaxation at rest (btr relax's machinery) ->
// tapping (coupling/dem/tapping.h) -> the series of snapshots and NAME_cycles.csv with the columns of dynamic
// BTR's run (shake_cycles.h), and shake_dem.json.
#include "shake_dem.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "command_support.h"
#include "commands.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/tapping.h"
#include "coupling/engines.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "packing_meta.h"
#include "series_files.h"
#include "shake_cycles.h"

namespace btr_app {

using nlohmann::json;

int run_shake_dem(const ShakeOptions& o, const CLI::App& cmd, const btr::Scene& btr_scene, std::uint64_t seed) {
  namespace fs = std::filesystem;
  if (o.check)
    throw btr::SceneError("--check: the self-check judges BTR packings (grains exactly touching); a DEM snapshot's "
                          "grains overlap at their contacts, so --check is refused with --engine");
  const std::string name = output_name(o.name, btr_scene);
  const btr::Scene scene = btr::engine_scene(btr_scene);  // the intruder gets the bed's material
  btr::TapSettings ts;
  ts.taps = cmd.count("--taps") ? static_cast<long>(o.taps) : static_cast<long>(scene.shaking->cycles);
  ts.np = o.np;
  ts.wall_time_limit = o.time_limit;
  ts.max_rest_time = o.rest_time;
  const std::int64_t every = scene.shaking->snapshot_every;

  // The BTR packing of dynamic BTR's run: same scene, grains, intruder and seed.
  btr::Packing start;
  start.grains = btr::run_scene(btr_scene, seed, btr_scene.grains.count, {}).grains;
  const json scene_json = btr::scene_to_json(btr_scene);
  start.meta = scene_packing_meta(scene, start.grains, seed, "shake");
  btr::make_tap_plan(start, scene, ts, o.engine);  // refuses a scene it cannot tap before any engine runs

  btr::RelaxSettings rs;
  rs.np = o.np;
  rs.wall_time_limit = o.time_limit;
  const fs::path out(o.out);
  fs::create_directories(out);
  std::cout << "shake --engine " << o.engine << ": " << start.grains.size() << " grains; relaxing the BTR packing at "
            << "rest in " << (out / "relax").string() << "\n";
  btr::RelaxResult relaxed;
  try {
    relaxed = btr::relax(start, scene, o.engine, rs, (out / "relax").string());
  } catch (const std::invalid_argument& e) {
    // An engine's writer refusing the scene before anything runs (e.g. YADE's periodic cell narrower than 4 largest
    // radii, container.size): bad input, exit 2.
    throw btr::RelaxRefused(e.what());
  }
  const btr::RelaxPlan plan = btr::make_tap_plan(relaxed.relaxed, scene, ts, o.engine);
  const auto adapter = btr::make_adapter(o.engine);
  const btr::TapResult tapped =
      btr::run_tapping(relaxed.relaxed, scene, *adapter, o.engine, ts, plan, (out / "tap").string());

  const double d_small = bed_grain_diameter(relaxed.relaxed.grains, btr_scene);
  SeriesWriter series(o.out, name, "cycle");
  std::string table = kCycleHeader;
  const long n_taps = static_cast<long>(tapped.taps.size());
  for (long c = 0; c <= n_taps; ++c) {
    const btr::Grains& grains = c == 0 ? relaxed.relaxed.grains : tapped.taps[c - 1].grains;
    const double seconds = relaxed.cpu_seconds + (c == 0 ? 0.0 : tapped.cpu_seconds[c - 1]);
    table += cycle_row_text(measure_cycle(c, seconds, grains, btr_scene, d_small), d_small);
    if (c % every == 0 || c == n_taps) {
      json meta = snapshot_meta("shake", btr_scene, scene_json, seed, grains.size());
      meta["cycle"] = c;
      meta["engine"] = o.engine;
      meta["simulated_time"] = c == 0 ? 0.0 : tapped.taps[c - 1].rested_time;
      series.write(c, static_cast<double>(c), grains, meta);
    }
  }
  btr::write_text_file((out / (name + "_cycles.csv")).string(), table);

  json record = {
      {"engine", o.engine},
      {"scene", scene.file},
      {"seed", seed},
      {"grains", start.grains.size()},
      {"gamma", tapped.record["gamma"]},
      {"frequency", tapped.record["frequency"]},
      {"amplitude", tapped.record["amplitude"]},
      {"timestep", tapped.record["timestep"]},
      {"timestep_rule", tapped.record["timestep_rule"]},
      {"relax",
       {{"dir", "relax"},
        {"stop_reason", relaxed.stop_reason},
        {"simulated_time", relaxed.simulated_time},
        {"engine_cpu_seconds", relaxed.cpu_seconds},
        {"wall_seconds", relaxed.wall_seconds}}},
      {"tapping", tapped.record},
      {"btr_cpu_seconds", own_cpu_seconds()},
      {"seconds_column", "NAME_cycles.csv seconds: the engine's processor time so far (the relaxation's, plus the "
                         "tapping run's up to the end of that tap's rest, shared out by time steps)"},
  };
  btr::write_text_file((out / "shake_dem.json").string(), record.dump(1) + "\n");

  if (!o.quiet) {
    const json& rec = tapped.record;
    std::printf("%s: %zu grains, %ld taps in %s (Gamma %.4g, %.4g Hz, amplitude %.4g m); engine %.4g s processor "
                "time per tap (relaxation %.4g s)\n",
                scene.name.c_str(), start.grains.size(), n_taps, o.engine.c_str(), rec["gamma"].get<double>(),
                rec["frequency"].get<double>(), rec["amplitude"].get<double>(),
                rec["engine_cpu_seconds_per_tap"].get<double>(), relaxed.cpu_seconds);
    std::printf("  wrote %s/%s.pvd (%d snapshots), %s_cycles.csv and shake_dem.json\n", o.out.c_str(), name.c_str(),
                series.count(), name.c_str());
  }
  return kSuccess;
}

}  // namespace btr_app
