// `btr deposit` and `btr bench` as a user runs them: files, metadata, determinism, exit codes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "coupling/io/packing_io.h"
#include "coupling/io/scene_json.h"
#include "cli_run.h"

namespace btr {
namespace {
namespace fs = std::filesystem;

const fs::path& scratch() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / ("btr_deposit_cli_" + std::to_string(::getpid()));
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

CliRun btr(const std::string& args) { return run_btr(args, scratch()); }

const std::string kHeap = std::string(BTR_SOURCE_DIR) + "/inputs/heap2d.toml";

TEST(DepositCli, WritesThePackingWithItsMetadata) {
  const fs::path dir = scratch() / "a" / "b";  // created if missing
  const CliRun r = btr("deposit " + kHeap + " -o " + dir.string() + " --count 400 --seed 7 --check");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("heap2d: 400 grains"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("angle of repose"), std::string::npos) << r.out;
  const Packing p = read_packing((dir / "heap2d.csv").string());
  ASSERT_EQ(p.grains.size(), 400u);
  EXPECT_TRUE(fs::exists(dir / "heap2d.vtp"));
  for (const Grain& g : p.grains) EXPECT_EQ(g.x.y(), 0.0);  // 2D: the x-z plane
  const nlohmann::json& m = p.meta;
  EXPECT_EQ(m["scene_name"], "heap2d");
  EXPECT_EQ(m["scene_file"], kHeap);
  EXPECT_EQ(m["seed"], 7);
  EXPECT_EQ(m["dimension"], 2);
  EXPECT_EQ(m["count"], 400);
  EXPECT_EQ(m["counts"]["1"], 400);
  EXPECT_EQ(m["container"]["kind"], "open");
  EXPECT_FALSE(m["version"].get<std::string>().empty());
  for (const char* stage : {"deposition", "check", "writing"}) EXPECT_GT(m["timings"][stage].get<double>(), 0.0) << stage;
  EXPECT_EQ(m["check"]["ok"], true);
  EXPECT_TRUE(m["measures"]["heap"]["valid"].get<bool>());
  EXPECT_EQ(m["measures"]["bulk"]["contact_tolerance"], 1e-7);  // the definition travels with the numbers
  // the stored scene rebuilds this run: it carries the seed and count actually used
  const Scene s = scene_from_json(m["scene"], "meta");
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.grains.count, 400);
  EXPECT_EQ(s.dimension, 2);
}

TEST(DepositCli, SameSeedSameBytesOtherSeedOtherPacking) {
  const fs::path dir = scratch() / "det";
  ASSERT_EQ(btr("deposit " + kHeap + " -o " + dir.string() + " --count 300 --name one -q").code, 0);
  ASSERT_EQ(btr("deposit " + kHeap + " -o " + dir.string() + " --count 300 --name two -q").code, 0);
  ASSERT_EQ(btr("deposit " + kHeap + " -o " + dir.string() + " --count 300 --name three --seed 99 -q").code, 0);
  EXPECT_EQ(slurp(dir / "one.csv"), slurp(dir / "two.csv"));
  EXPECT_NE(slurp(dir / "one.csv"), slurp(dir / "three.csv"));
}

TEST(DepositCli, QuietPrintsNothing) {
  const CliRun r = btr("deposit " + kHeap + " -o " + (scratch() / "q").string() + " --count 50 --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "");
}

TEST(DepositCli, ExitCodes) {
  // bad scene file: 2, and the message names the file
  const fs::path bad = scratch() / "bad.toml";
  {
    std::ofstream f(bad);
    f << slurp(kHeap) << "\n[typo]\nx = 1\n";
  }
  CliRun r = btr("deposit " + bad.string() + " -o " + (scratch() / "x").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
  // bad options: 2
  EXPECT_EQ(btr("deposit " + kHeap + " -o " + (scratch() / "x").string() + " --count 0").code, 2);
  EXPECT_EQ(btr("deposit " + kHeap).code, 2);                   // no -o
  EXPECT_EQ(btr("deposit /no/such/scene.toml -o x").code, 2);
  // the output folder cannot be created (a file is in the way): 3
  const fs::path file = scratch() / "plain_file";
  std::ofstream(file) << "x";
  r = btr("deposit " + kHeap + " -o " + (file / "sub").string() + " --count 20");
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("plain_file"), std::string::npos) << r.err;
}

// --forces: NAME.forces.csv beside the packing (header i,j,fx,fy,fz; %.17g, so the rows are exact),
// the floor carrying the weight computed independently from the packing's radii and the scene's
// density, byte-identical across runs, and the .vtp with one line per contact.
TEST(DepositCli, ForcesFileBalancesTheWeight) {
  const fs::path dir = scratch() / "forces";
  const std::string bed = std::string(BTR_SOURCE_DIR) + "/inputs/bed3d.toml";
  const CliRun r = btr("deposit " + bed + " -o " + dir.string() + " --count 500 --forces");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("forces: "), std::string::npos) << r.out;
  const Packing p = read_packing((dir / "bed3d.csv").string());
  double weight = 0.0;
  for (const Grain& g : p.grains) weight += 4.0 / 3.0 * M_PI * g.r * g.r * g.r * 2500.0 * 9.81;
  std::ifstream in(dir / "bed3d.forces.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "i,j,fx,fy,fz");
  double floor = 0.0;
  std::size_t rows = 0;
  std::set<std::pair<long, long>> seen;
  while (std::getline(in, line)) {
    long i = 0, j = 0;
    double f[3];
    ASSERT_EQ(std::sscanf(line.c_str(), "%ld,%ld,%lf,%lf,%lf", &i, &j, f, f + 1, f + 2), 5) << line;
    EXPECT_GE(i, 1);
    EXPECT_LE(i, 500);
    EXPECT_LT(j, i);
    EXPECT_GE(j, 0);  // a periodic bed has a floor and no side walls
    EXPECT_TRUE(seen.insert({i, j}).second) << "contact listed twice: " << line;
    if (j == 0) floor += f[2];
    ++rows;
  }
  EXPECT_GT(rows, 500u);
  // The floor carries the weight, plus the small upward load of "lifted" grains (force_network.h).
  EXPECT_GE(floor, weight * (1 - 1e-9));
  EXPECT_LT(floor, weight * 1.1);
  const std::string vtp = slurp(dir / "bed3d.forces.vtp");
  EXPECT_NE(vtp.find("NumberOfLines=\"" + std::to_string(rows) + "\""), std::string::npos);
  ASSERT_EQ(btr("deposit " + bed + " -o " + dir.string() + " --count 500 --forces --name again -q").code, 0);
  EXPECT_EQ(slurp(dir / "bed3d.forces.csv"), slurp(dir / "again.forces.csv"));
}

TEST(MeasureCli, SameMeasuresAsTheDepositAndNamedOptions) {
  const fs::path dir = scratch() / "measure";
  ASSERT_EQ(btr("deposit " + kHeap + " -o " + dir.string() + " --count 400 -q").code, 0);
  const fs::path csv = dir / "heap2d.csv";
  const CliRun r = btr("measure " + csv.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json measured = nlohmann::json::parse(r.out);
  const nlohmann::json stored = nlohmann::json::parse(slurp(dir / "heap2d.json"))["measures"];
  EXPECT_EQ(measured, stored);  // one definition: the deposit stored exactly what `btr measure` computes
  // options change the numbers and are named next to them
  const CliRun wide = btr("measure " + csv.string() + " --margin 2 --contact-tolerance 0.01 -o " +
                          (dir / "m.json").string() + " --per-grain " + (dir / "g.csv").string());
  ASSERT_EQ(wide.code, 0) << wide.err;
  const nlohmann::json m = nlohmann::json::parse(slurp(dir / "m.json"));
  EXPECT_EQ(m["bulk"]["window_margin_diameters"], 2.0);
  EXPECT_EQ(m["bulk"]["contact_tolerance"], 0.01);
  EXPECT_GE(m["mean_coordination_all_grains"].get<double>(), stored["mean_coordination_all_grains"].get<double>());
  std::istringstream rows(slurp(dir / "g.csv"));
  std::string line;
  int n = 0;
  std::getline(rows, line);
  EXPECT_EQ(line, "id,coordination,in_window,surface_depth");
  while (std::getline(rows, line)) ++n;
  EXPECT_EQ(n, 400);
  // bad input: a packing without its JSON, and a negative margin
  fs::copy_file(csv, dir / "alone.csv");
  const CliRun alone = btr("measure " + (dir / "alone.csv").string());
  EXPECT_EQ(alone.code, 2);
  EXPECT_NE(alone.err.find((dir / "alone.json").string()), std::string::npos) << alone.err;
  const CliRun negative = btr("measure " + csv.string() + " --margin -1");
  EXPECT_EQ(negative.code, 2);
  EXPECT_NE(negative.err.find("--margin"), std::string::npos) << negative.err;
}

TEST(BenchCli, PrintsATableAndTheExponent) {
  const CliRun r = btr("bench --sizes 200,400 --scenes heap2d");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("heap2d          200"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("heap2d          400"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("exponent"), std::string::npos) << r.out;
  EXPECT_EQ(btr("bench --sizes 2.5").code, 2);
}

}  // namespace
}  // namespace btr
