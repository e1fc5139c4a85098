// `btr shake --engine liggghts|yade` as a user runs it: a tiny Brazil-nut scene (120 grains and an intruder in a
// periodic cell) relaxed and tapped twice for real in LIGGGHTS, and smaller ones (periodic 3D, 2D box) tapped once
// in YADE: the files of dynamic BTR's run with the same columns, ids kept, the floor moved and the grains with it,
// nobody below the floor, the record; and the refusals of bad [shaking] gamma / frequency and of a YADE cell too
// narrow (exit 2, naming the file and the field).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "cli_run.h"
#include "coupling/io/packing_io.h"
#include "relax_fixtures.h"

namespace btr {
namespace {
namespace fs = std::filesystem;

class ShakeDemCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("btr_shake_dem_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static CliRun btr(const std::string& args) { return run_btr(args, dir_); }

  // A scene file in the scratch folder: the tiny Brazil nut with `shaking_extra` appended to [shaking].
  static std::string scene_file(const std::string& name, const std::string& shaking_extra) {
    const fs::path p = dir_ / (name + ".toml");
    std::ofstream(p) << "[scene]\nname = \"" << name << "\"\ndimension = 3\nseed = 3\n" << kTinyNut << shaking_extra;
    return p.string();
  }

  static fs::path dir_;
  static const char* kTinyNut;
};

fs::path ShakeDemCli::dir_;

// 120 grains of radius 0.5 mm and an intruder of diameter ratio 3 in a periodic cell 6 mm x 6 mm.
const char* ShakeDemCli::kTinyNut = R"([grains]
count = 120
density = 2500.0
radius = { distribution = "constant", value = 0.5e-3 }

[container]
kind = "periodic"
size = [0.006, 0.006]

[source]
kind = "rain"

[intruder]
diameter_ratio = 3.0
position = [0.0, 0.0]

[material]
young = 5e6
poisson = 0.3
restitution = 0.5
friction = 0.5

[relax]
model = "hertz"
max_time = 0.3
stop_kinetic_ratio = 1e-6
timestep_fraction = 0.2

[shaking]
cycles = 2
lift = 1.0e-3
noise = 0.1e-3
snapshot_every = 1
)";

std::vector<std::vector<std::string>> read_csv(const fs::path& p, std::string& header) {
  std::ifstream in(p);
  std::getline(in, header);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    std::string c;
    while (std::getline(s, c, ',')) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

// The packing after the last tap against dynamic BTR's cycle 0 and the relaxed packing: the same grains in the same
// order (radius and species; the intruder, of radius intruder_r, is grain 1), every centre above the floor, below
// 20 mm and inside the 6 mm periodic cell. Returns the largest vertical move of a grain from the relaxed packing.
double check_tapped(const fs::path& btr0_csv, const fs::path& rested_csv, const fs::path& tapped_csv,
                    double intruder_r) {
  const Packing btr0 = read_packing(btr0_csv.string());
  const Packing rested = read_packing(rested_csv.string());
  const Packing tapped = read_packing(tapped_csv.string());
  EXPECT_EQ(tapped.grains.size(), btr0.grains.size());
  EXPECT_EQ(rested.grains.size(), btr0.grains.size());
  if (tapped.grains.size() != btr0.grains.size() || rested.grains.size() != btr0.grains.size()) return 0.0;
  double largest_move = 0.0;
  for (std::size_t i = 0; i < tapped.grains.size(); ++i) {
    const Grain& g = tapped.grains[i];
    EXPECT_EQ(g.r, btr0.grains[i].r) << "grain " << i + 1;
    EXPECT_EQ(g.species, btr0.grains[i].species) << "grain " << i + 1;
    EXPECT_GT(g.x.z(), 0.9 * g.r) << "grain " << i + 1 << " is below the floor";
    EXPECT_LT(g.x.z(), 0.02) << "grain " << i + 1 << " flew off";
    EXPECT_LE(std::max(std::abs(g.x.x()), std::abs(g.x.y())), 0.003) << "grain " << i + 1 << " is outside the cell";
    largest_move = std::max(largest_move, std::abs(g.x.z() - rested.grains[i].x.z()));
  }
  EXPECT_EQ(tapped.grains[0].r, intruder_r);
  return largest_move;
}

// Runs dynamic BTR (`btr_args`) and `taps` DEM taps in `engine` (`dem_args` added; Gamma 2.5 at 40 Hz) of `scene`
// (named `name`) into btr_out and dem_out; checks that the DEM run wrote dynamic BTR's files with the same table
// columns, a row per tap, and the engine, the floor's amplitude and period and a record per tap in shake_dem.json.
// Returns the DEM run's NAME_cycles.csv rows and its shake_dem.json.
struct DemRun {
  std::vector<std::vector<std::string>> rows;
  nlohmann::json record;
};
DemRun run_both(const std::string& scene, const std::string& name, const fs::path& btr_out, const fs::path& dem_out,
                const std::string& btr_args, const std::string& engine, long taps, const std::string& dem_args) {
  DemRun out;
  const CliRun b = run_btr("shake " + scene + " -o " + btr_out.string() + " --quiet " + btr_args, btr_out.parent_path());
  EXPECT_EQ(b.code, 0) << b.err;
  const CliRun r = run_btr("shake " + scene + " -o " + dem_out.string() + " --engine " + engine + " --taps " +
                               std::to_string(taps) + " " + dem_args,
                           dem_out.parent_path());
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  if (b.code != 0 || r.code != 0) return out;
  for (const std::string f : {"_c000000.csv", "_c000001.json", "_c000001.vtp", ".pvd", "_cycles.csv"})
    EXPECT_TRUE(fs::exists(dem_out / (name + f))) << name + f;
  std::string btr_header, dem_header;
  read_csv(btr_out / (name + "_cycles.csv"), btr_header);
  out.rows = read_csv(dem_out / (name + "_cycles.csv"), dem_header);
  EXPECT_EQ(dem_header, btr_header);
  EXPECT_EQ(out.rows.size(), static_cast<std::size_t>(taps) + 1);
  out.record = nlohmann::json::parse(slurp(dem_out / "shake_dem.json"));
  const nlohmann::json& t = out.record["tapping"];
  EXPECT_EQ(out.record["engine"], engine);
  EXPECT_EQ(t["engine"], engine);
  EXPECT_EQ(t["per_tap"].size(), static_cast<std::size_t>(taps));
  EXPECT_EQ(t["gamma"], 2.5);
  EXPECT_EQ(t["frequency"], 40.0);
  const double omega = 2.0 * M_PI * 40.0;
  EXPECT_NEAR(t["amplitude"].get<double>(), 2.5 * 9.81 / (omega * omega), 1e-12);
  EXPECT_NEAR(t["timestep"].get<double>() * t["steps_per_tap"].get<double>(), 1.0 / 40.0, 1e-12);
  EXPECT_TRUE(fs::exists(dem_out / "relax" / "relaxed.csv"));
  return out;
}

TEST_F(ShakeDemCli, TinyBrazilNutTappedTwiceInLiggghts) {
  if (!btr_test::have_engine("liggghts")) FAIL() << "liggghts is not installed";
  const std::string scene = scene_file("nut", "gamma = 2.5\nfrequency = 40.0\n");
  const fs::path btr_out = dir_ / "btr", dem_out = dir_ / "dem";
  // The same files as dynamic BTR's run, and the same table columns.
  const DemRun run = run_both(scene, "nut", btr_out, dem_out, "", "liggghts", 2, "");
  const auto& rows = run.rows;
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_TRUE(fs::exists(dem_out / "nut_c000002.vtp"));
  double previous_seconds = -1.0;
  for (std::size_t c = 0; c < rows.size(); ++c) {
    ASSERT_EQ(rows[c].size(), 7u);
    EXPECT_EQ(std::stol(rows[c][0]), static_cast<long>(c));
    const double seconds = std::stod(rows[c][1]), intruder_d = std::stod(rows[c][4]);
    EXPECT_GT(seconds, previous_seconds) << "the engine's processor time so far grows, row " << c;
    previous_seconds = seconds;
    EXPECT_TRUE(std::isfinite(intruder_d)) << rows[c][4];
    EXPECT_GT(intruder_d, 1.0) << "the intruder (3 d) rests with its centre above 1 d";  // centre >= 1.5 d
  }

  // Ids kept: the BTR packing's grains (cycle 0 of dynamic BTR), with the intruder as grain 1.
  const double largest_move = check_tapped(btr_out / "nut_c000000.csv", dem_out / "nut_c000000.csv",
                                           dem_out / "nut_c000002.csv", 1.5e-3);
  EXPECT_GT(largest_move, 1e-5) << "two taps moved no grain";

  // The record: the scene's Gamma and frequency, the floor's amplitude, grains thrown up by each tap and at rest
  // after it.
  const nlohmann::json& rec = run.record;
  const nlohmann::json& t = rec["tapping"];
  ASSERT_EQ(t["per_tap"].size(), 2u);
  const double threshold = t["rest"]["kinetic_threshold"].get<double>();
  for (const auto& tap : t["per_tap"]) {
    EXPECT_GT(tap["moved_kinetic_energy"].get<double>(), 100.0 * threshold) << tap.dump();
    EXPECT_TRUE(tap["settled"].get<bool>()) << tap.dump();
    EXPECT_LT(tap["rested_kinetic_energy"].get<double>(), threshold) << tap.dump();
    EXPECT_GT(tap["rest_time"].get<double>(), 0.0);
    EXPECT_GT(tap["engine_cpu_seconds"].get<double>(), 0.0);
  }
  EXPECT_GT(t["engine_cpu_seconds"].get<double>(), 0.0);
  EXPECT_GT(rec["relax"]["engine_cpu_seconds"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(dem_out / "tap" / "btr_tap_floor.stl"));
}

// The YADE tapping of a smaller nut: 80 grains and an intruder of diameter ratio 2 (YADE's periodic cell needs a
// period above 4 largest radii), relaxed briefly and tapped once with a short rest.
TEST_F(ShakeDemCli, TinyBrazilNutTappedOnceInYade) {
  if (!btr_test::have_engine("yade")) FAIL() << "yade is not installed";
  std::string nut = kTinyNut;
  auto set = [&](const std::string& from, const std::string& to) {
    const std::size_t at = nut.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    nut.replace(at, from.size(), to);
  };
  set("count = 120", "count = 80");
  set("diameter_ratio = 3.0", "diameter_ratio = 2.0");
  set("max_time = 0.3", "max_time = 0.1");
  const fs::path scene = dir_ / "ynut.toml";
  std::ofstream(scene) << "[scene]\nname = \"ynut\"\ndimension = 3\nseed = 3\n" << nut << "gamma = 2.5\nfrequency = 40.0\n";
  const fs::path btr_out = dir_ / "ybtr", dem_out = dir_ / "ydem";
  const DemRun run = run_both(scene.string(), "ynut", btr_out, dem_out, "--cycles 1", "yade", 1, "--rest-time 0.05");
  ASSERT_EQ(run.rows.size(), 2u);

  // Ids kept (the intruder is grain 1); after the tap every grain is above the floor and inside the cell.
  EXPECT_EQ(read_packing((btr_out / "ynut_c000000.csv").string()).grains.size(), 81u);
  const double largest_move = check_tapped(btr_out / "ynut_c000000.csv", dem_out / "ynut_c000000.csv",
                                           dem_out / "ynut_c000001.csv", 1.0e-3);
  EXPECT_GT(largest_move, 1e-5) << "the tap moved no grain";

  // The floor's motion as the script measured it on the floor body at every step: one period of A sin(omega t),
  // from z = 0 up to A, down to -A and back to 0; the grains were thrown (kinetic energy when the floor stopped).
  const nlohmann::json& t = run.record["tapping"];
  const double omega = 2.0 * M_PI * 40.0, amplitude = 2.5 * 9.81 / (omega * omega);
  ASSERT_EQ(t["per_tap"].size(), 1u);
  const nlohmann::json& tap = t["per_tap"][0];
  ASSERT_TRUE(tap.contains("floor_measured")) << tap.dump();
  const nlohmann::json& floor = tap["floor_measured"];
  const double dphi = omega * t["timestep"].get<double>();  // the sine sampled at the steps: peak within 1 - dphi^2/8
  EXPECT_LE(floor["highest"].get<double>(), amplitude * (1.0 + 1e-9)) << floor.dump();
  EXPECT_GE(floor["highest"].get<double>(), amplitude * (1.0 - dphi * dphi)) << floor.dump();
  EXPECT_GE(floor["lowest"].get<double>(), -amplitude * (1.0 + 1e-9)) << floor.dump();
  EXPECT_LE(floor["lowest"].get<double>(), -amplitude * (1.0 - dphi * dphi)) << floor.dump();
  EXPECT_NEAR(floor["peak_speed"].get<double>(), amplitude * omega, 1e-3 * amplitude * omega) << floor.dump();
  EXPECT_LT(std::abs(floor["end"].get<double>()), 1e-9 * amplitude) << floor.dump();
  const double threshold = t["rest"]["kinetic_threshold"].get<double>();
  EXPECT_GT(tap["moved_kinetic_energy"].get<double>(), 100.0 * threshold) << tap.dump();
  EXPECT_GT(tap["rest_time"].get<double>(), 0.0);
  EXPECT_GT(tap["engine_cpu_seconds"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(dem_out / "tap" / "yade_tap_1.csv"));
}

// YADE taps 2D disks in a box too: 20 disks and the intruder (ratio 2) between walls 6 mm apart, held in y = 0.
TEST_F(ShakeDemCli, Tiny2dBoxTappedOnceInYade) {
  if (!btr_test::have_engine("yade")) FAIL() << "yade is not installed";
  std::string nut = std::string("[scene]\nname = \"box2d\"\ndimension = 2\nseed = 3\n") + kTinyNut +
                    "gamma = 2.5\nfrequency = 40.0\n";
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"count = 120", "count = 20"},
           {"diameter_ratio = 3.0", "diameter_ratio = 2.0"},
           {"max_time = 0.3", "max_time = 0.1"},
           {"kind = \"periodic\"\nsize = [0.006, 0.006]", "kind = \"box\"\nsize = [0.006]"},
           {"position = [0.0, 0.0]", "position = [0.0]"}}) {
    const std::size_t at = nut.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    nut.replace(at, from.size(), to);
  }
  const fs::path scene = dir_ / "box2d.toml";
  std::ofstream(scene) << nut;
  const fs::path dem_out = dir_ / "box2d_dem";
  const DemRun run =
      run_both(scene.string(), "box2d", dir_ / "box2d_btr", dem_out, "--cycles 1", "yade", 1, "--rest-time 0.05");
  ASSERT_EQ(run.rows.size(), 2u);
  check_tapped(dir_ / "box2d_btr" / "box2d_c000000.csv", dem_out / "box2d_c000000.csv",
               dem_out / "box2d_c000001.csv", 1.0e-3);
  for (const Grain& g : read_packing((dem_out / "box2d_c000001.csv").string()).grains) EXPECT_EQ(g.x.y(), 0.0);
  const nlohmann::json& tap = run.record["tapping"]["per_tap"][0];
  const double amplitude = run.record["tapping"]["amplitude"].get<double>();
  EXPECT_NEAR(tap["floor_measured"]["highest"].get<double>(), amplitude, 1e-3 * amplitude) << tap.dump();
}

TEST_F(ShakeDemCli, BadGammaOrFrequencyIsRefusedNamingTheField) {
  struct Case {
    std::string extra, field;
  };
  const std::vector<Case> cases = {{"gamma = 0.0\n", "gamma"},
                                   {"gamma = -2.0\n", "gamma"},
                                   {"gamma = \"high\"\n", "gamma"},
                                   {"frequency = 0\n", "frequency"},
                                   {"frequency = 1e6\n", "frequency"}};
  int k = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.extra);
    const std::string scene = scene_file("bad" + std::to_string(k), c.extra);
    const fs::path out = dir_ / ("bad_out" + std::to_string(k++));
    const CliRun r = btr("shake " + scene + " -o " + out.string() + " --engine liggghts --taps 1");
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find(scene), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("shaking." + c.field), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "shake_dem.json"));
  }
  // The engine's options without an engine: refused, naming the option.
  const CliRun r = btr("shake " + scene_file("plain", "") + " -o " + (dir_ / "plain").string() + " --taps 3");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--taps"), std::string::npos) << r.err;
}

TEST_F(ShakeDemCli, YadeRefusesACellNarrowerThanFourIntruderRadii) {
  // The tiny nut's intruder has radius 1.5 mm: 4 radii are its 6 mm period, and YADE gives a pair one periodic image
  // only in a wider cell. Refused before any engine runs: exit 2, naming the scene file and the field.
  const std::string scene = scene_file("narrow", "");
  const fs::path out = dir_ / "narrow_out";
  const CliRun r = btr("shake " + scene + " -o " + out.string() + " --engine yade --taps 1");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find(scene), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("container.size"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "shake_dem.json"));
  EXPECT_FALSE(fs::exists(out / "relax" / "relax_yade.py"));
}

TEST_F(ShakeDemCli, AnEngineFailureIsExit5WithItsRecord) {
  if (!btr_test::have_engine("liggghts")) FAIL() << "liggghts is not installed";
  // Killed at a wall-time limit no relaxation can meet: exit 5, the failure record where the engine ran, and no
  // series pretending to be a result.
  const fs::path out = dir_ / "killed";
  const CliRun r = btr("shake " + scene_file("killed", "") + " -o " + out.string() +
                       " --engine liggghts --taps 1 --time-limit 0.02");
  EXPECT_EQ(r.code, 5) << r.out << r.err;
  EXPECT_NE(r.err.find("wall-time limit"), std::string::npos) << r.err;
  const nlohmann::json failure = nlohmann::json::parse(slurp(out / "relax" / "relax_failure.json"));
  EXPECT_EQ(failure["kind"], "time_limit");
  EXPECT_FALSE(fs::exists(out / "killed_cycles.csv"));
  EXPECT_FALSE(fs::exists(out / "shake_dem.json"));
}

}  // namespace
}  // namespace btr
