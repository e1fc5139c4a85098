// `btr shake SCENE.toml -o OUTDIR`: dynamic BTR by shaking (seed 001 section 6.6). The scene's
// packing is built with the BTR engine, then shaken [shaking].cycles times; every snapshot_every
// cycles (and at cycle 0 and the last) OUTDIR/NAME_cNNNNNN.{csv,json,vtp} is written, and
// OUTDIR/NAME.pvd indexes them for ParaView; OUTDIR/NAME_cycles.csv has one row per cycle. With --engine the
// DEM counterpart runs instead (shake_dem.h): the same packing relaxed and tapped, the same files and columns.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include "btr/dynamics/shaking.h"
#include "btr/placement/deposition.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "command_support.h"
#include "commands.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "engine_command.h"
#include "progress.h"
#include "series_files.h"
#include "shake_cycles.h"
#include "shake_dem.h"
#include "validators.h"

namespace btr_app {
namespace {

using nlohmann::json;
using Options = ShakeOptions;

int run(const Options& o, const CLI::App& cmd) {
  btr::Scene scene = btr::load_scene(o.scene);
  if (!scene.shaking)
    throw btr::SceneError(o.scene + ": missing table [shaking] (cycles, lift, noise, snapshot_every)");
  if (scene.container.kind == btr::ContainerKind::Mesh)
    throw btr::SceneError(o.scene + ": container.kind: \"mesh\" is not shaken: a redeposition starts its grains "
                          "inside the container, which a triangle mesh's placement does not support");
  const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
  scene.seed = seed;
  if (cmd.count("--cycles")) scene.shaking->cycles = o.cycles;
  if (!o.engine.empty()) return run_shake_dem(o, cmd, scene, seed);
  for (const char* dem_only : {"--np", "--time-limit", "--taps", "--rest-time"})
    if (cmd.count(dem_only))
      throw btr::SceneError(std::string(dem_only) + ": only with --engine (DEM tapping); dynamic BTR has no engine");
  const btr::ShakingSpec sh = *scene.shaking;
  const std::string name = output_name(o.name, scene);

  const json scene_json = btr::scene_to_json(scene);
  SeriesWriter series(o.out, name, "cycle");
  std::string table = kCycleHeader;
  bool all_ok = true;
  auto t0 = std::chrono::steady_clock::now();
  ProgressBar bar(scene.name, o.quiet);
  btr::Grains grains = btr::run_scene(scene, seed, scene.grains.count, {}).grains;
  // Lengths in bed-grain diameters: the bed's equal grains with an intruder, else the mean diameter.
  const double d_small = bed_grain_diameter(grains, scene);
  btr::Shaker shaker(scene.dimension, scene.container, sh.lift, sh.noise, seed ^ 0x5348414b45ULL);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (std::int64_t c = 0;; ++c) {
    table += cycle_row_text(measure_cycle(c, seconds, grains, scene, d_small), d_small);
    if (c % sh.snapshot_every == 0 || c == sh.cycles) {
      json meta = snapshot_meta("shake", scene, scene_json, seed, grains.size());
      meta["cycle"] = c;
      if (o.check) all_ok = check_snapshot("shake", "cycle", c, grains, scene, meta) && all_ok;
      series.write(c, c, grains, meta);
    }
    btr::write_text_file(o.out + "/" + name + "_cycles.csv", table);
    if (c == sh.cycles) break;
    bar.update(c, sh.cycles);
    const auto t = std::chrono::steady_clock::now();
    grains = shaker.cycle(grains);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  }
  if (!o.quiet) {
    std::printf("%s: %zu grains (%dD, %s container, seed %llu), %lld cycles (lift %.4g m, noise %.4g m)\n",
                scene.name.c_str(), grains.size(), scene.dimension, btr::to_string(scene.container.kind),
                static_cast<unsigned long long>(seed), static_cast<long long>(sh.cycles), sh.lift, sh.noise);
    std::printf("  wrote %s/%s.pvd (%d snapshots) and %s_cycles.csv\n", o.out.c_str(), name.c_str(),
                series.count(), name.c_str());
  }
  return o.check && !all_ok ? kCheckFailed : kSuccess;
}

}  // namespace

Runner add_shake_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "shake",
      "Dynamic BTR by shaking (Jullien-Meakin; seed 001 section 6.6): build the scene's packing, then per\n"
      "cycle number the grains by height, lift the pile by [shaking].lift, and redeposit them lowest first\n"
      "with the BTR engine (optional noise: a uniform horizontal displacement in [-a, a] per grain).\n"
      "Writes OUTDIR/NAME_cNNNNNN.{csv,json,vtp} every snapshot_every cycles, OUTDIR/NAME.pvd (ParaView\n"
      "collection) and OUTDIR/NAME_cycles.csv (cycle, seconds, packing_fraction, bed_top_d, intruder_z_d,\n"
      "intruder_z_over_bed_top, intruder_below_top_d; lengths in bed-grain diameters d).\n"
      "With --engine liggghts|yade: the same BTR packing is relaxed at rest in the engine and then tapped: per tap the\n"
      "floor moves by z = A sin(2 pi f t) for one period ([shaking] gamma = A (2 pi f)^2 / g, frequency f), then the\n"
      "bed rests until its kinetic energy dies out; the same files, plus OUTDIR/shake_dem.json, OUTDIR/relax/ and\n"
      "OUTDIR/tap/ (the engine runs); seconds = the engine's processor time so far.\n"
      "Exit codes: 0 ok, 2 bad input, 3 internal failure (placement or I/O), 4 --check failed, 5 the engine failed.");
  add_scene_run_options(
      cmd, *o, "scene file (TOML) with a [shaking] table, e.g. inputs/brazil_nut.toml",
      "random seed for the deposition and the noise (default: the scene's)",
      [&] {
        cmd->add_option("--cycles", o->cycles, "number of cycles (default: [shaking].cycles)")->check(positive_integer());
      },
      "self-check every snapshot; exit code 4 if any fails (files are still written)",
      "no progress bar and no summary; only errors");
  cmd->add_option("--engine", o->engine, "liggghts | yade: DEM tapping instead of dynamic BTR (default: dynamic BTR)")
      ->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("--taps", o->taps, "--engine: number of taps (default: [shaking].cycles)")->check(positive_integer());
  cmd->add_option("--rest-time", o->rest_time,
                  "--engine: longest rest after a tap [simulated s]; a rest ends sooner once the kinetic energy is "
                  "below the relaxation's threshold at two checks in a row")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--np", o->np, "--engine: LIGGGHTS MPI ranks (mpirun -np N), YADE threads")->check(positive_integer());
  cmd->add_option("--time-limit", o->time_limit, "--engine: wall-time limit of each engine run [s]")
      ->capture_default_str()
      ->check(positive_number());
  return [o, cmd]() {
    if (o->engine.empty()) return run_reporting_errors("shake", [&] { return run(*o, *cmd); });
    return run_engine_command("shake", kInternalFailure, [&] { return run(*o, *cmd); });
  };
}

}  // namespace btr_app
