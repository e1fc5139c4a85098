// `btr relax PACKING.csv --engine liggghts|yade [--np N] -o OUTDIR`: run a DEM relaxation of a packing
// and write the relaxed packing, its kinetic-energy history and its contacts into OUTDIR.
#include <cmath>
#include <iostream>
#include <memory>

#include "commands.h"
#include "coupling/relax.h"
#include "load_packing.h"

namespace btr_app {

Runner add_relax_command(CLI::App& app) {
  struct Options {
    std::string packing, engine, out;
    btr::RelaxSettings settings;
    double timestep = 0.0;
    double max_time = 0.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("relax", "Relax a packing in LIGGGHTS or YADE and read the result back");
  cmd->add_option("packing", o->packing, "PACKING.csv (the scene is read from PACKING.json beside it)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--engine", o->engine, "liggghts | yade (default: the scene's relax.engine)")
      ->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("--np", o->settings.np, "LIGGGHTS: MPI ranks (mpirun -np N); YADE: threads")
      ->check(CLI::PositiveNumber);
  cmd->add_option("-o,--out", o->out, "output folder (engine inputs, log, relaxed.csv/json/vtp, kinetic.csv, "
                                      "contacts.csv)")
      ->required();
  cmd->add_option("--timestep", o->timestep, "time step [s]; refused if above the stable one")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-time", o->max_time, "simulated time limit [s] (default: the scene's relax.max_time)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-overlap", o->settings.max_overlap,
                  "refuse packings whose largest overlap / smaller radius exceeds this")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--preload", o->settings.preload,
                "pre-loaded start: give each contact the overlap that carries its static force (also on when "
                "the scene sets [relax] preload = true); writes OUTDIR/preloaded.* and preloaded.forces.*");
  cmd->add_option("--time-limit", o->settings.wall_time_limit, "wall-time limit of the engine run [s]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);

  return [o, cmd]() -> int {
    try {
      PackingWithScene p = load_packing_with_scene(o->packing);
      if (cmd->count("--timestep")) o->settings.timestep = o->timestep;
      if (cmd->count("--max-time")) p.scene.relax.max_time = o->max_time;
      const std::string engine = o->engine.empty() ? p.scene.relax.engine : o->engine;
      const btr::RelaxResult r = btr::relax(p.packing, p.scene, engine, o->settings, o->out);
      std::cout << engine << ": stopped by " << r.stop_reason << " at t = " << r.simulated_time << " s after "
                << r.wall_seconds << " s wall time; final kinetic energy "
                << (r.kinetic_history.empty() ? 0.0 : r.kinetic_history.back().second) << " J; " << r.contacts.size()
                << " contacts\n"
                << "wrote " << o->out << "/relaxed.csv (.json, .vtp), kinetic.csv, contacts.csv, velocities.csv\n";
      return kSuccess;
    } catch (const btr::EngineFailure& e) {
      std::cerr << "btr relax: " << e.what() << "\n";
      return kEngineFailed;
    } catch (const std::exception& e) {
      std::cerr << "btr relax: " << e.what() << "\n";
      return kBadInput;
    }
  };
}

}  // namespace btr_app
