// `btr relax PACKING.csv --engine liggghts|yade [--np N] -o OUTDIR`: run a DEM relaxation of a packing
// and write the relaxed packing, its kinetic-energy history and its contacts into OUTDIR.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/preload.h"
#include "coupling/dem/process.h"
#include "coupling/dem/relax.h"
#include "coupling/io/atomic_file.h"
#include "coupling/engines.h"
#include "engine_command.h"
#include "load_packing.h"
#include "measures_json.h"
#include "validators.h"

namespace btr_app {
namespace {

constexpr const char* kPredictedOverlapFile = "predicted_overlap.json";

nlohmann::json load_json(const btr::StaticOverlap::Load& l) {
  return {{"mean_relative", l.mean_relative}, {"largest_relative", l.largest_relative}, {"mean_overlap", l.mean_depth}};
}

// `--predict-overlap`: the contact law's static overlap of the grains on the floor (coupling/dem/preload.h),
// written to OUTDIR/predicted_overlap.json and summed up on the console; no engine is run.
int predict_overlap(const PackingWithScene& p, const std::string& out_dir) {
  const btr::StaticOverlap s = btr::predict_static_overlap(p.packing.grains, p.scene);
  const btr::Component& wall = btr::wall_component(p.scene);
  const nlohmann::json j = {
      {"law", s.law},
      {"floor_grains", s.floor_grains},
      {"total_weight", s.total_weight},
      {"column_force", s.column_force},
      {"single_grain", load_json(s.single)},
      {"under_column", load_json(s.column)},
      {"wall_material", {{"species", wall.species}, {"young", wall.material.young}, {"poisson", wall.material.poisson}}},
      {"definition",
       "static overlap of the contact law (relax.model) between a grain and the floor: single_grain under the grain's "
       "own weight, under_column under the packing's total weight shared by the grains on the floor (gap to the floor "
       "at most 1e-3 of the radius); *_relative: overlap / the grain's radius, mean and largest over those grains; "
       "mean_overlap in m"}};
  std::filesystem::create_directories(out_dir);
  const std::string path = (std::filesystem::path(out_dir) / kPredictedOverlapFile).string();
  btr::write_text_file(path, j.dump(1) + "\n");
  std::cout << "predicted static overlap (" << s.law << ", " << s.floor_grains
            << " grains on the floor): one grain under its weight " << s.single.mean_relative
            << " of its radius, under its column (" << s.column_force << " N) " << s.column.mean_relative
            << "\nwrote " << path << "\n";
  return kSuccess;
}

}  // namespace

Runner add_relax_command(CLI::App& app) {
  struct Options {
    std::string packing, engine, out;
    btr::RelaxSettings settings;
    double timestep = 0.0;
    double forced_timestep = 0.0;
    double max_time = 0.0;
    double damping = 0.0;
    double target_phi = 0.0;
    double compaction_damping = 0.0;
    double compaction_timestep_fraction = 0.0;
    std::vector<double> friction_scales;
    std::string stop_rule;
    bool predict_overlap = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("relax", "Relax a packing in LIGGGHTS or YADE and read the result back");
  cmd->footer(
      "Exit codes: 0 ok, 2 bad input, 5 the engine failed (OUTDIR/relax_failure.json says how: its \"kind\"), 6 "
      "--target-phi not reached (the relaxed packing is written), 128+N stopped by signal N (SIGTERM, SIGINT, SIGHUP: "
      "the engine and every process it started are ended first).");
  cmd->add_option("packing", o->packing, "PACKING.csv (the scene is read from PACKING.json beside it)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--engine", o->engine, "liggghts | yade (default: the scene's relax.engine)")
      ->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("--np", o->settings.np, "LIGGGHTS: MPI ranks (mpirun -np N); YADE: threads")
      ->check(positive_integer());
  cmd->add_option("-o,--out", o->out, "output folder (engine inputs, log, relaxed.csv/json/vtp, kinetic.csv, "
                                      "contacts.csv)")
      ->required();
  cmd->add_option("--timestep", o->timestep, "time step [s]; refused if above the stable one")
      ->check(positive_number());
  // Stability studies only (workflows/btrdem/stability.py bisects the step with it): hidden from --help
  // (empty group), never used by default; relaxed.json and the console record that the step was forced.
  cmd->add_option("--force-timestep", o->forced_timestep,
                  "time step [s] used even above the stable one (stability study only)")
      ->check(positive_number())
      ->excludes("--timestep")
      ->group("");
  cmd->add_option("--max-time", o->max_time, "simulated time limit [s] (default: the scene's relax.max_time)")
      ->check(positive_number());
  cmd->add_option("--damping", o->damping,
                  "quasi-static damping in [0, 1): YADE's NewtonIntegrator damping, LIGGGHTS' fix viscous of equal "
                  "dissipation per oscillation (default: the scene's relax.damping, 0 = off)")
      ->check(number_in(0.0, 0.999999, "a damping in [0, 1)"));
  cmd->add_option("--stop-rule", o->stop_rule,
                  "kinetic-energy | unbalanced-force | displacement (default: the scene's relax.stop_rule)")
      ->check(CLI::IsMember({"kinetic-energy", "unbalanced-force", "displacement"}));
  cmd->add_option("--target-phi", o->target_phi,
                  "land on this bulk packing fraction: in the same run, compact with the friction scaled down until "
                  "the bulk packing fraction reaches it, then restore the friction, stop every grain and settle "
                  "(default: the scene's relax.target_phi, unset = no compaction)")
      ->check(number_in(0.0, 1.0, "a packing fraction in [0, 1]"));
  cmd->add_option("--friction-scales", o->friction_scales,
                  "--target-phi: friction scales of the compaction, decreasing in [0, 1), the next tried when the "
                  "bed comes to rest below the target (default: the scene's relax.friction_scales, 0)")
      ->delimiter(',');
  cmd->add_option("--compaction-damping", o->compaction_damping,
                  "--target-phi: damping during the compaction, as --damping; 0 lets the bed collapse freely (default: "
                  "the scene's relax.compaction_damping, 0.15)")
      ->check(number_in(0.0, 0.999999, "a damping in [0, 1)"));
  cmd->add_option("--compaction-timestep-fraction", o->compaction_timestep_fraction,
                  "--target-phi: time step of the compaction as a fraction of the rule's Rayleigh / contact time "
                  "(the settle keeps relax.timestep_fraction's step; default: the scene's "
                  "relax.compaction_timestep_fraction, else the same step)")
      ->check(number_in(1e-9, 1.0, "a fraction in (0, 1]"));
  cmd->add_option("--target-margin", o->settings.target_margin,
                  "bulk window of --target-phi: this many largest diameters from floor, walls and free surface "
                  "(btr measure --margin)")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--max-overlap", o->settings.max_overlap,
                  "refuse packings whose largest overlap / smaller radius exceeds this")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_flag("--preload", o->settings.preload,
                "pre-loaded start: give each contact the overlap that carries its static force (also on when "
                "the scene sets [relax] preload = true); writes OUTDIR/preloaded.* and preloaded.forces.*");
  cmd->add_option("--time-limit", o->settings.wall_time_limit, "wall-time limit of the engine run [s]")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_flag("--predict-overlap", o->predict_overlap,
                "only predict: write OUTDIR/" + std::string(kPredictedOverlapFile) +
                    ", the contact law's static overlap of a grain on the floor alone and under its column, "
                    "and run no engine");

  // Anything else is a file it could not read or a value it refuses: bad input.
  return [o, cmd]() -> int {
    return run_engine_command("relax", kBadInput, [&]() -> int {
      PackingWithScene p = load_packing_with_scene(o->packing);
      if (o->predict_overlap) return predict_overlap(p, o->out);
      if (cmd->count("--timestep")) o->settings.timestep = o->timestep;
      if (cmd->count("--force-timestep")) o->settings.forced_timestep = o->forced_timestep;
      if (cmd->count("--max-time")) p.scene.relax.max_time = o->max_time;
      if (cmd->count("--damping")) o->settings.damping = o->damping;
      if (!o->stop_rule.empty()) p.scene.relax.stop_rule = o->stop_rule;
      const std::string engine = o->engine.empty() ? p.scene.relax.engine : o->engine;
      if (cmd->count("--target-phi")) o->settings.target_phi = o->target_phi;
      if (cmd->count("--friction-scales")) o->settings.friction_scales = o->friction_scales;
      if (cmd->count("--compaction-damping")) o->settings.compaction_damping = o->compaction_damping;
      if (cmd->count("--compaction-timestep-fraction"))
        o->settings.compaction_timestep_fraction = o->compaction_timestep_fraction;
      btr::RelaxResult r = btr::relax(p.packing, p.scene, engine, o->settings, o->out);
      // The relaxed packing's measures, by the same definition as the deposit's, stored in relaxed.json.
      r.relaxed.meta["measures"] = measures_to_json(measure_in_scene(r.relaxed.grains, p.scene));
      btr::write_packing_meta(o->out, "relaxed", r.relaxed.meta);
      std::cout << engine << ": stopped by " << r.stop_reason << " (rule: " << p.scene.relax.stop_rule
                << ") at t = " << r.simulated_time << " s after " << r.wall_seconds
                << " s wall time; final kinetic energy "
                << (r.kinetic_history.empty() ? 0.0 : r.kinetic_history.back().second) << " J; unbalanced force "
                << r.final_unbalanced_force << "; " << r.contacts.size() << " contacts\n";
      if (p.scene.container.kind == btr::ContainerKind::Open)
        std::cout << "open floor: " << r.removed.size() << " grain(s) left the region and were removed\n";
      std::cout << "wrote " << o->out << "/relaxed.csv (.json, .vtp), kinetic.csv, contacts.csv, velocities.csv\n";
      const nlohmann::json& target = r.relaxed.meta.contains("target_phi") ? r.relaxed.meta["target_phi"]
                                                                            : nlohmann::json();
      if (target.is_object() && target.value("reached", true) == false) {
        std::cerr << "btr relax: the target packing fraction " << target.value("target", 0.0)
                  << " was not reached (relaxed.json, target_phi); the relaxed packing is written\n";
        return kTargetNotReached;
      }
      return kSuccess;
    });
  };
}

}  // namespace btr_app
