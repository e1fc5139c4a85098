// `btr settle SCENE.toml -o OUTDIR [--engine liggghts|yade] [--count N] [--seed N] [--np N]`: a DEM-ready packing
// that stands for pouring the scene, without pouring it (docs/guide/settle.md). A bed: the BTR packing, a small
// periodic calibration pour of the scene's grains whose bulk packing fraction becomes the target, and a DEM
// relaxation of the BTR packing to that target. A heap: the calibration is the scene poured with softened grains,
// whose flank angle BTR then builds (settle_heap.h); coupling/dem/settle_plan.h says what is chosen and why.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "btr/model/number_text.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "btr/scene/size_budget.h"
#include "commands.h"
#include "coupling/dem/process.h"
#include "coupling/dem/settle_plan.h"
#include "coupling/dem/settle_verdict.h"
#include "coupling/engines.h"
#include "coupling/io/atomic_file.h"
#include "engine_command.h"
#include "measures_json.h"
#include "packing_meta.h"
#include "progress.h"
#include "settle_heap.h"
#include "settle_target.h"
#include "settle_steps.h"
#include "validators.h"

namespace btr_app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Options {
  std::string scene, out, engine;
  std::int64_t count = 0, calibration_grains = 0;
  double target_error = 0.0;
  std::uint64_t seed = 0;
  int np = 1;
  double time_limit = 7200.0;
  bool quiet = false;
};

int run(const Options& o, const CLI::App& cmd) {
  const StepClock total;
  btr::Scene scene = btr::load_scene(o.scene);
  const std::uint64_t seed = cmd.count("--seed") ? o.seed : scene.seed;
  const std::int64_t count = cmd.count("--count") ? o.count : scene.grains.count;
  if (cmd.count("--count")) btr::check_count_fits(scene, count, "--count");
  scene.seed = seed;
  scene.grains.count = count;
  if (!o.engine.empty()) scene.relax.engine = o.engine;
  const std::string engine = scene.relax.engine;
  scene.relax.target_phi.reset();  // settle chooses the target; a scene's own is for `btr relax`
  const bool heap = btr::settle_builds_heap(scene);
  const btr::CalibrationPlan cal = [&] {
    try {
      btr::check_settle_scene(scene);
      if (heap && cmd.count("--target-error"))
        throw btr::RelaxRefused("--target-error: a heap is judged by its angle, which its calibration (the scene "
                                "itself, softened) gives without a packing-fraction target");
      if (heap && cmd.count("--calibration-grains"))
        throw btr::RelaxRefused("--calibration-grains: a heap's calibration pours the scene's own grains (a smaller "
                                "heap stands at another angle); it takes no grain count");
      return heap ? btr::CalibrationPlan{} : btr::calibration_plan(scene, o.calibration_grains);
    } catch (const btr::RelaxRefused& e) {
      throw btr::SceneError(e.what());
    }
  }();
  SettleRunOptions run_options;
  run_options.seed = seed;
  run_options.np = o.np;
  run_options.time_limit = o.time_limit;
  const std::string of = heap ? "/4 " : "/3 ";
  const fs::path out(o.out);
  fs::create_directories(out);
  for (const char* stale : {".csv", ".json", ".vtp"}) fs::remove(out / (scene.name + stale));
  fs::remove(out / "settle.json");  // never left describing an earlier run
  json steps = json::array();

  // ---- 1. the BTR packing
  say("1" + of + "BTR deposit of " + std::to_string(count) + " grains");
  btr::Packing btr_packing;
  {
    const StepClock clock;
    btr::RunResult deposit;
    {
      ProgressBar bar(scene.name, o.quiet);
      deposit = btr::run_scene(scene, seed, count, [&](std::int64_t d, std::int64_t n) { bar.update(d, n); });
    }
    btr_packing.grains = std::move(deposit.grains);
    if (!heap) {
      try {
        btr::check_settle_window(btr_packing.grains, scene);
      } catch (const btr::RelaxRefused& e) {
        throw btr::SceneError(e.what());
      }
    }
    btr_packing.meta = scene_packing_meta(scene, btr_packing.grains, seed, "settle");
    btr_packing.meta["measures"] = measures_to_json(measure_in_scene(btr_packing.grains, scene));
    btr::write_packing((out / "btr").string(), scene.name, btr_packing);
    btr::write_packing_meta((out / "btr").string(), scene.name, btr_packing.meta);
    steps.push_back(clock.finish("deposit", 0.0, {{"what", "BTR deposition"}, {"output", "btr/" + scene.name + ".csv"}}));
  }

  // ---- 2. (beds) the calibration pour: the target packing fraction; (heaps) the calibration and the BTR heap
  double target = 0.0;
  json target_from;
  CalibratedTarget calibrated;
  btr::Packing to_relax;
  HeapSteps heap_steps;
  if (heap) {
    heap_steps = settle_heap(scene, engine, btr_packing.grains, run_options, out.string());
    for (const json& step : heap_steps.steps) steps.push_back(step);
    to_relax = heap_steps.heap;
  } else {
    say("2/3 calibration pour of " + std::to_string(cal.grains) + " grains in a periodic cell " +
        std::to_string(cal.width * 1e3) + " mm wide (" + engine + ")");
    calibrated =
        calibrated_target(cal, scene.dimension, engine, run_options, out.string(), o.target_error);
    for (const json& step : calibrated.steps) steps.push_back(step);
    target = calibrated.phi;
    target_from = calibrated.from;
    say("target bulk packing fraction " + std::to_string(target) + " +- " + btr::g6(calibrated.standard_error) +
        " (calibration pour" + (calibrated.steps.size() > 1 ? "s" : "") +
        "; standard error from the window in blocks)");
    if (!calibrated.error_met)
      std::cerr << "btr settle: --target-error " << o.target_error << " not reached in " << kMaxCalibrationPours
                << " calibration pours (standard error " << calibrated.standard_error
                << "); settling to their mean (settle.json, chosen.target_phi.from.target_error)\n";
    to_relax = btr_packing;
  }

  // ---- 3. the relaxation of the BTR packing to the target
  say(heap ? "4/4 " + engine + " quasi-static relaxation of the BTR heap"
            : "3/3 " + engine + " relaxation of the BTR packing to the target");
  const btr::SettleChoices choices =
      heap ? btr::heap_settle_choices(scene, heap_steps.angle_deg, heap_steps.angle_from)
           : btr::settle_choices(scene, target, target_from,
                                 btr::bed_depth_in_largest_diameters(btr_packing.grains, scene, target),
                                 btr::settle_target_margin(btr_packing.grains, scene, target));
  const std::string warning = choices.record.value(json::json_pointer("/compaction_damping/warning"), std::string());
  if (!warning.empty()) std::cerr << "btr settle: warning: " << warning << "\n";
  btr::Scene relax_scene = choices.scene;
  relax_scene.relax.stop_rule = choices.stop_rule;
  btr::RelaxSettings settings = choices.settings;
  settings.np = o.np;
  settings.wall_time_limit = o.time_limit;
  btr::RelaxResult r;
  btr::PackingMeasures settled_measures;
  {
    const StepClock clock;
    r = btr::relax(to_relax, relax_scene, engine, settings, (out / "relax").string());
    settled_measures = measure_in_scene(r.relaxed.grains, scene);
    r.relaxed.meta["measures"] = measures_to_json(settled_measures);
    btr::write_packing_meta((out / "relax").string(), "relaxed", r.relaxed.meta);
    steps.push_back(clock.finish("relax", r.cpu_seconds,
                                 {{"what", heap ? "DEM quasi-static relaxation of the BTR heap"
                                                : "DEM relaxation of the BTR packing to the target"},
                                  {"simulated_seconds", r.simulated_time},
                                  {"stop_reason", r.stop_reason},
                                  {"output", "relax/relaxed.csv"}}));
    const json not_at_rest =
        btr::relaxation_not_at_rest(r.relaxed.meta["relax"], r.relaxed.grains, r.velocities, heap);
    if (!not_at_rest.is_null()) {
      steps.back()["not_at_rest"] = not_at_rest;
      std::cerr << "btr settle: warning: " << not_at_rest["why"].get<std::string>() << " (settle.json, the relax step's "
                << "not_at_rest)\n";
    }
  }

  // ---- the settled packing, and the engine's ready-to-run inputs of it
  btr::Packing settled = r.relaxed;
  bool off_target = false;
  if (!heap && settled.meta.contains("target_phi")) {
    json& t = settled.meta["target_phi"];
    const json& settled_phi = t["settled_bulk_packing_fraction"];
    const btr::TargetVerdict v = btr::settle_target_verdict(
        t.value("initial_bulk_packing_fraction", 0.0),
        settled_phi.is_number() ? settled_phi.get<double>() : std::nan(""), t.value("compaction_ran", false),
        t.value("reached", true), target, calibrated.standard_error, calibrated.from.value("bulk_coordination", json()));
    off_target = v.off_target;
    if (!v.looser_than_btr.is_null()) {
      t["reached"] = false;
      t["looser_than_btr"] = v.looser_than_btr;
    }
    if (!v.short_of_target.is_null()) t["short_of_target"] = v.short_of_target;
  }
  settled.meta["command"] = "settle";
  json record = {{"program", "btr"},     {"version", BTR_VERSION}, {"command", "settle"},
                 {"scene_file", scene.file}, {"scene_name", scene.name}, {"engine", engine},
                 {"seed", seed},          {"count", count},          {"np", o.np},
                 {"chosen", choices.record}};
  const json& reached = settled.meta.contains("target_phi") ? settled.meta["target_phi"] : json();
  {
    const StepClock clock;
    btr::Scene user = scene;  // the user's own run: the scene's relax section as written
    std::vector<std::string> files = btr::export_inputs(settled, user, engine, btr::RelaxSettings{},
                                                        (out / "dem_input").string());
    for (std::string& f : files) f = fs::relative(f, out).string();
    steps.push_back(clock.finish("engine input", 0.0, {{"what", "ready-to-run " + engine + " input of the settled "
                                                                 "packing (the scene's relax settings)"},
                                                        {"files", files}}));
  }
  record["steps"] = steps;
  record["target_phi"] = reached;
  if (heap)
    record["angle_deg"] = {{"calibration", heap_steps.angle_deg},
                           {"settled", settled_measures.heap.valid ? json(settled_measures.heap.angle_deg) : json()}};
  record["measures"] = settled.meta["measures"];
  const json all = total.finish("total", 0.0, json::object());
  double cpu = 0.0;
  for (const json& s : steps) cpu += s["engine_cpu_seconds"].get<double>();
  record["cpu_seconds"] = all["btr_cpu_seconds"].get<double>() + cpu;
  record["wall_seconds"] = all["wall_seconds"];
  settled.meta["settle"] = record;
  btr::write_packing(o.out, scene.name, settled);
  btr::write_packing_meta(o.out, scene.name, settled.meta);
  btr::write_text_file((out / "settle.json").string(), record.dump(1) + "\n");

  say(measures_summary(settled_measures));
  say("processor time " + std::to_string(record["cpu_seconds"].get<double>()) + " s (calibration included), wall " +
      std::to_string(record["wall_seconds"].get<double>()) + " s");
  say("wrote " + o.out + "/" + scene.name + ".csv (.json, .vtp), settle.json, dem_input/, and each step's folder "
      "(btr/, calibration/, " + std::string(heap ? "btr_heap/, " : "") + "relax/)");
  for (const char* verdict : {"looser_than_btr", "short_of_target"})
    if (reached.is_object() && reached.contains(verdict))
      std::cerr << "btr settle: " << reached[verdict]["why"].get<std::string>() << " (settle.json, target_phi." << verdict
                << ")" << (off_target ? "; the settled packing is written" : "") << "\n";
  if (off_target) return kTargetNotReached;
  return kSuccess;
}

}  // namespace

Runner add_settle_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "settle",
      "A DEM-ready packing that stands for pouring the scene, without pouring it. A bed: the BTR packing,\n"
      "a small periodic calibration pour of the scene's grains and material in the same engine (its bulk\n"
      "packing fraction is the target), then the BTR packing relaxed to that target. A heap: the scene poured\n"
      "with softened grains (its flank angle is the target), BTR's heap built at that angle, then a\n"
      "quasi-static relaxation. Writes OUTDIR/NAME.csv\n"
      "(.json with the measures, .vtp), settle.json (every step's processor and wall time, the values chosen\n"
      "and where each came from), dem_input/ (the engine's ready-to-run input of the settled packing), and\n"
      "the steps' folders btr/, calibration/, (heaps) btr_heap/, relax/. Serves beds (periodic, box, cylinder;\n"
      "rain) and heaps (point sources; region sources in 2D and Hele-Shaw cells); refuses drums, meshes and\n"
      "clusters with the reason.");
  cmd->footer(
      "Exit codes: 0 ok, 2 bad input or a scene settle does not serve, 5 an engine failed (its folder's "
      "relax_failure.json says how), 6 the settled bed is not within 2 standard errors of the target (the compaction "
      "came to rest short of it, or the material pours looser than BTR places grains; the settled packing is written, "
      "settle.json target_phi says which), 128+N stopped by signal N.");
  cmd->add_option("scene", o->scene, "SCENE.toml")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "output folder, created if missing")->required();
  cmd->add_option("--engine", o->engine, "liggghts | yade (default: the scene's relax.engine)")
      ->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("--count", o->count, "number of grains (default: the scene's grains.count)")
      ->check(positive_integer());
  cmd->add_option("--seed", o->seed, "seed of the drops, and of the calibration's (default: the scene's seed)");
  cmd->add_option("--np", o->np, "LIGGGHTS: MPI ranks (mpirun -np N); YADE: threads")->check(positive_integer());
  cmd->add_option("--calibration-grains", o->calibration_grains,
                  "beds: grains of the calibration pour (default: enough to fill its cell 10 largest diameters "
                  "deep; fewer is cheaper and noisier); heaps take none")
      ->check(positive_integer());
  cmd->add_option("--target-error", o->target_error,
                  "beds: pour the calibration cell again at the next seeds (at most " +
                      std::to_string(kMaxCalibrationPours) +
                      " pours) until the standard error of the target is at most this (default: one pour)")
      ->check(positive_number());
  cmd->add_option("--time-limit", o->time_limit, "wall-time limit of each engine run [s]")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_flag("--quiet", o->quiet, "no progress bar");
  return [o, cmd]() -> int { return run_engine_command("settle", kInternalFailure, [&] { return run(*o, *cmd); }); };
}

}  // namespace btr_app
