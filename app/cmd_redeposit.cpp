// `btr redeposit SCENE.toml -o OUTDIR`: coarsening of a cohesive nano-powder by redeposition of rigid
// clusters (seed 000 section 5). The scene's grains are deposited as random compact clusters of
// [clusters].size, then [clusters].cycles times cut into blocks, split into clusters of touching
// grains and dropped again. Every cycle writes OUTDIR/NAME_cNNNNNN.{csv,json,vtp} (csv with the
// cluster column) and a row of OUTDIR/NAME_cycles.csv; OUTDIR/NAME_sizes.csv holds the cluster-size
// distribution per cycle; OUTDIR/NAME.pvd indexes the snapshots.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include "btr/dynamics/redeposition.h"
#include "btr/placement/deposition.h"
#include "btr/scene/scene_toml.h"
#include "btr/verify/cluster_check.h"
#include "command_support.h"
#include "commands.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "series_files.h"
#include "scene_run_options.h"
#include "validators.h"

namespace btr_app {
namespace {

using nlohmann::json;

struct Options : SceneRunOptions {
  std::int64_t cycles = -1;
};

int run(const Options& o, const CLI::App& cmd) {
  btr::Scene scene = btr::load_scene(o.scene);
  if (!scene.clusters)
    throw btr::SceneError(o.scene + ": missing table [clusters] (size, block, cycles)");
  const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
  scene.seed = seed;
  if (o.cycles >= 0) scene.clusters->cycles = o.cycles;
  const std::string name = output_name(o.name, scene);
  const json scene_json = btr::scene_to_json(scene);
  SeriesWriter series(o.out, name, "cycle");
  std::string table = "cycle,seconds,grains,clusters,mean_cluster_size,largest_cluster,mean_height_d,packing_fraction\n";
  std::string sizes = "cycle,size,count\n";
  bool all_ok = true;
  btr::Redeposition redeposition(scene, seed);
  btr::Grains grains;
  double d = 0.0;
  for (std::int64_t c = 0; c <= scene.clusters->cycles; ++c) {
    const auto t0 = std::chrono::steady_clock::now();
    grains = c == 0 ? redeposition.initial() : redeposition.cycle(grains);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (c == 0) {
      for (const btr::Grain& g : grains) d += 2.0 * g.r;
      d /= static_cast<double>(grains.size());
    }
    const btr::CycleMeasures m = btr::measure_cycle(grains, scene.dimension, scene.container);
    std::int64_t clusters = 0, largest = 0;
    for (std::size_t s = 1; s < m.size_counts.size(); ++s) {
      clusters += m.size_counts[s];
      if (m.size_counts[s]) largest = static_cast<std::int64_t>(s);
      if (m.size_counts[s]) sizes += std::to_string(c) + "," + std::to_string(s) + "," + std::to_string(m.size_counts[s]) + "\n";
    }
    char row[320];
    std::snprintf(row, sizeof row, "%lld,%.6f,%zu,%lld,%.10g,%lld,%.10g,%.10g\n", static_cast<long long>(c), seconds,
                  grains.size(), static_cast<long long>(clusters), double(grains.size()) / double(clusters),
                  static_cast<long long>(largest), m.mean_height / d, m.packing_fraction);
    table += row;
    json meta = snapshot_meta("redeposit", scene, scene_json, seed, grains.size());
    meta["cycle"] = c;
    meta["clusters"] = clusters;
    if (o.check) {
      const btr::ClusterCheckReport rep = btr::check_clusters(grains, scene.dimension, scene.container);
      meta["check"] = {{"ok", rep.ok()}, {"overlaps", rep.overlaps}, {"unsupported", rep.unsupported},
                       {"examples", rep.examples}};
      if (!rep.ok()) {
        all_ok = false;
        std::cerr << "btr redeposit: check failed at cycle " << c << ": " << rep.overlaps << " overlaps, "
                  << rep.unsupported << " unsupported clusters\n";
      }
    }
    series.write(c, c, grains, meta);
    btr::write_text_file(o.out + "/" + name + "_cycles.csv", table);
    btr::write_text_file(o.out + "/" + name + "_sizes.csv", sizes);
    if (!o.quiet)
      std::printf("cycle %lld: %lld clusters (largest %lld), <h> = %.4g d, packing fraction %.4f, %.2f s\n",
                  static_cast<long long>(c), static_cast<long long>(clusters), static_cast<long long>(largest),
                  m.mean_height / d, m.packing_fraction, seconds);
  }
  if (o.check && !all_ok) return kCheckFailed;
  return kSuccess;
}

}  // namespace

Runner add_redeposit_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "redeposit",
      "Rigid clusters of a cohesive nano-powder (seed 000 section 5): deposit the scene's grains as random\n"
      "compact clusters of [clusters].size, then per cycle cut the deposit into blocks [clusters].block mean\n"
      "diameters wide, split each into clusters of touching grains and drop them again at random positions.\n"
      "Writes OUTDIR/NAME_cNNNNNN.{csv,json,vtp} per cycle (cluster column), OUTDIR/NAME.pvd,\n"
      "OUTDIR/NAME_cycles.csv (cycle, seconds, grains, clusters, mean_cluster_size, largest_cluster,\n"
      "mean_height_d: <h> by the strip method in mean diameters, packing_fraction) and OUTDIR/NAME_sizes.csv.\n"
      "Exit codes: 0 ok, 2 bad input, 3 internal failure (placement or I/O), 4 --check failed.");
  add_scene_run_options(
      cmd, *o, "scene file (TOML) with a [clusters] table, e.g. inputs/nano_powder.toml",
      "random seed (default: the scene's)",
      [&] {
        cmd->add_option("--cycles", o->cycles, "number of redeposition cycles (default: [clusters].cycles)")
            ->check(non_negative_integer());
      },
      "check every cycle's packing (overlaps, support of every cluster); exit 4 if any fails",
      "no per-cycle lines; only errors");
  return [o, cmd]() { return run_reporting_errors("redeposit", [&] { return run(*o, *cmd); }); };
}

}  // namespace btr_app
