// `btr drum SCENE.toml -o OUTDIR`: dynamic BTR in a slowly rotating drum (seed 000 section 6). The
// scene's packing is rained into the drum with the BTR engine, then each step rotates every grain with
// the drum by 2 pi / steps_per_revolution, lifts it by [drum].lift and redeposits all grains lowest
// first. Every snapshot_every steps (and at step 0 and the last) OUTDIR/NAME_sNNNNNN.{csv,json,vtp}
// is written, OUTDIR/NAME.pvd indexes them, and OUTDIR/NAME_steps.csv has one row per step.
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <iostream>
#include <memory>

#include "btr/dynamics/drum.h"
#include "btr/measures/metrics.h"
#include "btr/placement/deposition.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "command_support.h"
#include "commands.h"
#include "drum_dem.h"
#include "drum_table.h"
#include "engine_command.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "progress.h"
#include "series_files.h"
#include "scene_run_options.h"
#include "validators.h"

namespace btr_app {
namespace {

using nlohmann::json;

struct Options : SceneRunOptions {
  std::int64_t steps = 0;
  DrumDemOptions dem;  // --engine: the DEM drum
};

// Processor time of this process [s] (std::clock): the step's own cost when other jobs share the cores.
double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

int run(const Options& o, const CLI::App& cmd) {
  btr::Scene scene = btr::load_scene(o.scene);
  if (!scene.drum)
    throw btr::SceneError(o.scene + ": missing table [drum] (steps_per_revolution, revolutions, lift, "
                          "snapshot_every) with container.kind = \"drum\"");
  const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
  scene.seed = seed;
  if (!o.dem.engine.empty()) {
    DrumDemOptions d = o.dem;
    d.out = o.out, d.name = o.name, d.seed = seed, d.quiet = o.quiet;
    if (!cmd.count("--revolutions")) d.revolutions = scene.drum->revolutions;
    return run_drum_dem(scene, d);
  }
  for (const char* dem_only : {"--np", "--time-limit", "--revolutions", "--settle-max-time"})
    if (cmd.count(dem_only))
      throw btr::SceneError(std::string(dem_only) + ": only with --engine liggghts|yade (the DEM drum)");
  const btr::DrumSpec dr = *scene.drum;
  const std::int64_t steps =
      cmd.count("--steps") ? o.steps : std::llround(dr.revolutions * static_cast<double>(dr.steps_per_revolution));
  const std::string name = output_name(o.name, scene);
  const double R = scene.container.radius, dphi = 2.0 * M_PI / static_cast<double>(dr.steps_per_revolution);
  const json scene_json = btr::scene_to_json(scene);
  SeriesWriter series(o.out, name, "step");
  std::string table = drum_table_header();
  bool all_ok = true;
  auto t0 = std::chrono::steady_clock::now();
  double c0 = cpu_now();
  ProgressBar bar(scene.name, o.quiet);
  btr::Grains grains = btr::run_scene(scene, seed, scene.grains.count, {}).grains;
  const double fill_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double step_seconds = 0.0;
  btr::DrumStepper stepper(scene.dimension, scene.container, dr.lift);
  double seconds = fill_seconds, cpu = cpu_now() - c0;
  for (std::int64_t s = 0;; ++s) {
    const double angle_deg = 360.0 * static_cast<double>(s) / static_cast<double>(dr.steps_per_revolution);
    table += drum_table_row(s, angle_deg, seconds, cpu, btr::drum_measures(grains, scene.dimension, scene.container), R);
    if (s % dr.snapshot_every == 0 || s == steps) {
      json meta = snapshot_meta("drum", scene, scene_json, seed, grains.size());
      meta["step"] = s;
      meta["angle_deg"] = angle_deg;
      if (o.check) all_ok = check_snapshot("drum", "step", s, grains, scene, meta) && all_ok;
      series.write(s, angle_deg, grains, meta);
    }
    btr::write_text_file(o.out + "/" + name + "_steps.csv", table);
    if (s == steps) break;
    bar.update(s, steps);
    const auto t = std::chrono::steady_clock::now();
    c0 = cpu_now();
    grains = stepper.step(grains, dphi);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    cpu = cpu_now() - c0;
    step_seconds += seconds;
  }
  if (!o.quiet) {
    std::printf("%s: %zu grains (%dD drum, radius %.4g m, seed %llu): fill %.3f s, %lld steps in %.3f s "
                "(%.4f s per step, %.0f grains/s)\n",
                scene.name.c_str(), grains.size(), scene.dimension, R, static_cast<unsigned long long>(seed),
                fill_seconds, static_cast<long long>(steps), step_seconds, steps ? step_seconds / steps : 0.0,
                step_seconds > 0 ? static_cast<double>(grains.size()) * steps / step_seconds : 0.0);
    std::printf("  wrote %s/%s.pvd (%d snapshots) and %s_steps.csv\n", o.out.c_str(), name.c_str(), series.count(),
                name.c_str());
  }
  return o.check && !all_ok ? kCheckFailed : kSuccess;
}

}  // namespace

Runner add_drum_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "drum",
      "Dynamic BTR in a slowly rotating drum (seed 000 section 6): rain the scene's grains into the drum, then\n"
      "per step rotate every grain with the drum by 360/steps_per_revolution degrees, lift it by [drum].lift\n"
      "and redeposit all grains lowest first with the BTR engine. Writes OUTDIR/NAME_sNNNNNN.{csv,json,vtp}\n"
      "every snapshot_every steps, OUTDIR/NAME.pvd (ParaView collection) and OUTDIR/NAME_steps.csv (step,\n"
      "angle_deg, seconds, cpu_seconds, segregation_index, axis_small_R, axis_large_R, core_small_R, core_large_R, com_x_R,\n"
      "com_z_R, surface_angle_deg; distances in drum radii, small/large split at the median radius).\n"
      "With --engine liggghts|yade the drum is DEM: the same fill, relaxed in the still drum (OUTDIR/relax/),\n"
      "then rotated by the engine at [drum].rpm or .froude (default Froude 5e-3) for --revolutions\n"
      "(OUTDIR/rotation/), with snapshots at the same angles and OUTDIR/drum_dem.json (docs/guide/drum_dem.md).\n"
      "Exit codes: 0 ok, 2 bad input, 3 internal failure (placement or I/O), 4 --check failed, 5 the engine failed.");
  add_scene_run_options(
      cmd, *o, "scene file (TOML) with a drum container and a [drum] table",
      "random seed of the fill (default: the scene's)",
      [&] {
        cmd->add_option("--steps", o->steps, "number of steps (default: revolutions x steps_per_revolution)")
            ->check(positive_integer());
      },
      "self-check every snapshot; exit code 4 if any fails (files are still written)",
      "no progress bar and no summary; only errors");
  cmd->add_option("--engine", o->dem.engine, "liggghts | yade: rotate the drum in this DEM engine (default: dynamic BTR)")
      ->check(CLI::IsMember({"liggghts", "yade"}))
      ->excludes("--steps")
      ->excludes("--check");
  cmd->add_option("--np", o->dem.np, "--engine: LIGGGHTS MPI ranks, YADE threads")->check(positive_integer());
  cmd->add_option("--time-limit", o->dem.time_limit, "--engine: wall-time limit of each engine run [s]")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--revolutions", o->dem.revolutions, "--engine: revolutions to turn (default: [drum].revolutions)")
      ->check(positive_number());
  cmd->add_option("--settle-max-time", o->dem.settle_max_time,
                  "--engine: simulated time limit of the relaxation in the still drum [s] (default: relax.max_time)")
      ->check(positive_number());
  return [o, cmd]() {
    if (o->dem.engine.empty()) return run_reporting_errors("drum", [&] { return run(*o, *cmd); });
    return run_engine_command("drum", kInternalFailure, [&] { return run(*o, *cmd); });  // exit 5: the engine failed
  };
}

}  // namespace btr_app
