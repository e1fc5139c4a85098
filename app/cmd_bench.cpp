// `btr bench`: deposition speed and peak memory against N for a 3D periodic bed and a 2D heap.
// Each (scene, N) runs in a fresh child process (this program re-executed with a hidden option), so the
// peak resident memory reported is that run's own.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "btr/deposition.h"
#include "btr/run_scene.h"
#include "commands.h"

namespace btr_app {
namespace {

struct Options {
  std::vector<double> sizes{1e4, 1e5, 1e6};
  bool big = false;
  std::vector<std::string> scenes{"bed3d", "heap2d"};
  std::uint64_t seed = 1;
  // hidden: run one size in this process and print the result as one JSON line
  std::string child_scene;
  std::int64_t child_count = 0;
};

btr::Component constant_mass_glass() {
  btr::Component c;
  c.density = 2500.0;
  c.radius.kind = btr::RadiusSpec::Kind::ConstantMass;
  c.radius.min = 0.5e-3;
  c.radius.max = 1.0e-3;
  return c;
}

// The bench scenes, as inputs/bed3d.toml and inputs/heap2d.toml but built here so that the bed's
// footprint grows with N: 0.03 m x 0.03 m per 10^4 grains keeps the bed about 3 cm deep at every N.
btr::Scene bench_scene(const std::string& which, std::int64_t n) {
  btr::Scene s;
  s.name = which;
  s.file = "(btr bench)";
  s.grains.count = n;
  s.grains.components = {constant_mass_glass()};
  if (which == "bed3d") {
    s.dimension = 3;
    s.container.kind = btr::ContainerKind::Periodic;
    s.container.size_x = s.container.size_y = 0.03 * std::sqrt(double(n) / 1e4);
    s.source.kind = btr::SourceSpec::Kind::Rain;
  } else if (which == "heap2d") {
    s.dimension = 2;
    s.container.kind = btr::ContainerKind::Open;
    s.source.kind = btr::SourceSpec::Kind::Point;
    s.source.scatter = 0.5e-3;
  } else {
    throw std::invalid_argument("unknown bench scene '" + which + "'");
  }
  return s;
}

double cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

int run_child(const Options& o) {
  try {
    const btr::Scene scene = bench_scene(o.child_scene, o.child_count);
    const double cpu0 = cpu_seconds();
    const btr::RunResult r = btr::run_scene(scene, o.seed, o.child_count, {});
    const double cpu = cpu_seconds() - cpu0;
    nlohmann::json j = {{"scene", o.child_scene}, {"n", r.grains.size()}, {"wall", r.wall_seconds}, {"cpu", cpu}};
    std::cout << j.dump() << std::endl;
    return kSuccess;
  } catch (const std::exception& e) {
    std::cerr << "btr bench (" << o.child_scene << ", N = " << o.child_count << "): " << e.what() << "\n";
    return kInternalFailure;
  }
}

struct ChildResult {
  bool ok = false;
  std::string error;
  double wall = 0.0;     // deposition only, measured by the child
  double cpu = 0.0;      // CPU time of the deposition (differs from wall time on a busy machine)
  double peak_mb = 0.0;
};

ChildResult spawn(const std::string& scene, std::int64_t n, std::uint64_t seed) {
  ChildResult out;
  int fd[2];
  if (::pipe(fd) != 0) {
    out.error = std::string("pipe: ") + std::strerror(errno);
    return out;
  }
  const std::string count = std::to_string(n), seed_s = std::to_string(seed);
  std::vector<const char*> argv = {"btr", "bench", "--child-scene", scene.c_str(), "--child-count", count.c_str(),
                                   "--seed", seed_s.c_str(), nullptr};
  const pid_t pid = ::fork();
  if (pid < 0) {
    out.error = std::string("fork: ") + std::strerror(errno);
    return out;
  }
  if (pid == 0) {
    ::dup2(fd[1], STDOUT_FILENO);
    ::close(fd[0]);
    ::close(fd[1]);
    ::execv("/proc/self/exe", const_cast<char* const*>(argv.data()));
    std::fprintf(stderr, "btr bench: cannot re-execute /proc/self/exe: %s\n", std::strerror(errno));
    ::_exit(127);
  }
  ::close(fd[1]);
  std::string text;
  char buf[4096];
  for (;;) {
    ssize_t k = ::read(fd[0], buf, sizeof buf);
    if (k > 0) text.append(buf, static_cast<std::size_t>(k));
    else if (k == 0 || errno != EINTR) break;
  }
  ::close(fd[0]);
  int status = 0;
  struct rusage usage {};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  out.peak_mb = usage.ru_maxrss / 1024.0;  // Linux: kilobytes
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    out.error = WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                  : "killed by signal " + std::to_string(WTERMSIG(status));
    return out;
  }
  try {
    nlohmann::json j = nlohmann::json::parse(text);
    out.wall = j.at("wall").get<double>();
    out.cpu = j.at("cpu").get<double>();
    out.ok = true;
  } catch (const std::exception& e) {
    out.error = std::string("unreadable child output: ") + e.what();
  }
  return out;
}

// Least-squares slope of log(t) against log(N).
double exponent(const std::vector<std::pair<double, double>>& points) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (auto [N, t] : points) {
    const double x = std::log(N), y = std::log(t);
    n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double den = n * sxx - sx * sx;
  return den > 0 ? (n * sxy - sx * sy) / den : std::nan("");
}

int run(const Options& o) {
  if (!o.child_scene.empty()) return run_child(o);
  std::vector<std::int64_t> sizes;
  for (double s : o.sizes) {
    if (!(s >= 1.0) || s > 1e10 || s != std::floor(s)) {
      std::cerr << "btr bench: --sizes: expected whole numbers >= 1 (e.g. 1e4,1e5), got " << s << "\n";
      return kBadInput;
    }
    sizes.push_back(static_cast<std::int64_t>(s));
  }
  std::printf("%-8s %10s %10s %12s %10s %9s\n", "scene", "N", "wall s", "grains/s", "cpu s", "peak MB");
  std::fflush(stdout);
  bool failed = false;
  struct Fit { std::string scene; double wall, cpu; };
  std::vector<Fit> exponents;
  for (const std::string& scene : o.scenes) {
    std::vector<std::int64_t> ns = sizes;
    if (o.big && scene == "bed3d") ns.push_back(10000000);
    std::vector<std::pair<double, double>> points, cpu_points;
    for (std::int64_t n : ns) {
      const ChildResult r = spawn(scene, n, o.seed);
      if (!r.ok) {
        std::printf("%-8s %10lld   failed: %s\n", scene.c_str(), static_cast<long long>(n), r.error.c_str());
        failed = true;
      } else {
        std::printf("%-8s %10lld %10.3f %12.0f %10.3f %9.1f\n", scene.c_str(), static_cast<long long>(n), r.wall,
                    r.wall > 0 ? n / r.wall : 0.0, r.cpu, r.peak_mb);
        if (r.wall > 0 && r.cpu > 0) points.push_back({double(n), r.wall}), cpu_points.push_back({double(n), r.cpu});
      }
      std::fflush(stdout);
    }
    if (points.size() >= 2) exponents.push_back({scene, exponent(points), exponent(cpu_points)});
  }
  if (!exponents.empty()) {
    std::printf("\nleast-squares exponent b of time ~ N^b:\n");
    for (const Fit& f : exponents) std::printf("  %-8s wall %.2f, cpu %.2f\n", f.scene.c_str(), f.wall, f.cpu);
  }
  return failed ? kInternalFailure : kSuccess;
}

}  // namespace

Runner add_bench_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Time the deposition against N: a 3D periodic bed of polydisperse spheres (constant-mass radii,\n"
      "r_max/r_min = 2, footprint 0.03 m x 0.03 m per 10^4 grains so the depth stays ~3 cm) and a 2D\n"
      "heap from a point source (same radii). Each N runs in a fresh child process; the table gives the\n"
      "deposition wall time, grains per second, the deposition's CPU time (lower than the wall time\n"
      "when other processes compete for the cores) and the child's peak resident memory, then the\n"
      "least-squares exponent b of time ~ N^b per scene.");
  cmd->add_option("--sizes", o->sizes, "grain counts, comma-separated")->delimiter(',')->capture_default_str();
  cmd->add_flag("--big", o->big, "add N = 1e7 for the bed (several GB of memory, minutes)");
  cmd->add_option("--scenes", o->scenes, "which scenes, comma-separated")
      ->delimiter(',')
      ->check(CLI::IsMember({"bed3d", "heap2d"}))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--child-scene", o->child_scene)->group("");
  cmd->add_option("--child-count", o->child_count)->group("");
  return [o]() { return run(*o); };
}

}  // namespace btr_app
