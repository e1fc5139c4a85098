// `btr settle SCENE.toml -o OUTDIR [--engine liggghts|yade] [--count N] [--seed N] [--np N]`: a DEM-ready packing
// of a bed that stands for pouring the scene, without pouring it (docs/guide/settle.md): the BTR packing, a small
// periodic calibration pour of the scene's grains whose bulk packing fraction becomes the target, and a DEM
// relaxation of the BTR packing to that target (coupling/dem/settle_plan.h says what is chosen and why).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "btr/scene/size_budget.h"
#include "commands.h"
#include "coupling/dem/process.h"
#include "coupling/dem/settle_plan.h"
#include "coupling/engines.h"
#include "coupling/io/atomic_file.h"
#include "engine_command.h"
#include "measures_json.h"
#include "packing_meta.h"
#include "progress.h"
#include "validators.h"

namespace btr_app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Options {
  std::string scene, out, engine;
  std::int64_t count = 0, calibration_grains = 0;
  std::uint64_t seed = 0;
  int np = 1;
  double time_limit = 7200.0;
  bool quiet = false;
};

// One step's record in settle.json: processor time of btr itself (own_cpu_seconds' growth) plus that of the
// engine it ran, and wall time.
class StepClock {
 public:
  StepClock() : cpu0_(own_cpu_seconds()), wall0_(std::chrono::steady_clock::now()) {}
  json finish(const std::string& step, double engine_cpu_seconds, json details) const {
    const double own = own_cpu_seconds() - cpu0_;
    details["step"] = step;
    details["btr_cpu_seconds"] = own;
    details["engine_cpu_seconds"] = engine_cpu_seconds;
    details["cpu_seconds"] = own + engine_cpu_seconds;
    details["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
    return details;
  }

 private:
  double cpu0_;
  std::chrono::steady_clock::time_point wall0_;
};

// Simulated seconds the calibration pour may settle after its last batch, at least (a bed of ten largest diameters
// comes to rest in a few tenths of a second).
constexpr double kCalibrationSettleTime = 1.0;

void say(const std::string& line) { std::cout << "btr settle: " << line << std::endl; }

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
  const btr::CalibrationPlan cal = [&] {
    try {
      btr::check_settle_scene(scene);
      return btr::calibration_plan(scene, o.calibration_grains);
    } catch (const btr::RelaxRefused& e) {
      throw btr::SceneError(e.what());
    }
  }();
  const fs::path out(o.out);
  fs::create_directories(out);
  for (const char* stale : {".csv", ".json", ".vtp"}) fs::remove(out / (scene.name + stale));
  fs::remove(out / "settle.json");  // never left describing an earlier run
  json steps = json::array();

  // ---- 1. the BTR packing
  say("1/3 BTR deposit of " + std::to_string(count) + " grains");
  btr::Packing btr_packing;
  {
    const StepClock clock;
    btr::RunResult deposit;
    {
      ProgressBar bar(scene.name, o.quiet);
      deposit = btr::run_scene(scene, seed, count, [&](std::int64_t d, std::int64_t n) { bar.update(d, n); });
    }
    btr_packing.grains = std::move(deposit.grains);
    btr_packing.meta = scene_packing_meta(scene, btr_packing.grains, seed, "settle");
    btr_packing.meta["measures"] = measures_to_json(measure_in_scene(btr_packing.grains, scene));
    btr::write_packing((out / "btr").string(), scene.name, btr_packing);
    btr::write_packing_meta((out / "btr").string(), scene.name, btr_packing.meta);
    steps.push_back(clock.finish("deposit", 0.0, {{"what", "BTR deposition"}, {"output", "btr/" + scene.name + ".csv"}}));
  }

  // ---- 2. the calibration pour: the target packing fraction
  say("2/3 calibration pour of " + std::to_string(cal.grains) + " grains in a periodic cell " +
      std::to_string(cal.width * 1e3) + " mm wide (" + engine + ")");
  double target = 0.0;
  json target_from;
  {
    const StepClock clock;
    const btr::Grains grains = btr::scene_drop_grains(cal.scene, seed);
    btr::PourSettings settings;
    settings.seed = seed;
    settings.np = o.np;
    settings.wall_time_limit = o.time_limit;
    // At rest, not cut short by a max time chosen for the user's own relaxation.
    settings.settle_max_time = std::max(scene.relax.max_time, kCalibrationSettleTime);
    const fs::path dir = out / "calibration";
    btr::PourResult r = btr::pour(grains, cal.scene, engine, settings, dir.string(),
                                  scene_packing_meta(cal.scene, grains, seed, "settle calibration pour"));
    btr::MetricsOptions window;
    window.margin_diameters = btr::kCalibrationMargin;
    const btr::PackingMeasures m = measure_in_scene(r.poured.grains, cal.scene, window);
    r.poured.meta["measures"] = measures_to_json(m);
    btr::write_packing_meta(dir.string(), "poured", r.poured.meta);
    const json& pour_record = r.poured.meta["pour"];
    btr::write_text_file((dir / "pour.json").string(), pour_record.dump(1) + "\n");
    if (!m.bulk.valid)
      throw btr::SceneError("--calibration-grains: the calibration pour's bulk window is empty (" + m.bulk.note +
                            "): its bed of " + std::to_string(cal.grains) + " grains is too shallow; give more");
    target = m.bulk.packing_fraction;
    target_from = {{"source", "calibration pour"},
                   {"grains", cal.grains},
                   {"cell", {{"kind", "periodic"}, {"width", cal.width}, {"dimension", scene.dimension}}},
                   {"seed", seed},
                   {"engine", engine},
                   {"bulk_window_margin_largest_diameters", btr::kCalibrationMargin},
                   {"bulk_grains", m.bulk.grains_in_window},
                   {"bulk_coordination", m.bulk.mean_coordination},
                   {"output", "calibration/poured.csv"}};
    steps.push_back(clock.finish("calibration", pour_record.value("engine_cpu_seconds", r.run.cpu_seconds),
                                 {{"what", "periodic pour of the scene's grains and material"},
                                  {"grains", cal.grains},
                                  {"bulk_packing_fraction", target},
                                  {"simulated_seconds", r.run.simulated_time},
                                  {"stop_reason", r.run.stop_reason}}));
  }
  say("target bulk packing fraction " + std::to_string(target) + " (calibration pour)");

  // ---- 3. the relaxation of the BTR packing to the target
  say("3/3 " + engine + " relaxation of the BTR packing to the target");
  const btr::SettleChoices choices = btr::settle_choices(
      scene, target, target_from, btr::bed_depth_in_largest_diameters(btr_packing.grains, scene, target));
  btr::Scene relax_scene = scene;
  relax_scene.relax.stop_rule = choices.stop_rule;
  btr::RelaxSettings settings = choices.settings;
  settings.np = o.np;
  settings.wall_time_limit = o.time_limit;
  btr::RelaxResult r;
  btr::PackingMeasures settled_measures;
  {
    const StepClock clock;
    r = btr::relax(btr_packing, relax_scene, engine, settings, (out / "relax").string());
    settled_measures = measure_in_scene(r.relaxed.grains, scene);
    r.relaxed.meta["measures"] = measures_to_json(settled_measures);
    btr::write_packing_meta((out / "relax").string(), "relaxed", r.relaxed.meta);
    steps.push_back(clock.finish("relax", r.cpu_seconds,
                                 {{"what", "DEM relaxation of the BTR packing to the target"},
                                  {"simulated_seconds", r.simulated_time},
                                  {"stop_reason", r.stop_reason},
                                  {"output", "relax/relaxed.csv"}}));
  }

  // ---- the settled packing, and the engine's ready-to-run inputs of it
  btr::Packing settled = r.relaxed;
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
      "(btr/, calibration/, relax/)");
  if (reached.is_object() && reached.value("reached", true) == false) {
    std::cerr << "btr settle: the relaxation did not reach the target packing fraction " << target
              << " (settle.json, target_phi); the settled packing is written\n";
    return kTargetNotReached;
  }
  return kSuccess;
}

}  // namespace

Runner add_settle_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "settle",
      "A DEM-ready packing of a bed that stands for pouring the scene, without pouring it: the BTR packing,\n"
      "a small periodic calibration pour of the scene's grains and material in the same engine (its bulk\n"
      "packing fraction is the target), then the BTR packing relaxed to that target. Writes OUTDIR/NAME.csv\n"
      "(.json with the measures, .vtp), settle.json (every step's processor and wall time, the values chosen\n"
      "and where each came from), dem_input/ (the engine's ready-to-run input of the settled packing), and\n"
      "the steps' folders btr/, calibration/, relax/. Serves beds (periodic, box, cylinder; rain); refuses\n"
      "heaps, Hele-Shaw cells, drums and clusters with the reason.");
  cmd->footer(
      "Exit codes: 0 ok, 2 bad input or a scene settle does not serve, 5 an engine failed (its folder's "
      "relax_failure.json says how), 6 the target was not reached (the settled packing is written), 128+N stopped "
      "by signal N.");
  cmd->add_option("scene", o->scene, "SCENE.toml")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "output folder, created if missing")->required();
  cmd->add_option("--engine", o->engine, "liggghts | yade (default: the scene's relax.engine)")
      ->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("--count", o->count, "number of grains (default: the scene's grains.count)")
      ->check(positive_integer());
  cmd->add_option("--seed", o->seed, "seed of the drops, and of the calibration's (default: the scene's seed)");
  cmd->add_option("--np", o->np, "LIGGGHTS: MPI ranks (mpirun -np N); YADE: threads")->check(positive_integer());
  cmd->add_option("--calibration-grains", o->calibration_grains,
                  "grains of the calibration pour (default: enough to fill its cell 10 largest diameters deep; "
                  "fewer is cheaper and noisier)")
      ->check(positive_integer());
  cmd->add_option("--time-limit", o->time_limit, "wall-time limit of each engine run [s]")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_flag("--quiet", o->quiet, "no progress bar");
  return [o, cmd]() -> int { return run_engine_command("settle", kInternalFailure, [&] { return run(*o, *cmd); }); };
}

}  // namespace btr_app
