#pragma once
// The options every scene-driven BTR command takes (deposit, shake, drum, redeposit): the scene file, the
// output folder, the seed, the self-check, quiet and the output files' base name.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace btr_app {

struct SceneRunOptions {
  std::string scene, out, name;
  std::uint64_t seed = 0;  // 0: the scene's
  bool check = false, quiet = false;
};

// Adds them to cmd; the help texts that differ between commands are given. `between` runs after --seed,
// so a command's own options keep their place in --help.
template <class Between>
void add_scene_run_options(CLI::App* cmd, SceneRunOptions& o, const std::string& scene_help,
                           const std::string& seed_help, Between&& between, const std::string& check_help,
                           const std::string& quiet_help) {
  cmd->add_option("scene", o.scene, scene_help)->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o.out, "output folder, created if missing")->required();
  cmd->add_option("--seed", o.seed, seed_help);
  between();
  cmd->add_flag("--check", o.check, check_help);
  cmd->add_flag("-q,--quiet", o.quiet, quiet_help);
  cmd->add_option("--name", o.name, "base name of the output files (default: the scene name)");
}

}  // namespace btr_app
