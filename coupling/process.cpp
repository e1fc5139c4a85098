#include "coupling/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <thread>
#include <vector>

extern char** environ;

namespace btr {

std::string ProcessOutcome::describe() const {
  if (!started) return "could not start: " + start_error;
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

  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    out.start_error = std::string("fork failed: ") + std::strerror(errno);
    ::close(fd_out), ::close(fd_in), ::close(report[0]), ::close(report[1]);
    return out;
  }
  if (pid == 0) {
    ::setpgid(0, 0);  // own process group: a timeout kills mpirun and every rank
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
    if (!killed && now >= deadline) {
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
  if (out.timed_out) ::kill(-pid, SIGKILL);  // leftovers of the group, if any
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
