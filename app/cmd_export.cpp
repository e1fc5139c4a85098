// `btr export PACKING.csv --to liggghts|yade -o DIR`: write the engine's inputs only; they run
// unchanged elsewhere (see the head of the written script for the command).
#include <iostream>
#include <memory>

#include "commands.h"
#include "coupling/dem/relax.h"
#include "coupling/engines.h"
#include "load_packing.h"
#include "validators.h"

namespace btr_app {

Runner add_export_command(CLI::App& app) {
  struct Options {
    std::string packing, engine, out;
    btr::RelaxSettings settings;
    double timestep = 0.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("export", "Write ready-to-run LIGGGHTS or YADE inputs for a packing");
  cmd->add_option("packing", o->packing, "PACKING.csv (the scene is read from PACKING.json beside it)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--to", o->engine, "liggghts | yade")->required()->check(CLI::IsMember({"liggghts", "yade"}));
  cmd->add_option("-o,--out", o->out, "output folder")->required();
  cmd->add_option("--timestep", o->timestep, "time step [s]; refused if above the stable one")
      ->check(positive_number());
  cmd->add_option("--max-overlap", o->settings.max_overlap,
                  "refuse packings whose largest overlap / smaller radius exceeds this")
      ->capture_default_str()
      ->check(non_negative_number());

  cmd->add_flag("--preload", o->settings.preload,
                "write the pre-loaded packing (as btr relax --preload does)");

  return [o, cmd]() -> int {
    try {
      PackingWithScene p = load_packing_with_scene(o->packing);
      if (cmd->count("--timestep")) o->settings.timestep = o->timestep;
      for (const std::string& f : btr::export_inputs(p.packing, p.scene, o->engine, o->settings, o->out))
        std::cout << "wrote " << f << "\n";
      return kSuccess;
    } catch (const std::exception& e) {
      std::cerr << "btr export: " << e.what() << "\n";
      return kBadInput;
    }
  };
}

}  // namespace btr_app
