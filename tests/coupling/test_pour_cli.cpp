// `btr pour` as a user runs it: a tiny scene poured for real in LIGGGHTS and in YADE (same grains as the
// deposit, ids kept, every grain inside the container and at rest, the record), and the refusals (exit 2,
// naming the file and the field).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "coupling/dem/dem_walls.h"
#include "coupling/io/packing_io.h"
#include "coupling/io/scene_json.h"
#include "cli_run.h"
#include "relax_fixtures.h"

namespace btr {
namespace {
namespace fs = std::filesystem;

class PourCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("btr_pour_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static CliRun btr(const std::string& args) { return run_btr(args, dir_); }

  // A scene file in the scratch folder: `body` follows the [scene] table.
  static std::string scene_file(const std::string& name, const std::string& body, int dimension = 3) {
    const fs::path p = dir_ / (name + ".toml");
    std::ofstream(p) << "[scene]\nname = \"" << name << "\"\ndimension = " << dimension << "\nseed = 4\n" << body;
    return p.string();
  }

  static fs::path dir_;
};

fs::path PourCli::dir_;

// 36 spheres of radius 0.8-1.2 mm rained into a box 8 mm x 8 mm: four lattice layers, poured in 2 batches.
const char* kTinyBox = R"([grains]
count = 36
density = 2500.0
radius = { distribution = "uniform", min = 0.8e-3, max = 1.2e-3 }

[container]
kind = "box"
size = [0.008, 0.008]

[source]
kind = "rain"

[material]
young = 5e6
poisson = 0.3
restitution = 0.3
friction = 0.5

[relax]
model = "hertz"
max_time = 0.5
stop_kinetic_ratio = 1e-6
timestep_fraction = 0.2
)";

void expect_poured(const fs::path& out, const std::string& scene_path, const std::string& engine,
                   const Packing& deposited) {
  const Packing p = read_packing((out / "poured.csv").string());
  ASSERT_EQ(p.grains.size(), deposited.grains.size());
  const Scene scene = scene_from_json(p.meta["scene"], "poured.json");
  const std::vector<DemWall> walls = dem_walls(scene.container, scene.dimension);
  for (std::size_t i = 0; i < p.grains.size(); ++i) {
    const Grain& g = p.grains[i];
    // ids kept: grain i is the deposit's grain i (the same drops of the same scene and seed)
    EXPECT_EQ(g.r, deposited.grains[i].r) << "grain " << i + 1;
    EXPECT_EQ(g.species, deposited.grains[i].species) << "grain " << i + 1;
    for (const DemWall& w : walls) EXPECT_GT(w.distance(g.x), 0.9 * g.r) << "grain " << i + 1 << ", " << w.name;
    EXPECT_LT(g.x.z(), 0.02) << "grain " << i + 1 << " did not come down";
  }
  const nlohmann::json& r = p.meta["pour"];
  EXPECT_EQ(r["engine"], engine);
  EXPECT_EQ(r["stop_reason"], "kinetic-energy");  // at rest, not cut off by max time
  EXPECT_LT(r["final_kinetic_energy"].get<double>(), r["kinetic_threshold"].get<double>());
  EXPECT_GT(r["wall_seconds"].get<double>(), 0.0);
  EXPECT_GT(r["cpu_seconds"].get<double>(), 0.0);
  EXPECT_GE(r["cpu_seconds"].get<double>(), r["engine_cpu_seconds"].get<double>());
  EXPECT_NE(r["timestep_rule"].get<std::string>().find("Rayleigh time"), std::string::npos);
  EXPECT_EQ(r["settings"]["seed"], 4);
  EXPECT_EQ(r["batches"].get<std::size_t>(), r["batch_steps"].size());
  EXPECT_GE(r["batches"].get<int>(), 2);
  EXPECT_GT(r["simulated_time"].get<double>(), r["release_time"].get<double>());
  EXPECT_EQ(p.meta["seed"], 4);
  EXPECT_EQ(p.meta["command"], "pour");
  EXPECT_EQ(p.meta["scene_file"], scene_path);
  EXPECT_TRUE(p.meta["measures"].is_object());
  const nlohmann::json record = nlohmann::json::parse(slurp(out / "pour.json"));
  EXPECT_EQ(record["stop_reason"], r["stop_reason"]);
  // at rest: every grain's final speed is small against a fall through its own radius
  std::ifstream vel(out / "velocities.csv");
  std::string line;
  std::getline(vel, line);
  int rows = 0;
  while (std::getline(vel, line)) {
    double id, vx, vy, vz;
    char c;
    std::istringstream(line) >> id >> c >> vx >> c >> vy >> c >> vz;
    EXPECT_LT(std::sqrt(vx * vx + vy * vy + vz * vz), 0.01) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 36);
}

TEST_F(PourCli, TinySceneInLiggghtsAndYade) {
  const std::string scene = scene_file("tiny_box", kTinyBox);
  const CliRun dep = btr("deposit " + scene + " -o " + (dir_ / "deposit").string() + " --quiet");
  ASSERT_EQ(dep.code, 0) << dep.err;
  const Packing deposited = read_packing((dir_ / "deposit" / "tiny_box.csv").string());
  for (const std::string engine : {"liggghts", "yade"}) {
    SCOPED_TRACE(engine);
    if (!btr_test::have_engine(engine)) {
      ADD_FAILURE() << engine << " is not installed";
      continue;
    }
    const fs::path out = dir_ / ("pour_" + engine);
    const CliRun r = btr("pour " + scene + " -o " + out.string() + " --engine " + engine + " --max-batches 2");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find(engine + " pour: 36 grains, stopped by kinetic-energy"), std::string::npos) << r.out;
    expect_poured(out, scene, engine, deposited);
    EXPECT_TRUE(fs::exists(out / (engine == "liggghts" ? "in.btr" : "relax_yade.py")));  // the inputs are kept
  }
}

TEST_F(PourCli, APackingsGrainsKeepTheirIds) {
  const std::string scene = scene_file("tiny_box2", kTinyBox);
  ASSERT_EQ(btr("deposit " + scene + " -o " + (dir_ / "dep2").string() + " --quiet --count 20").code, 0);
  const std::string csv = (dir_ / "dep2" / "tiny_box2.csv").string();
  const fs::path out = dir_ / "pour_packing";
  const CliRun r = btr("pour " + csv + " -o " + out.string() + " --engine liggghts --seed 9 --pace 0.5");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const Packing in = read_packing(csv), p = read_packing((out / "poured.csv").string());
  ASSERT_EQ(p.grains.size(), in.grains.size());
  for (std::size_t i = 0; i < in.grains.size(); ++i) EXPECT_EQ(p.grains[i].r, in.grains[i].r);
  EXPECT_EQ(p.meta["pour"]["settings"]["seed"], 9);
  EXPECT_EQ(p.meta["pour"]["settings"]["pace"], 0.5);
  EXPECT_EQ(p.meta["source_packing"], fs::absolute(csv).string());
}

TEST_F(PourCli, RefusalsNameTheFileAndTheField) {
  const std::string open_rain = scene_file("open_rain", R"([grains]
count = 10
radius = { distribution = "constant", value = 1e-3 }
[container]
kind = "open"
[source]
kind = "rain"
)");
  CliRun r = btr("pour " + open_rain + " -o " + (dir_ / "r1").string());
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find(open_rain), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("source.kind"), std::string::npos) << r.err;

  const std::string stiff = scene_file("stiff", std::string(kTinyBox) + "\n");
  r = btr("pour " + stiff + " -o " + (dir_ / "r2").string() + " --pace 0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--pace"), std::string::npos) << r.err;

  std::string negative(kTinyBox);
  negative.replace(negative.find("stop_kinetic_ratio = 1e-6"), 25, "stop_kinetic_ratio = -1");
  const std::string bad_fraction = scene_file("bad_ratio", negative);
  r = btr("pour " + bad_fraction + " -o " + (dir_ / "r3").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(bad_fraction), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stop_kinetic_ratio"), std::string::npos) << r.err;

  ASSERT_EQ(btr("deposit " + stiff + " -o " + (dir_ / "dep3").string() + " --quiet --count 5").code, 0);
  r = btr("pour " + (dir_ / "dep3" / "stiff.csv").string() + " -o " + (dir_ / "r4").string() + " --count 3");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--count"), std::string::npos) << r.err;

  fs::remove(dir_ / "dep3" / "stiff.json");
  r = btr("pour " + (dir_ / "dep3" / "stiff.csv").string() + " -o " + (dir_ / "r5").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("stiff.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r5" / "poured.csv"));
}

}  // namespace
}  // namespace btr
