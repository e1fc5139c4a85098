// `btr shake SCENE.toml -o OUTDIR`: dynamic BTR by shaking (seed 001 section 6.6). The scene's
// packing is built with the BTR engine, then shaken [shaking].cycles times; every snapshot_every
// cycles (and at cycle 0 and the last) OUTDIR/NAME_cNNNNNN.{csv,json,vtp} is written, and
// OUTDIR/NAME.pvd indexes them for ParaView; OUTDIR/NAME_cycles.csv has one row per cycle.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "btr/dynamics/shaking.h"
#include "btr/measures/metrics.h"
#include "btr/placement/deposition.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "command_support.h"
#include "commands.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "progress.h"
#include "series_files.h"
#include "validators.h"

namespace btr_app {
namespace {

using nlohmann::json;

struct Options {
  std::string scene, out, name;
  std::uint64_t seed = 0;
  std::int64_t cycles = 0;
  bool check = false, quiet = false;
};

// One row of NAME_cycles.csv.
struct CycleRow {
  std::int64_t cycle = 0;
  double seconds = 0.0;
  double packing_fraction = NAN;  // bulk window (metrics.h); NaN when the bed is too shallow
  double bed_top = 0.0;           // mean free-surface height [m]
  double intruder_z = NAN;        // intruder centre height [m]
};

CycleRow measure(std::int64_t cycle, double seconds, const btr::Grains& grains, const btr::Scene& scene,
                 double d_small) {
  CycleRow row;
  row.cycle = cycle;
  row.seconds = seconds;
  // The bulk window keeps 3 bed-grain diameters (not 3 intruder diameters) from floor, walls and surface.
  double r_max = 0.0;
  for (const btr::Grain& g : grains) r_max = std::max(r_max, g.r);
  btr::MetricsOptions mo;
  mo.margin_diameters = 3.0 * d_small / (2.0 * r_max);
  const btr::BulkMeasures bulk = btr::bulk_measures(grains, scene.dimension, scene.container, mo);
  if (bulk.valid) row.packing_fraction = bulk.packing_fraction;
  if (scene.intruder) {
    btr::Grains bed(grains.begin() + 1, grains.end());  // the intruder is grain 1
    row.bed_top = btr::mean_surface_height(bed, scene.dimension, scene.container, 2.0 * d_small);
    row.intruder_z = grains[0].x.z();
  } else {
    row.bed_top = btr::mean_surface_height(grains, scene.dimension, scene.container, 2.0 * d_small);
  }
  return row;
}

std::string row_text(const CycleRow& r, double d_small) {
  char buf[320];
  const double in_d = r.intruder_z / d_small, below_top = (r.bed_top - r.intruder_z) / d_small;
  std::snprintf(buf, sizeof buf, "%lld,%.6f,%.10g,%.10g,%.10g,%.10g,%.10g\n", static_cast<long long>(r.cycle),
                r.seconds, r.packing_fraction, r.bed_top / d_small, in_d, r.intruder_z / r.bed_top, below_top);
  return buf;
}

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
  const btr::ShakingSpec sh = *scene.shaking;
  const std::string name = output_name(o.name, scene);

  const json scene_json = btr::scene_to_json(scene);
  SeriesWriter series(o.out, name, "cycle");
  std::string table = "cycle,seconds,packing_fraction,bed_top_d,intruder_z_d,intruder_z_over_bed_top,intruder_below_top_d\n";
  bool all_ok = true;
  auto t0 = std::chrono::steady_clock::now();
  ProgressBar bar(scene.name, o.quiet);
  btr::Grains grains = btr::run_scene(scene, seed, scene.grains.count, {}).grains;
  // Lengths in bed-grain diameters: the bed's equal grains with an intruder, else the mean diameter.
  double d_small = 0.0;
  if (scene.intruder) {
    d_small = 2.0 * grains.back().r;
  } else {
    for (const btr::Grain& g : grains) d_small += 2.0 * g.r;
    d_small /= static_cast<double>(grains.size());
  }
  btr::Shaker shaker(scene.dimension, scene.container, sh.lift, sh.noise, seed ^ 0x5348414b45ULL);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (std::int64_t c = 0;; ++c) {
    const CycleRow row = measure(c, seconds, grains, scene, d_small);
    table += row_text(row, d_small);
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
      "Exit codes: 0 ok, 2 bad input, 3 internal failure (placement or I/O), 4 --check failed.");
  cmd->add_option("scene", o->scene, "scene file (TOML) with a [shaking] table, e.g. inputs/brazil_nut.toml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "output folder, created if missing")->required();
  cmd->add_option("--seed", o->seed, "random seed for the deposition and the noise (default: the scene's)");
  cmd->add_option("--cycles", o->cycles, "number of cycles (default: [shaking].cycles)")->check(positive_integer());
  cmd->add_flag("--check", o->check, "self-check every snapshot; exit code 4 if any fails (files are still written)");
  cmd->add_flag("-q,--quiet", o->quiet, "no progress bar and no summary; only errors");
  cmd->add_option("--name", o->name, "base name of the output files (default: the scene name)");
  return [o, cmd]() { return run_reporting_errors("shake", [&] { return run(*o, *cmd); }); };
}

}  // namespace btr_app
