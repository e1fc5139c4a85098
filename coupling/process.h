#pragma once
// Running an engine: one child process in a given folder, its stdout and stderr captured to a file,
// killed (with its whole process group, e.g. mpirun and its ranks) past a wall-time limit.
#include <string>

#include "coupling/engine_adapter.h"

namespace btr {

struct ProcessOutcome {
  bool started = false;       // false: argv[0] could not be executed (start_error says why)
  std::string start_error;
  int exit_code = -1;         // when it exited normally
  int signal = 0;             // when a signal ended it
  bool timed_out = false;     // killed for exceeding the limit
  double wall_seconds = 0.0;
  bool ok() const { return started && !timed_out && signal == 0 && exit_code == 0; }
  std::string describe() const;  // "exit status 1", "killed by signal 9", "killed after 3600 s" ...
};

// Runs command.argv (argv[0] looked up on PATH) in dir with command.env added to the environment,
// stdin from /dev/null, stdout and stderr appended to output_file. time_limit in seconds (> 0).
ProcessOutcome run_process(const EngineCommand& command, const std::string& dir, double time_limit,
                           const std::string& output_file);

// The last n lines of a text file ("" if it cannot be read).
std::string tail_lines(const std::string& path, int n);

}  // namespace btr
