#pragma once
// Small packings and scenes for the coupling tests, made here so the tests do not wait for the BTR
// engine: grains dropped at random (seeded) in horizontal layers 2.2 radii apart, without overlap,
// the lowest layer slightly above the floor; a relaxation lets them fall and settle.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "btr/scene/scene.h"
#include "coupling/io/packing_io.h"
#include "coupling/io/scene_json.h"
#include "coupling/yade/yade_script.h"

namespace btr_test {

// Is the engine ("liggghts" or "yade") installed? (the engine tests skip, with the reason, when not)
inline bool have_engine(const std::string& engine) {
  const std::string probe = engine == "liggghts"
                                ? "command -v liggghts >/dev/null 2>&1"
                                : std::string("test -d ") + btr::kYadePythonPath + "/yade";
  return std::system(probe.c_str()) == 0;
}

// splitmix64, mapped to [0, 1) by hand (std distributions are implementation-defined).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  double uniform() {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

 private:
  std::uint64_t s_;
};

inline btr::Material soft_material() {
  btr::Material m;
  m.young = 5e7;
  m.poisson = 0.3;
  m.restitution = 0.5;
  m.friction = 0.5;
  return m;
}

// A one-component scene (r in [0.8, 1.2] mm, 2500 kg/m^3) in the given container.
inline btr::Scene make_scene(const std::string& name, int dimension, const btr::Container& container) {
  btr::Scene s;
  s.name = name;
  s.file = name + ".toml";
  s.dimension = dimension;
  btr::Component c;
  c.species = 1;
  c.density = 2500.0;
  c.radius.kind = btr::RadiusSpec::Kind::Uniform;
  c.radius.min = 0.8e-3;
  c.radius.max = 1.2e-3;
  c.material = soft_material();
  s.grains.components = {c};
  s.grains.count = 0;
  s.container = container;
  s.source.kind = btr::SourceSpec::Kind::Point;
  s.relax.engine = "liggghts";
  s.relax.model = "hertz";
  s.relax.max_time = 2.0;
  s.relax.stop_kinetic_ratio = 1e-6;
  s.relax.timestep_fraction = 0.2;
  return s;
}

// As make_scene, with rolling friction: a sphere rolling on a flat floor without rolling resistance
// never stops (its kinetic energy stays constant).
inline btr::Scene settling_scene(const std::string& name, int dimension, const btr::Container& container) {
  btr::Scene s = make_scene(name, dimension, container);
  s.grains.components[0].material.rolling_friction = 0.1;
  return s;
}

// Does a grain of radius r at x fit the container's footprint (lateral walls only)?
inline bool fits(const btr::Scene& s, const btr::Vec3& x, double r) {
  const btr::Container& c = s.container;
  switch (c.kind) {
    case btr::ContainerKind::Open: return true;
    case btr::ContainerKind::Periodic: return true;
    case btr::ContainerKind::Box:
      return std::abs(x.x()) <= c.size_x / 2 - r && (s.dimension == 2 || std::abs(x.y()) <= c.size_y / 2 - r);
    case btr::ContainerKind::HeleShaw: return std::abs(x.x()) <= c.size_x / 2 - r && std::abs(x.y()) <= c.gap / 2 - r;
    case btr::ContainerKind::Cylinder: return std::hypot(x.x(), x.y()) <= c.radius - r;
    case btr::ContainerKind::Drum: return false;  // the DEM coupling refuses drums
    case btr::ContainerKind::Mesh: return false;  // meshes have their own fixture (test_mesh_relax.cpp)
  }
  return false;
}

// n grains in random layers over the container's footprint (for "open": a square of half-width
// open_half about the axis). Species alternate over `species`.
inline btr::Packing layered_packing(const btr::Scene& scene, int n, std::uint64_t seed,
                                    const std::vector<int>& species = {1}, double open_half = 0.01) {
  Rng rng(seed);
  const btr::Container& c = scene.container;
  double half_x = 0, half_y = 0;
  switch (c.kind) {
    case btr::ContainerKind::Cylinder: half_x = half_y = c.radius; break;
    case btr::ContainerKind::HeleShaw: half_x = c.size_x / 2, half_y = c.gap / 2; break;
    case btr::ContainerKind::Open: half_x = half_y = open_half; break;
    default: half_x = c.size_x / 2, half_y = c.size_y / 2; break;
  }
  if (scene.dimension == 2) half_y = 0;
  const double r_max = 1.2e-3;
  btr::Packing p;
  double z = 1.1 * r_max;
  int layer_start = 0, failures = 0;
  while (static_cast<int>(p.grains.size()) < n) {
    btr::Grain g;
    g.r = rng.uniform(0.8e-3, 1.2e-3);
    g.species = species[p.grains.size() % species.size()];
    g.x = btr::Vec3(rng.uniform(-half_x, half_x), scene.dimension == 2 ? 0.0 : rng.uniform(-half_y, half_y), z);
    bool ok = fits(scene, g.x, g.r);
    for (std::size_t j = layer_start; ok && j < p.grains.size(); ++j) {
      btr::Vec3 d = p.grains[j].x - g.x;
      if (c.kind == btr::ContainerKind::Periodic) {
        d.x() -= c.size_x * std::round(d.x() / c.size_x);
        if (scene.dimension == 3) d.y() -= c.size_y * std::round(d.y() / c.size_y);
      }
      ok = d.norm() > 1.05 * (g.r + p.grains[j].r);
    }
    if (ok) {
      p.grains.push_back(g);
      failures = 0;
    } else if (++failures > 2000) {  // layer full: start the next one
      z += 2.2 * r_max;
      layer_start = static_cast<int>(p.grains.size());
      failures = 0;
    }
  }
  p.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", scene.dimension}};
  return p;
}

inline btr::Container container(btr::ContainerKind kind, double a = 0.02, double b = 0.02) {
  btr::Container c;
  c.kind = kind;
  switch (kind) {
    case btr::ContainerKind::Open: break;
    case btr::ContainerKind::Cylinder: c.radius = a; break;
    case btr::ContainerKind::HeleShaw: c.size_x = a, c.gap = b; break;
    default: c.size_x = a, c.size_y = b; break;
  }
  return c;
}

// The folder every fresh_dir of this test process lives in, removed when the process ends (set
// BTR_KEEP_TEST_FILES to keep it for a look at a failed run's files). The process id keeps concurrent
// test runs (other worktrees on the same machine) out of each other's way.
struct TestFolder {
  std::filesystem::path root = std::filesystem::temp_directory_path() /
                               ("btr_coupling_test_" + std::to_string(::getpid()));
  ~TestFolder() {
    std::error_code ec;
    if (!std::getenv("BTR_KEEP_TEST_FILES")) std::filesystem::remove_all(root, ec);
  }
};
inline TestFolder test_folder;

inline std::string fresh_dir(const std::string& name) {
  const auto dir = test_folder.root / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace btr_test
