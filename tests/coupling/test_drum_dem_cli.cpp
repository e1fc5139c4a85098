// `btr drum --engine` as a user runs it: a tiny 2D and 3D drum rotated for real in LIGGGHTS and in YADE (the fill's
// grains and ids kept, the grains on the wall carried round with it in the drum's sense, nobody outside the drum,
// the steps table in the BTR run's columns, drum_dem.json); `btr relax` of a BTR drum snapshot in both engines;
// and the refused speeds (exit 2, naming the file and the field).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_run.h"
#include "coupling/io/packing_io.h"
#include "relax_fixtures.h"

namespace btr {
namespace {
namespace fs = std::filesystem;

class DrumDemCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("btr_drum_dem_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static CliRun btr(const std::string& args) { return run_btr(args, dir_); }
  static fs::path dir_;
};

fs::path DrumDemCli::dir_;

constexpr double kR = 0.005;  // drum radius [m]

// A tiny drum, about half full, turning 10 degrees per BTR step; `drum_extra` goes into [drum].
std::string drum_scene(const fs::path& dir, const std::string& name, int dimension, const std::string& drum_extra) {
  const fs::path p = dir / (name + ".toml");
  std::ofstream(p) << "[scene]\nname = \"" << name << "\"\ndimension = " << dimension << "\nseed = 3\n\n"
                   << "[grains]\ncount = " << (dimension == 2 ? 30 : 45) << "\ndensity = 2500.0\n"
                   << "radius = { distribution = \"uniform\", min = 0.45e-3, max = 0.6e-3 }\n\n"
                   << "[container]\nkind = \"drum\"\nradius = " << kR << "\n"
                   << (dimension == 3 ? "length = 0.003\nends = \"walls\"\n" : "") << "\n"
                   << "[source]\nkind = \"rain\"\n\n"
                   << "[material]\nyoung = 5e6\npoisson = 0.3\nrestitution = 0.3\nfriction = 0.6\n\n"
                   << "[relax]\nmodel = \"hertz\"\nmax_time = 0.5\ntimestep_fraction = 0.2\n\n"
                   << "[drum]\nsteps_per_revolution = 36\nrevolutions = 1\nsnapshot_every = 1\n" << drum_extra;
  return p.string();
}

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

std::vector<std::vector<double>> csv_rows(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) row.push_back(std::strtod(cell.c_str(), nullptr));
    rows.push_back(row);
  }
  return rows;
}

// Angle of a centre about the drum's axis, increasing in the drum's sense (its lowest line moving towards +x).
double axis_angle(const Vec3& x) { return std::atan2(x.z() - kR, x.x()); }

void expect_rotated_drum(const fs::path& out, const std::string& name, int dimension, const std::string& engine,
                         const Packing& fill, const std::string& btr_header) {
  // the steps table: the BTR run's columns, a row per snapshot at 10-degree angles (0, 10, 20, 30)
  EXPECT_EQ(first_line(out / (name + "_steps.csv")), btr_header);
  const auto rows = csv_rows(out / (name + "_steps.csv"));
  ASSERT_EQ(rows.size(), 4u);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k][0], static_cast<double>(k));
    EXPECT_NEAR(rows[k][1], 10.0 * k, 1e-9);
    if (k > 0) {
      EXPECT_GT(rows[k][3], rows[k - 1][3]) << "cpu_seconds grows";
    }
  }
  const nlohmann::json rec = nlohmann::json::parse(slurp(out / "drum_dem.json"));
  EXPECT_EQ(rec["engine"], engine);
  EXPECT_EQ(rec["speed_source"], "drum.froude");
  EXPECT_NEAR(rec["froude"].get<double>(), 0.02, 1e-12);
  EXPECT_NEAR(rec["revolutions_turned"].get<double>(), 30.0 / 360.0, 1e-12);
  // simulated time = angle / omega, within a time step
  EXPECT_NEAR(rec["simulated_time"].get<double>(), (M_PI / 6.0) / rec["omega"].get<double>(),
              1.5 * rec["timestep"].get<double>());
  EXPECT_GT(rec["engine_cpu_seconds_per_revolution"].get<double>(), rec["engine_cpu_seconds"].get<double>());

  const Packing start = read_packing((out / (name + "_s000000.csv")).string());
  const Packing last = read_packing((out / (name + "_s000003.csv")).string());
  ASSERT_EQ(start.grains.size(), fill.grains.size());
  ASSERT_EQ(last.grains.size(), fill.grains.size());
  double moved = 0.0;
  int on_wall = 0;
  for (std::size_t i = 0; i < fill.grains.size(); ++i) {
    for (const Packing* p : {&start, &last}) {  // ids kept: grain i is the fill's grain i
      EXPECT_EQ(p->grains[i].r, fill.grains[i].r) << "grain " << i + 1;
      EXPECT_EQ(p->grains[i].species, fill.grains[i].species) << "grain " << i + 1;
      const Grain& g = p->grains[i];
      // nobody outside the drum (a contact's overlap is allowed, well below half a radius)
      EXPECT_GT(kR - std::hypot(g.x.x(), g.x.z() - kR), 0.5 * g.r) << "grain " << i + 1;
      if (dimension == 3) EXPECT_LT(std::abs(g.x.y()), 0.0015 - 0.5 * g.r) << "grain " << i + 1;
      else EXPECT_EQ(g.x.y(), 0.0) << "grain " << i + 1;
    }
    const Grain& g0 = start.grains[i];
    if (kR - std::hypot(g0.x.x(), g0.x.z() - kR) - g0.r < 0.02 * g0.r) {  // touching the wall at the start
      moved += axis_angle(last.grains[i].x) - axis_angle(g0.x);
      ++on_wall;
    }
  }
  ASSERT_GE(on_wall, 4) << "grains touching the drum at the start";
  const double mean_deg = moved / on_wall * 180.0 / M_PI;
  // carried round with the wall (30 degrees), in its sense: a sizable fraction of it, and not beyond it
  EXPECT_GT(mean_deg, 0.5 * 30.0) << engine;
  EXPECT_LT(mean_deg, 1.1 * 30.0) << engine;
}

// The dynamic BTR run of a tiny drum gives the fill (its step 0) and the table's columns; the DEM run turns the
// same drum by 30 degrees (3 BTR steps of 10 degrees) at Froude 0.02.
void turn_tiny_drum(const fs::path& dir, int dimension, const std::string& engine) {
  if (!btr_test::have_engine(engine)) GTEST_FAIL() << engine << " is not installed";
  const std::string name = "tiny_drum" + std::to_string(dimension) + "d";
  const std::string scene = drum_scene(dir, name, dimension, "froude = 0.02\n");
  const fs::path btr_out = dir / (name + "_btr_" + engine);
  const CliRun b = run_btr("drum " + scene + " -o " + btr_out.string() + " --steps 1 --quiet", dir);
  ASSERT_EQ(b.code, 0) << b.err;
  const Packing fill = read_packing((btr_out / (name + "_s000000.csv")).string());
  const std::string header = first_line(btr_out / (name + "_steps.csv"));
  const fs::path out = dir / (name + "_" + engine);
  const CliRun r = run_btr("drum " + scene + " -o " + out.string() + " --engine " + engine + " --revolutions " +
                               std::to_string(3.0 / 36.0) + " --settle-max-time 0.05 --time-limit 300",
                           dir);
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  expect_rotated_drum(out, name, dimension, engine, fill, header);
}

TEST_F(DrumDemCli, Tiny2dDrumTurnsInLiggghts) { turn_tiny_drum(dir_, 2, "liggghts"); }
TEST_F(DrumDemCli, Tiny3dDrumTurnsInLiggghts) { turn_tiny_drum(dir_, 3, "liggghts"); }
TEST_F(DrumDemCli, Tiny2dDrumTurnsInYade) { turn_tiny_drum(dir_, 2, "yade"); }
// No 3D drum in YADE here: its 2016 facets (256 panels and the end discs, for grains of R / 11) are moved, bounded
// and sorted at every step, 4.5 ms per step: 67 s of processor time for this 30-degree turn (docs/guide/drum_dem.md).

// `btr relax` of a BTR drum snapshot (step 2) in the still drum: accepted, every grain kept and inside the drum,
// nobody carried far.
void relax_drum_snapshot(const fs::path& dir, int dimension, const std::string& engine) {
  if (!btr_test::have_engine(engine)) GTEST_FAIL() << engine << " is not installed";
  const std::string name = "relax_drum" + std::to_string(dimension) + "d";
  const std::string scene = drum_scene(dir, name, dimension, "");
  const fs::path btr_out = dir / (name + "_btr_" + engine);
  const CliRun b = run_btr("drum " + scene + " -o " + btr_out.string() + " --steps 2 --quiet", dir);
  ASSERT_EQ(b.code, 0) << b.err;
  const Packing snap = read_packing((btr_out / (name + "_s000002.csv")).string());
  const fs::path out = dir / (name + "_relax_" + engine);
  const CliRun r = run_btr("relax " + (btr_out / (name + "_s000002.csv")).string() + " -o " + out.string() +
                               " --engine " + engine + " --max-time 0.05 --time-limit 300",
                           dir);
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const Packing relaxed = read_packing((out / "relaxed.csv").string());
  ASSERT_EQ(relaxed.grains.size(), snap.grains.size());
  for (std::size_t i = 0; i < snap.grains.size(); ++i) {
    const Grain& g = relaxed.grains[i];
    EXPECT_EQ(g.r, snap.grains[i].r);
    EXPECT_GT(kR - std::hypot(g.x.x(), g.x.z() - kR), 0.5 * g.r) << "grain " << i + 1;
    EXPECT_LT((g.x - snap.grains[i].x).norm(), 2.0 * g.r) << "grain " << i + 1;  // a settle, not a rotation
  }
}

TEST_F(DrumDemCli, RelaxOf2dDrumSnapshotInLiggghts) { relax_drum_snapshot(dir_, 2, "liggghts"); }
TEST_F(DrumDemCli, RelaxOf3dDrumSnapshotInLiggghts) { relax_drum_snapshot(dir_, 3, "liggghts"); }
TEST_F(DrumDemCli, RelaxOf2dDrumSnapshotInYade) { relax_drum_snapshot(dir_, 2, "yade"); }

TEST_F(DrumDemCli, BadSpeedsAreRefused) {
  struct Case {
    std::string drum, field;
  };
  // rpm 1000 in a 5 mm drum: Froude 5.6, the grains would centrifuge
  for (const Case& c : {Case{"froude = 1.5\n", "drum.froude"}, Case{"froude = 0\n", "drum.froude"},
                        Case{"rpm = -3\n", "drum.rpm"}, Case{"rpm = 1000\n", "drum.rpm"},
                        Case{"rpm = 10\nfroude = 0.01\n", "drum.froude"}}) {
    SCOPED_TRACE(c.drum);
    const std::string scene = drum_scene(dir_, "bad_speed", 2, c.drum);
    const CliRun r = btr("drum " + scene + " -o " + (dir_ / "bad_speed").string() + " --engine liggghts");
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find(scene), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.field), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "bad_speed" / "relax")) << "refused before any engine ran";
  }
}

}  // namespace
}  // namespace btr
