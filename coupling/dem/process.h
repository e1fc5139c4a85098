#pragma once
// Running an engine: one child process in a given folder, its stdout and stderr captured to a file,
// killed (with its whole process group, e.g. mpirun and its ranks) past a wall-time limit, and stopped
// with everything it started when btr receives SIGTERM, SIGINT or SIGHUP or dies.
#include <stdexcept>
#include <string>

#include "coupling/dem/engine_adapter.h"

namespace btr {

struct ProcessOutcome {
  bool started = false;       // false: argv[0] could not be executed (start_error says why)
  std::string start_error;
  int exit_code = -1;         // when it exited normally
  int signal = 0;             // when a signal ended it
  bool timed_out = false;     // killed for exceeding the limit
  int stopped_by = 0;         // killed because this process received this signal (SIGTERM, SIGINT, SIGHUP)
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;   // processor time (user + system) of the child and the descendants it waited for
  bool ok() const { return started && !timed_out && stopped_by == 0 && signal == 0 && exit_code == 0; }
  std::string describe() const;  // "exit status 1", "killed by signal 9", "killed after 3600 s" ...
};

// btr received a stop signal while an engine ran; the engine and every process it started were ended.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal, const std::string& what) : std::runtime_error(what), signal_(signal) {}
  int signal() const { return signal_; }

 private:
  int signal_;
};

// "SIGTERM", "SIGINT", "SIGHUP", ... for messages.
std::string signal_name(int sig);

// Runs command.argv (argv[0] looked up on PATH) in dir with command.env added to the environment,
// stdin from /dev/null, stdout and stderr appended to output_file. time_limit in seconds (> 0).
// While it runs, SIGTERM, SIGINT and SIGHUP stop the child's process group (SIGTERM, then SIGKILL after
// 5 s) and are reported in stopped_by; the child gets SIGTERM if this process dies; when the child has
// ended, any descendant it left behind is killed (this process becomes a child subreaper).
ProcessOutcome run_process(const EngineCommand& command, const std::string& dir, double time_limit,
                           const std::string& output_file);

// The last n lines of a text file ("" if it cannot be read).
std::string tail_lines(const std::string& path, int n);

}  // namespace btr
