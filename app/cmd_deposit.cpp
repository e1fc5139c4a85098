// `btr deposit SCENE.toml -o OUTDIR`: build a packing with the BTR engine and write
// OUTDIR/NAME.csv, NAME.json and NAME.vtp, then print a summary.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>

#include "btr/measures/metrics.h"
#include "btr/placement/deposition.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "btr/scene/size_budget.h"
#include "btr/verify/check.h"
#include "command_support.h"
#include "commands.h"
#include "coupling/dem/preload.h"
#include "coupling/io/force_io.h"
#include "coupling/io/packing_io.h"
#include "coupling/io/scene_json.h"
#include "measures_json.h"
#include "packing_meta.h"
#include "progress.h"
#include "scene_run_options.h"
#include "validators.h"

namespace btr_app {
namespace {

using nlohmann::json;

struct Options : SceneRunOptions {
  std::int64_t count = 0;
  bool forces = false;
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

int run(const Options& o, const CLI::App& cmd) {
  const auto t_start = std::chrono::steady_clock::now();
  btr::Scene scene = btr::load_scene(o.scene);
  const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
  const std::int64_t count = cmd.count("--count") ? o.count : scene.grains.count;
  if (cmd.count("--count")) btr::check_count_fits(scene, count, "--count");
  const std::string name = output_name(o.name, scene);
  scene.seed = seed;  // the stored scene rebuilds exactly this packing
  scene.grains.count = count;

  // ---- deposition
  btr::RunResult result;
  {
    ProgressBar bar(scene.name, o.quiet);
    result = btr::run_scene(scene, seed, count, [&](std::int64_t done, std::int64_t total) { bar.update(done, total); });
  }
  btr::Packing packing;
  packing.grains = std::move(result.grains);
  const btr::Grains& grains = packing.grains;
  const std::int64_t n = static_cast<std::int64_t>(grains.size());

  // ---- self-check
  json check_json = nullptr;
  double check_seconds = 0.0;
  btr::CheckReport report;
  if (o.check) {
    auto t = std::chrono::steady_clock::now();
    report = btr::check_packing(grains, scene.dimension, scene.container);
    check_seconds = seconds_since(t);
    check_json = check_to_json(report);
  }

  // ---- summary measures
  auto t_metrics = std::chrono::steady_clock::now();
  const btr::PackingMeasures measures = measure_in_scene(grains, scene);
  const double metrics_seconds = seconds_since(t_metrics);

  // ---- metadata and files
  packing.meta = scene_packing_meta(scene, grains, seed, "deposit");
  packing.meta.update({
      {"timings", {{"deposition", result.wall_seconds}, {"check", o.check ? json(check_seconds) : json(nullptr)},
                   {"measures", metrics_seconds}, {"writing", nullptr}}},
      {"check", check_json},
      {"measures", measures_to_json(measures)},
  });
  auto t_write = std::chrono::steady_clock::now();
  std::vector<double> z(measures.coordination.begin(), measures.coordination.end());
  btr::write_packing(o.out, name, packing, {{"coordination", std::move(z)}});
  const double write_seconds = seconds_since(t_write);
  packing.meta["timings"]["writing"] = write_seconds;
  btr::write_packing_meta(o.out, name, packing.meta);

  // ---- static force network
  btr::ForceNetwork network;
  if (o.forces) {
    try {
      network = btr::packing_forces(grains, scene);
      btr::write_forces(o.out, name, grains, network);
    } catch (const std::exception& e) {
      std::cerr << "btr deposit: force network: " << e.what() << "\n";
      return kInternalFailure;
    }
    if (!network.unbalanced.empty()) {
      const btr::UnbalancedGrain* worst = &network.unbalanced.front();
      for (const btr::UnbalancedGrain& u : network.unbalanced)
        if (u.residual.norm() / u.load > worst->residual.norm() / worst->load) worst = &u;
      std::fprintf(stderr,
                   "btr deposit: force network: %zu grain(s) whose supports cannot carry their load with "
                   "non-negative normal forces (the rest is left unbalanced, not given negative forces); worst: "
                   "grain %lld, %.3g of its %.3g N load (%.3g N vertically)\n",
                   network.unbalanced.size(), static_cast<long long>(worst->id), worst->residual.norm() / worst->load,
                   worst->load, worst->residual.z());
    }
  }

  // ---- summary
  if (!o.quiet) {
    const double rate = result.wall_seconds > 0 ? n / result.wall_seconds : 0.0;
    std::printf("%s: %lld grains (%dD, %s container, seed %llu) in %.3f s, %.0f grains/s\n", scene.name.c_str(),
                static_cast<long long>(n), scene.dimension, btr::to_string(scene.container.kind),
                static_cast<unsigned long long>(seed), result.wall_seconds, rate);
    std::fputs(measures_summary(measures).c_str(), stdout);
    if (o.check)
      std::printf("  check: %s in %.3f s\n", report.ok() ? "ok" : "FAILED", check_seconds);
    if (o.forces)
      std::printf("  forces: %zu contacts; floor and walls carry %.12g of the weight (%.6g N); %zu unbalanced "
                  "grains; %lld with a singular support set (carried by a smaller subset); %lld lifted (upward load %.3g "
                  "of the weight); %lld pushed sideways (largest lateral load %.3g of a grain's weight; left to "
                  "friction); wrote %s/%s.forces.csv, .forces.vtp\n",
                  network.contacts.size(), network.container_force.z() / network.total_weight, network.total_weight,
                  network.unbalanced.size(), static_cast<long long>(network.singular_grains),
                  static_cast<long long>(network.lifted_grains),
                  network.lifted_force / network.total_weight, static_cast<long long>(network.lateral_grains),
                  network.largest_lateral, o.out.c_str(), name.c_str());
    std::printf("  wrote %s/%s.csv, .json, .vtp in %.3f s; %.3f s in all\n", o.out.c_str(), name.c_str(),
                write_seconds, seconds_since(t_start));
  }
  if (o.check && !report.ok()) {
    std::cerr << "btr deposit: check failed: " << check_message(report) << "\n";
    return kCheckFailed;
  }
  return kSuccess;
}

}  // namespace

Runner add_deposit_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "deposit",
      "Build a packing with the BTR engine (grains dropped one by one fall, roll and stop on stable supports)\n"
      "and write OUTDIR/NAME.csv (id,x,y,z,radius,species), NAME.json (scene, seed, counts, timings,\n"
      "summary measures) and NAME.vtp (ParaView: apply a Glyph filter, sphere, scaled by 'radius').\n"
      "Exit codes: 0 ok, 2 bad input, 3 internal failure (placement or I/O), 4 --check failed.");
  add_scene_run_options(
      cmd, *o, "scene file (TOML), e.g. inputs/bed3d.toml", "random seed (default: the scene's [scene] seed)",
      [&] {
        cmd->add_option("--count", o->count, "number of grains to place (default: the scene's grains.count)")
            ->check(positive_integer());
      },
      "self-check the packing (overlaps, unsupported grains, grains outside the container); the files are still "
      "written, and the exit code is 4 if anything is wrong",
      "no progress bar and no summary; only errors");
  cmd->add_flag("--forces", o->forces,
                "also write the static normal-force network: NAME.forces.csv (i,j,fx,fy,fz: force on grain i "
                "from j; j = 0 the floor, j < 0 a wall) and NAME.forces.vtp (force chains, lines coloured by |f|)");
  return [o, cmd]() { return run_reporting_errors("deposit", [&] { return run(*o, *cmd); }); };
}

}  // namespace btr_app
