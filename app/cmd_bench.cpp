// `btr bench`: placement speed and peak memory against N for a shallow and a 10x deeper 3D periodic bed,
// one revolution of a 3D rotating drum, and (on request) a 2D heap. Each (scene, N) runs in a fresh child
// process (this program re-executed with a hidden option), so the peak resident memory is that run's own.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "btr/dynamics/drum.h"
#include "btr/placement/deposition.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/size_budget.h"
#include "commands.h"

namespace btr_app {
namespace {

struct Options {
  std::vector<double> sizes{1e5, 1e6};
  std::vector<double> drum_sizes{1e4, 1e5};
  int drum_steps = 100;
  bool big = false;
  std::vector<std::string> scenes{"bed3d", "bed3d_deep", "drum3d"};
  std::uint64_t seed = 1;
  // hidden: run one size in this process and print the result as one JSON line
  std::string child_scene;
  std::int64_t child_count = 0;
};

btr::Component constant_mass_glass(double r_min, double r_max) {
  btr::Component c;
  c.density = 2500.0;
  c.radius.kind = btr::RadiusSpec::Kind::ConstantMass;
  c.radius.min = r_min;
  c.radius.max = r_max;
  return c;
}

// The bench scenes, built here so that the footprint grows with N and the depth stays fixed:
//   bed3d       as inputs/bed3d.toml (constant-mass radii 0.5-1 mm, periodic rain), 0.03 m x 0.03 m per
//               10^4 grains: about 3 cm deep at every N;
//   bed3d_deep  the same with a footprint 10 times smaller in area: 10 times deeper;
//   drum3d      a drum with flat end walls (length = radius), radii 0.8-1 mm, ~40 % full (as
//               scripts/bench_drum.py), rained in, then rotated by one revolution of drum_steps steps;
//   heap2d      a 2D point-source heap on an open floor (radii 0.5-1 mm).
btr::Scene bench_scene(const std::string& which, std::int64_t n) {
  btr::Scene s;
  s.name = which;
  s.file = "(btr bench)";
  s.grains.count = n;
  s.grains.components = {constant_mass_glass(0.5e-3, 1.0e-3)};
  if (which == "bed3d" || which == "bed3d_deep") {
    s.dimension = 3;
    s.container.kind = btr::ContainerKind::Periodic;
    const double area = 0.03 * 0.03 * (double(n) / 1e4) / (which == "bed3d_deep" ? 10.0 : 1.0);
    s.container.size_x = s.container.size_y = std::sqrt(area);
    s.source.kind = btr::SourceSpec::Kind::Rain;
  } else if (which == "drum3d") {
    const double a = 0.8e-3, b = 1.0e-3;
    s.grains.components = {constant_mass_glass(a, b)};
    const double mean_v = 4.0 / 3.0 * M_PI * a * b * (a + b) / 2.0;  // constant mass: <r^3> = ab(a+b)/2
    const double R = std::cbrt(double(n) * mean_v / 0.58 / (0.4 * M_PI));  // 0.4 pi R^2 L at 0.58, L = R
    s.dimension = 3;
    s.container.kind = btr::ContainerKind::Drum;
    s.container.radius = R;
    s.container.size_y = R;
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

double wall_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Times the placements only: the deposition of a bed, or the drum's steps after its (untimed) fill.
int run_child(const Options& o) {
  try {
    const btr::Scene scene = bench_scene(o.child_scene, o.child_count);
    double wall = 0.0, cpu = 0.0;
    std::int64_t placed = 0;
    if (o.child_scene == "drum3d") {
      btr::Grains grains = btr::run_scene(scene, o.seed, o.child_count, {}).grains;
      btr::DrumStepper stepper(scene.dimension, scene.container, scene.container.radius / 10.0);
      const double dphi = 2.0 * M_PI / o.drum_steps;
      const double w0 = wall_seconds(), c0 = cpu_seconds();
      for (int k = 0; k < o.drum_steps; ++k) grains = stepper.step(grains, dphi);
      wall = wall_seconds() - w0, cpu = cpu_seconds() - c0;
      placed = static_cast<std::int64_t>(grains.size()) * o.drum_steps;
    } else {
      const double c0 = cpu_seconds();
      const btr::RunResult r = btr::run_scene(scene, o.seed, o.child_count, {});
      cpu = cpu_seconds() - c0, wall = r.wall_seconds;
      placed = static_cast<std::int64_t>(r.grains.size());
    }
    nlohmann::json j = {{"scene", o.child_scene}, {"placed", placed}, {"wall", wall}, {"cpu", cpu}};
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
  std::int64_t placed = 0;  // placements timed (N, or N x steps for the drum)
};

ChildResult spawn(const std::string& scene, std::int64_t n, const Options& o) {
  ChildResult out;
  int fd[2];
  if (::pipe(fd) != 0) {
    out.error = std::string("pipe: ") + std::strerror(errno);
    return out;
  }
  const std::string count = std::to_string(n), seed_s = std::to_string(o.seed), steps = std::to_string(o.drum_steps);
  std::vector<const char*> argv = {"btr", "bench", "--child-scene", scene.c_str(), "--child-count", count.c_str(),
                                   "--seed", seed_s.c_str(), "--drum-steps", steps.c_str(), nullptr};
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
    out.placed = j.at("placed").get<std::int64_t>();
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

bool whole_sizes(const std::vector<double>& in, const char* option, std::vector<std::int64_t>& out) {
  for (double s : in) {
    if (!(s >= 1.0) || s > 1e10 || s != std::floor(s)) {
      std::cerr << "btr bench: " << option << ": expected whole numbers >= 1 (e.g. 1e4,1e5), got " << s << "\n";
      return false;
    }
    if (auto why = btr::count_does_not_fit(static_cast<std::int64_t>(s), option)) {
      std::cerr << "btr bench: " << *why << "\n";
      return false;
    }
    out.push_back(static_cast<std::int64_t>(s));
  }
  return true;
}

int run(const Options& o) {
  if (!o.child_scene.empty()) return run_child(o);
  std::vector<std::int64_t> sizes, drum_sizes;
  if (!whole_sizes(o.sizes, "--sizes", sizes) || !whole_sizes(o.drum_sizes, "--drum-sizes", drum_sizes)) return kBadInput;
  if (o.drum_steps < 1) {
    std::cerr << "btr bench: --drum-steps: expected a whole number >= 1, got " << o.drum_steps << "\n";
    return kBadInput;
  }
  std::printf("%-10s %8s %10s %10s %9s %11s %12s %9s %8s\n", "scene", "N", "placed", "wall s", "cpu s",
              "grains/s", "grains/cpu-s", "peak MB", "B/grain");
  std::fflush(stdout);
  bool failed = false;
  struct Fit { std::string scene; double wall, cpu; };
  std::vector<Fit> exponents;
  std::map<std::string, std::map<std::int64_t, double>> cpu_per_grain;  // scene -> N -> CPU s per placement
  for (const std::string& scene : o.scenes) {
    std::vector<std::int64_t> ns = scene == "drum3d" ? drum_sizes : sizes;
    if (o.big && (scene == "bed3d" || scene == "bed3d_deep")) ns.push_back(10000000);
    std::vector<std::pair<double, double>> points, cpu_points;
    for (std::int64_t n : ns) {
      const ChildResult r = spawn(scene, n, o);
      if (!r.ok) {
        std::printf("%-10s %8lld   failed: %s\n", scene.c_str(), static_cast<long long>(n), r.error.c_str());
        failed = true;
      } else {
        const double placed = double(r.placed);
        std::printf("%-10s %8lld %10lld %10.3f %9.3f %11.0f %12.0f %9.1f %8.0f\n", scene.c_str(),
                    static_cast<long long>(n), static_cast<long long>(r.placed), r.wall, r.cpu,
                    r.wall > 0 ? placed / r.wall : 0.0, r.cpu > 0 ? placed / r.cpu : 0.0, r.peak_mb,
                    r.peak_mb * 1048576.0 / double(n));
        if (r.wall > 0 && r.cpu > 0) points.push_back({double(n), r.wall}), cpu_points.push_back({double(n), r.cpu});
        if (r.cpu > 0 && placed > 0) cpu_per_grain[scene][n] = r.cpu / placed;
      }
      std::fflush(stdout);
    }
    if (points.size() >= 2) exponents.push_back({scene, exponent(points), exponent(cpu_points)});
  }
  if (!exponents.empty()) {
    std::printf("\nleast-squares exponent b of time ~ N^b:\n");
    for (const Fit& f : exponents) std::printf("  %-11s wall %.2f, cpu %.2f\n", f.scene.c_str(), f.wall, f.cpu);
  }
  if (cpu_per_grain.count("bed3d") && cpu_per_grain.count("bed3d_deep")) {
    bool header = false;
    for (const auto& [n, shallow] : cpu_per_grain["bed3d"]) {
      const auto deep = cpu_per_grain["bed3d_deep"].find(n);
      if (deep == cpu_per_grain["bed3d_deep"].end()) continue;
      if (!header) std::printf("\nCPU time per grain, 10x deeper bed / shallow bed:\n"), header = true;
      std::printf("  N = %-9lld %.2f (%.2f us / %.2f us)\n", static_cast<long long>(n), deep->second / shallow,
                  1e6 * deep->second, 1e6 * shallow);
    }
  }
  return failed ? kInternalFailure : kSuccess;
}

}  // namespace

Runner add_bench_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Time the placement against N, each N in a fresh child process: bed3d, a 3D periodic bed of\n"
      "polydisperse spheres (constant-mass radii, r_max/r_min = 2, footprint 0.03 m x 0.03 m per 10^4\n"
      "grains, so ~3 cm deep at every N); bed3d_deep, the same 10 times deeper (footprint area / 10);\n"
      "drum3d, one revolution (--drum-steps steps, every grain redeposited each step) of a 3D drum ~40 %\n"
      "full of spheres with radii 0.8-1 mm (the fill is not timed); heap2d (on request), a 2D point-source\n"
      "heap. The table gives the placements timed, wall and CPU time, placements per wall and per CPU\n"
      "second, the child's peak resident memory and that per grain; then the least-squares exponent b of\n"
      "time ~ N^b per scene and the deep/shallow ratio of CPU time per grain.");
  cmd->add_option("--sizes", o->sizes, "grain counts of the beds and the heap, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--drum-sizes", o->drum_sizes, "grain counts of the drum, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--drum-steps", o->drum_steps, "drum steps timed (100: one revolution)")->capture_default_str();
  cmd->add_flag("--big", o->big, "add N = 1e7 for the beds (about 2 GB of memory each, minutes)");
  cmd->add_option("--scenes", o->scenes, "which scenes, comma-separated")
      ->delimiter(',')
      ->check(CLI::IsMember({"bed3d", "bed3d_deep", "drum3d", "heap2d"}))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--child-scene", o->child_scene)->group("");
  cmd->add_option("--child-count", o->child_count)->group("");
  return [o]() { return run(*o); };
}

}  // namespace btr_app
