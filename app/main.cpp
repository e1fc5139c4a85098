// The `btr` program: deposit, bench, relax, export, pour, measure, shake, drum, redeposit.
#include <iostream>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"btr: Bottom-To-Top Reconstruction of granular packings, and their DEM relaxation"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(BTR_VERSION));

  struct Entry { CLI::App* cmd; btr_app::Runner run; };
  std::vector<Entry> entries;
  auto remember = [&](btr_app::Runner run) { entries.push_back({app.get_subcommands({}).back(), run}); };
  remember(btr_app::add_deposit_command(app));
  remember(btr_app::add_bench_command(app));
  remember(btr_app::add_relax_command(app));
  remember(btr_app::add_export_command(app));
  remember(btr_app::add_pour_command(app));
  remember(btr_app::add_settle_command(app));
  remember(btr_app::add_measure_command(app));
  remember(btr_app::add_shake_command(app));
  remember(btr_app::add_redeposit_command(app));
  remember(btr_app::add_drum_command(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? btr_app::kSuccess : btr_app::kBadInput;
  }
  for (auto& e : entries)
    if (e.cmd->parsed()) return e.run();
  return btr_app::kBadInput;
}
