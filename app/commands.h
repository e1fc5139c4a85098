#pragma once
// Each subcommand of the `btr` program registers itself on the CLI11 app; main() runs the chosen one.
#include <CLI/CLI.hpp>
#include <functional>

namespace btr_app {

// Exit codes shared by every subcommand (docs/faults.md, "Exit codes").
enum ExitCode {
  kSuccess = 0,
  kBadInput = 2,
  kInternalFailure = 3,
  kCheckFailed = 4,
  kEngineFailed = 5,
  kTargetNotReached = 6,  // the run ended and wrote its result, but not what was asked (relaxed.json says which)
};

// Stopped by a signal while an engine ran (the engine and what it started were ended): 128 + the signal, as a
// shell reports a process the signal ended.
inline int interrupted_exit_code(int signal) { return 128 + signal; }

// A registered subcommand: `run` is called when the user chose it, and returns the exit code.
using Runner = std::function<int()>;

Runner add_deposit_command(CLI::App& app);
Runner add_bench_command(CLI::App& app);
Runner add_relax_command(CLI::App& app);
Runner add_export_command(CLI::App& app);
Runner add_measure_command(CLI::App& app);
Runner add_shake_command(CLI::App& app);
Runner add_drum_command(CLI::App& app);
Runner add_redeposit_command(CLI::App& app);
Runner add_pour_command(CLI::App& app);
Runner add_settle_command(CLI::App& app);

}  // namespace btr_app
