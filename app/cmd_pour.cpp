// `btr pour SCENE.toml|PACKING.csv -o DIR [--engine liggghts|yade]`: the reference DEM pour of a scene's grains
// (the drops `btr deposit` would place, same scene and seed) or of a packing's grains, written as
// DIR/poured.{csv,json,vtp} with the record DIR/pour.json (coupling/dem/pour.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "btr/placement/drops.h"
#include "btr/scene/scene_toml.h"
#include "btr/scene/size_budget.h"
#include "commands.h"
#include "coupling/dem/process.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/engines.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/scene_json.h"
#include "engine_command.h"
#include "load_packing.h"
#include "measures_json.h"
#include "packing_meta.h"
#include "validators.h"

namespace btr_app {
namespace {

using nlohmann::json;

struct Options {
  std::string input, out, engine;
  std::int64_t count = 0;
  std::uint64_t seed = 0;
  btr::PourSettings settings;
  double stop_ratio = 0.0, settle_max_time = 0.0, timestep_fraction = 0.0;
};

bool is_packing(const std::string& path) { return std::filesystem::path(path).extension() == ".csv"; }

int run(Options& o, const CLI::App& cmd) {
  btr::Scene scene;
  btr::Grains grains;
  json meta;
  std::optional<btr::Packing> source;
  if (is_packing(o.input)) {
    if (cmd.count("--count"))
      throw btr::SceneError("--count: a packing's grains are poured as they are (all of " + o.input +
                            "); pour a scene to choose the count");
    PackingWithScene p = load_packing_with_scene(o.input);
    scene = p.scene;
    const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
    grains = p.packing.grains;
    meta = scene_packing_meta(scene, grains, seed, "pour");
    meta["source_packing"] = std::filesystem::absolute(o.input).string();
    o.settings.seed = seed;
    source = std::move(p.packing);
  } else {
    scene = btr::load_scene(o.input);
    const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
    const std::int64_t count = cmd.count("--count") ? o.count : scene.grains.count;
    if (cmd.count("--count")) btr::check_count_fits(scene, count, "--count");
    scene.seed = seed;  // the stored scene rebuilds exactly these grains
    scene.grains.count = count;
    grains = btr::scene_drop_grains(scene, seed);
    meta = scene_packing_meta(scene, grains, seed, "pour");
    o.settings.seed = seed;
  }
  if (cmd.count("--stop-ratio")) o.settings.stop_ratio = o.stop_ratio;
  if (cmd.count("--settle-max-time")) o.settings.settle_max_time = o.settle_max_time;
  if (cmd.count("--timestep-fraction")) o.settings.timestep_fraction = o.timestep_fraction;
  const std::string engine = o.engine.empty() ? scene.relax.engine : o.engine;

  btr::PourResult r;
  try {
    r = btr::pour(grains, scene, engine, o.settings, o.out, meta, source ? &source->grains : nullptr);
  } catch (const btr::RelaxRefused& e) {
    // Name the file the refused values came from, unless the message does.
    const std::string from = is_packing(o.input)
                                 ? std::filesystem::path(o.input).replace_extension(".json").string()
                                 : o.input;
    const std::string what = e.what();
    throw btr::SceneError(what.rfind(from, 0) == 0 || what.rfind(scene.file, 0) == 0 ? what : from + ": " + what);
  }
  json& record = r.poured.meta["pour"];
  const double own = own_cpu_seconds();
  record["btr_cpu_seconds"] = own;
  record["cpu_seconds"] = own + record["engine_cpu_seconds"].get<double>();
  r.poured.meta["measures"] = measures_to_json(measure_in_scene(r.poured.grains, scene));
  btr::write_packing_meta(o.out, "poured", r.poured.meta);
  btr::write_text_file((std::filesystem::path(o.out) / "pour.json").string(), record.dump(1) + "\n");

  std::cout << engine << " pour: " << grains.size() << " grains, stopped by " << r.run.stop_reason << " at t = "
            << r.run.simulated_time << " s (time step " << record["timestep"].get<double>() << " s); "
            << r.run.wall_seconds << " s wall, " << record["cpu_seconds"].get<double>() << " s processor time\n";
  if (scene.container.kind == btr::ContainerKind::Open)
    std::cout << "open floor: " << r.run.removed.size() << " grain(s) left the region and were removed\n";
  std::cout << "wrote " << o.out << "/poured.csv (.json, .vtp), pour.json, kinetic.csv, contacts.csv, velocities.csv\n";
  return kSuccess;
}

}  // namespace

Runner add_pour_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "pour",
      "Reference DEM pour in LIGGGHTS or YADE: the grains start on a loose lattice over the source, are released\n"
      "in batches as a stream from a small drop height, and settle until the kinetic energy dies out (or the\n"
      "settle's max time). Writes OUTDIR/poured.csv (.json, .vtp; same ids), pour.json (the record), the engine's\n"
      "inputs and log, kinetic.csv, contacts.csv, velocities.csv.");
  cmd->footer("Exit codes: 0 ok, 2 bad input, 5 the engine failed, 128+N stopped by signal N.");
  cmd->add_option("input", o->input,
                  "SCENE.toml (its grains: the drops `btr deposit` places with the same seed) or PACKING.csv (its "
                  "grains, in order; the scene is read from PACKING.json)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "output folder, created if missing")->required();
  cmd->add_option("--engine", o->engine, "liggghts | yade (default: the scene's relax.engine)")
      ->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("--count", o->count, "SCENE: number of grains (default: the scene's grains.count)")
      ->check(positive_integer());
  cmd->add_option("--seed", o->seed,
                  "seed of the lattice's jitter and order, and of a scene's drops (default: the scene's seed)");
  cmd->add_option("--np", o->settings.np, "LIGGGHTS: MPI ranks (mpirun -np N); YADE: threads")
      ->check(positive_integer());
  cmd->add_option("--pace", o->settings.pace,
                  "batch interval / the batch's free-fall time (smaller pours faster)")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--drop-gap", o->settings.drop_gap,
                  "drop height of a batch above the pile's top [mean diameters]")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--max-batches", o->settings.max_batches, "at most this many batches (whole lattice layers)")
      ->capture_default_str()
      ->check(positive_integer());
  cmd->add_option("--stop-ratio", o->stop_ratio,
                  "settle until the kinetic energy < ratio * sum m g d (default: the scene's relax.stop_kinetic_ratio)")
      ->check(positive_number());
  cmd->add_option("--settle-max-time", o->settle_max_time,
                  "simulated seconds of settling after the last batch at most (default: the scene's relax.max_time)")
      ->check(positive_number());
  cmd->add_option("--timestep-fraction", o->timestep_fraction,
                  "time step as a fraction of the Rayleigh / contact time, the relaxation's rule (default: the "
                  "scene's relax.timestep_fraction, or its relax.timestep)")
      ->check(number_in(1e-9, 1.0, "a fraction in (0, 1]"));
  cmd->add_option("--check-interval", o->settings.check_interval,
                  "simulated seconds between stop checks (at least 1000 steps)")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--time-limit", o->settings.wall_time_limit, "wall-time limit of the engine run [s]")
      ->capture_default_str()
      ->check(positive_number());
  // Anything else is a file it could not read or a value it refuses: bad input.
  return [o, cmd]() -> int { return run_engine_command("pour", kBadInput, [&] { return run(*o, *cmd); }); };
}

}  // namespace btr_app
