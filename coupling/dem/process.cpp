#include "coupling/dem/process.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <thread>
#include <vector>

extern char** environ;

namespace btr {
namespace {

// The stop signal received while an engine runs (0: none). Only the handler writes it.
volatile sig_atomic_t g_stop_signal = 0;

void remember_stop_signal(int sig) { g_stop_signal = sig; }

constexpr int kStopSignals[] = {SIGTERM, SIGINT, SIGHUP};

// While it lives, SIGTERM, SIGINT and SIGHUP are noted instead of ending this process, so that the engine
// can be stopped first; the previous handlers come back at the end.
class StopSignalsNoted {
 public:
  StopSignalsNoted() {
    g_stop_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = remember_stop_signal;
    sigemptyset(&sa.sa_mask);
    for (std::size_t i = 0; i < std::size(kStopSignals); ++i) ::sigaction(kStopSignals[i], &sa, &previous_[i]);
  }
  ~StopSignalsNoted() {
    for (std::size_t i = 0; i < std::size(kStopSignals); ++i) ::sigaction(kStopSignals[i], &previous_[i], nullptr);
  }
  StopSignalsNoted(const StopSignalsNoted&) = delete;
  StopSignalsNoted& operator=(const StopSignalsNoted&) = delete;

 private:
  struct sigaction previous_[std::size(kStopSignals)] {};
};

// The processes whose parent is this one (read from /proc/PID/stat), except `except`.
std::vector<pid_t> children_of_this_process(pid_t except) {
  std::vector<pid_t> out;
  const pid_t self = ::getpid();
  DIR* proc = ::opendir("/proc");
  if (!proc) return out;
  while (const dirent* e = ::readdir(proc)) {
    char* end = nullptr;
    const long pid = std::strtol(e->d_name, &end, 10);
    if (*end != '\0' || pid <= 0 || pid == except) continue;
    std::ifstream stat("/proc/" + std::string(e->d_name) + "/stat");
    std::string text;
    if (!std::getline(stat, text)) continue;
    const std::size_t close = text.rfind(')');  // the command name may hold spaces and parentheses
    if (close == std::string::npos) continue;
    char state = 0;
    long ppid = 0;
    if (std::sscanf(text.c_str() + close + 1, " %c %ld", &state, &ppid) == 2 && ppid == self)
      out.push_back(static_cast<pid_t>(pid));
  }
  ::closedir(proc);
  return out;
}

double children_cpu_seconds() {
  rusage u {};
  ::getrusage(RUSAGE_CHILDREN, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// Ends what the engine left behind. This process is a child subreaper, so the descendants whose parent
// died (MPI ranks of a killed mpirun, say, which live in their own process groups) became its children.
void end_orphaned_descendants(pid_t engine) {
  for (int round = 0; round < 100; ++round) {
    const std::vector<pid_t> left = children_of_this_process(engine);
    if (left.empty()) return;
    for (pid_t p : left) ::kill(p, SIGKILL);
    for (pid_t p : left) ::waitpid(p, nullptr, 0);
  }
}

}  // namespace

std::string signal_name(int sig) {
  switch (sig) {
    case SIGTERM: return "SIGTERM";
    case SIGINT: return "SIGINT";
    case SIGHUP: return "SIGHUP";
    case SIGKILL: return "SIGKILL";
    default: return "signal " + std::to_string(sig);
  }
}

std::string ProcessOutcome::describe() const {
  if (!started) return "could not start: " + start_error;
  if (stopped_by != 0) return "stopped because btr received " + signal_name(stopped_by);
  if (timed_out) return "killed after the wall-time limit (" + std::to_string(wall_seconds) + " s)";
  if (signal != 0) return "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  return "exit status " + std::to_string(exit_code);
}

ProcessOutcome run_process(const EngineCommand& command, const std::string& dir, double time_limit,
                           const std::string& output_file) {
  ProcessOutcome out;
  if (command.argv.empty()) {
    out.start_error = "empty command";
    return out;
  }
  // Everything the child needs is prepared before fork (only async-signal-safe calls after it).
  std::vector<char*> argv;
  for (const std::string& a : command.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const int fd_out = ::open(output_file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd_out < 0) {
    out.start_error = "cannot open " + output_file + ": " + std::strerror(errno);
    return out;
  }
  const int fd_in = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  int report[2];  // the child writes errno here if exec fails; closes on a successful exec
  if (fd_in < 0 || ::pipe2(report, O_CLOEXEC) != 0) {
    out.start_error = std::string("cannot set up the child: ") + std::strerror(errno);
    ::close(fd_out);
    if (fd_in >= 0) ::close(fd_in);
    return out;
  }
  // The child's environment: ours with command.env added (replacing variables of the same name).
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) {
    const char* eq = std::strchr(*e, '=');
    const std::string name = eq ? std::string(*e, static_cast<std::size_t>(eq - *e)) : std::string(*e);
    if (!command.env.count(name)) env_strings.emplace_back(*e);
  }
  for (const auto& [k, v] : command.env) env_strings.push_back(k + "=" + v);
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);

  // Orphaned descendants of the engine become ours, so they can be found and ended (end_orphaned_descendants).
  ::prctl(PR_SET_CHILD_SUBREAPER, 1);
  const pid_t parent = ::getpid();
  StopSignalsNoted noted;
  const double cpu0 = children_cpu_seconds();  // the engine is the only child reaped in between
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    out.start_error = std::string("fork failed: ") + std::strerror(errno);
    ::close(fd_out), ::close(fd_in), ::close(report[0]), ::close(report[1]);
    return out;
  }
  if (pid == 0) {
    ::setpgid(0, 0);  // own process group: a timeout kills mpirun and every rank
    // If btr dies (even by SIGKILL) the engine gets SIGTERM; mpirun passes it on to its ranks.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);  // btr died before the line above
    for (int sig : kStopSignals) ::signal(sig, SIG_DFL);
    int err = 0;
    if (::chdir(dir.c_str()) != 0) err = errno;
    if (!err && (::dup2(fd_in, 0) < 0 || ::dup2(fd_out, 1) < 0 || ::dup2(fd_out, 2) < 0)) err = errno;
    if (!err) {
      ::execvpe(argv[0], argv.data(), envp.data());
      err = errno;
    }
    ssize_t w = ::write(report[1], &err, sizeof err);
    (void)w;
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also from the parent, so the group exists before any kill
  ::close(fd_out);
  ::close(fd_in);
  ::close(report[1]);
  int child_err = 0;
  ssize_t n = ::read(report[0], &child_err, sizeof child_err);
  ::close(report[0]);
  if (n == static_cast<ssize_t>(sizeof child_err)) {
    ::waitpid(pid, nullptr, 0);
    out.start_error = "'" + command.argv[0] + "' in " + dir + ": " + std::strerror(child_err);
    return out;
  }
  out.started = true;

  using clock = std::chrono::steady_clock;
  const auto deadline = t0 + std::chrono::duration<double>(time_limit);
  int status = 0;
  bool killed = false;
  clock::time_point kill_time;
  while (true) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) break;
    const auto now = clock::now();
    if (!killed && g_stop_signal != 0) {
      ::kill(-pid, SIGTERM);
      killed = true;
      kill_time = now;
      out.stopped_by = g_stop_signal;
    } else if (!killed && now >= deadline) {
      ::kill(-pid, SIGTERM);
      killed = true;
      kill_time = now;
      out.timed_out = true;
    } else if (killed && now - kill_time > std::chrono::seconds(5)) {
      ::kill(-pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  out.wall_seconds = std::chrono::duration<double>(clock::now() - t0).count();
  if (WIFEXITED(status)) out.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) out.signal = WTERMSIG(status);
  if (!killed && g_stop_signal != 0) out.stopped_by = g_stop_signal;  // arrived as the engine ended
  if (killed) ::kill(-pid, SIGKILL);  // leftovers of the group, if any
  end_orphaned_descendants(pid);
  out.cpu_seconds = children_cpu_seconds() - cpu0;
  return out;
}

std::string tail_lines(const std::string& path, int n) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    lines.push_back(line);
    if (static_cast<int>(lines.size()) > n) lines.pop_front();
  }
  std::string out;
  for (const std::string& l : lines) out += l + "\n";
  return out;
}

}  // namespace btr
