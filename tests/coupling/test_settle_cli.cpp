// `btr settle` as a user runs it: a tiny 2D bed settled for real in LIGGGHTS and in YADE (ids kept, the cost
// record adds up, the target comes from the calibration and is reached, no overlap beyond the contact law's,
// every grain above the floor, the engine's input of the settled packing written); a tiny 2D heap settled in
// both engines (the calibration is the scene softened, its angle the one chosen, the settled heap near it); and
// the refusals (exit 2, naming the file and the field, nothing written).
#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "btr/measures/metrics.h"
#include "btr/model/number_text.h"
#include "cli_run.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/relax_target.h"
#include "coupling/dem/settle_plan.h"
#include "coupling/io/packing_io.h"
#include "coupling/io/scene_json.h"
#include "relax_fixtures.h"

namespace btr {
namespace {
namespace fs = std::filesystem;

class SettleCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("btr_settle_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static CliRun btr(const std::string& args) { return run_btr(args, dir_); }
  static std::string scene_file(const std::string& name, const std::string& body) {
    const fs::path p = dir_ / (name + ".toml");
    std::ofstream(p) << "[scene]\nname = \"" << name << "\"\n" << body;
    return p.string();
  }
  static fs::path dir_;
};

fs::path SettleCli::dir_;

// 300 disks of radius 0.4-0.5 mm rained into a periodic line 3 cm long: a bed about 10 diameters deep.
const char* kTinyBed = R"(dimension = 2
seed = 4

[grains]
count = 300
density = 2500.0
radius = { distribution = "uniform", min = 0.4e-3, max = 0.5e-3 }

[container]
kind = "periodic"
size = [0.03]

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

TEST_F(SettleCli, TinyBedInLiggghtsAndYade) {
  const std::string scene_path = scene_file("tiny_bed", kTinyBed);
  for (const std::string engine : {"liggghts", "yade"}) {
    SCOPED_TRACE(engine);
    if (!btr_test::have_engine(engine)) {
      ADD_FAILURE() << engine << " is not installed";
      continue;
    }
    const fs::path out = dir_ / ("settle_" + engine);
    const CliRun r = btr("settle " + scene_path + " -o " + out.string() + " --engine " + engine + " --quiet");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const Packing btr_packing = read_packing((out / "btr" / "tiny_bed.csv").string());
    const Packing settled = read_packing((out / "tiny_bed.csv").string());
    const Scene scene = scene_from_json(settled.meta["scene"], "tiny_bed.json");

    // ids kept: grain i of the settled packing is grain i of the BTR packing
    ASSERT_EQ(settled.grains.size(), 300u);
    ASSERT_EQ(btr_packing.grains.size(), 300u);
    for (std::size_t i = 0; i < settled.grains.size(); ++i) {
      EXPECT_EQ(settled.grains[i].r, btr_packing.grains[i].r) << "grain " << i + 1;
      EXPECT_GT(settled.grains[i].x.z(), 0.9 * settled.grains[i].r) << "grain " << i + 1 << " below the floor";
    }
    // no overlap beyond the contact law's: soft grains under ten layers sink in by far less than 1 % of a radius
    EXPECT_LT(largest_overlap(settled.grains, 2, scene.container).largest, 0.01);

    // the record: steps in order, each with its times, the total at least their sum of engine time
    const nlohmann::json rec = nlohmann::json::parse(slurp(out / "settle.json"));
    EXPECT_EQ(rec["engine"], engine);
    ASSERT_EQ(rec["steps"].size(), 4u);
    const char* names[] = {"deposit", "calibration", "relax", "engine input"};
    double steps_cpu = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
      const nlohmann::json& s = rec["steps"][k];
      EXPECT_EQ(s["step"], names[k]);
      EXPECT_GE(s["cpu_seconds"].get<double>(), s["engine_cpu_seconds"].get<double>());
      EXPECT_GT(s["wall_seconds"].get<double>(), 0.0);
      steps_cpu += s["cpu_seconds"].get<double>();
    }
    EXPECT_GT(rec["steps"][1]["engine_cpu_seconds"].get<double>(), 0.0);  // the calibration ran the engine
    EXPECT_GT(rec["steps"][2]["engine_cpu_seconds"].get<double>(), 0.0);
    EXPECT_GE(rec["cpu_seconds"].get<double>(), 0.999 * steps_cpu);

    // the target is the calibration pour's bulk packing fraction (its own poured packing, measured here), a
    // random packing of disks, and the settled bed reaches it
    const nlohmann::json& target = rec["chosen"]["target_phi"];
    EXPECT_EQ(target["from"]["source"], "calibration pour");
    const Packing cal = read_packing((out / "calibration" / "poured.csv").string());
    const Scene cal_scene = scene_from_json(cal.meta["scene"], "poured.json");
    EXPECT_EQ(cal_scene.container.kind, ContainerKind::Periodic);
    EXPECT_EQ(static_cast<std::int64_t>(cal.grains.size()), target["from"]["grains"].get<std::int64_t>());
    const double phi_cal = bulk_packing_fraction(cal.grains, cal_scene, 2.0);
    EXPECT_DOUBLE_EQ(target["value"].get<double>(), phi_cal);
    EXPECT_GT(phi_cal, 0.78);
    EXPECT_LT(phi_cal, 0.88);
    // its precision, from the calibration's own window in blocks: a random packing's blocks differ, by less than
    // the packing fraction itself
    const double se = target["from"]["standard_error"]["value"].get<double>();
    EXPECT_GT(se, 0.0);
    EXPECT_LT(se, 0.05);
    EXPECT_NEAR(bulk_packing_fraction(settled.grains, scene, 2.0), phi_cal, 0.01);
    EXPECT_TRUE(rec["target_phi"]["reached"].get<bool>());

    // the engine's ready-to-run input of the settled packing
    EXPECT_TRUE(fs::exists(out / "dem_input" / (engine == "liggghts" ? "in.btr" : "relax_yade.py")));
    EXPECT_EQ(settled.meta["command"], "settle");
  }
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  return text.replace(text.find(from), from.size(), to);
}

// The tiny bed's disks poured from a point on an open floor, with rolling friction (free disks roll apart
// into a layer one or two grains high): a heap about ten diameters high.
std::string tiny_heap() {
  return replaced(replaced(replaced(kTinyBed, "kind = \"periodic\"\nsize = [0.03]", "kind = \"open\""),
                           "kind = \"rain\"", "kind = \"point\"\nposition = [0.0]\nscatter = 0.5e-3"),
                  "friction = 0.5\n", "friction = 0.5\nrolling_friction = 0.2\n");
}

TEST_F(SettleCli, TinyHeapInLiggghtsAndYade) {
  const std::string scene_path = scene_file("tiny_heap", tiny_heap());
  for (const std::string engine : {"liggghts", "yade"}) {
    SCOPED_TRACE(engine);
    if (!btr_test::have_engine(engine)) {
      ADD_FAILURE() << engine << " is not installed";
      continue;
    }
    const fs::path out = dir_ / ("heap_" + engine);
    const CliRun r = btr("settle " + scene_path + " -o " + out.string() + " --engine " + engine + " --quiet");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    const nlohmann::json rec = nlohmann::json::parse(slurp(out / "settle.json"));
    const char* names[] = {"deposit", "calibration", "heap deposit", "relax", "engine input"};
    ASSERT_EQ(rec["steps"].size(), 5u);
    double steps_cpu = 0.0;
    for (std::size_t k = 0; k < 5; ++k) {
      EXPECT_EQ(rec["steps"][k]["step"], names[k]);
      steps_cpu += rec["steps"][k]["cpu_seconds"].get<double>();
    }
    EXPECT_GT(rec["steps"][1]["engine_cpu_seconds"].get<double>(), 0.0);
    EXPECT_GE(rec["cpu_seconds"].get<double>(), 0.999 * steps_cpu);

    // The calibration is the scene itself, softer: its grains and container, every Young's modulus x the
    // recorded softening, and the angle settle chose is that pour's own flank, fitted here.
    const Packing cal = read_packing((out / "calibration" / "poured.csv").string());
    const Scene cal_scene = scene_from_json(cal.meta["scene"], "poured.json");
    const double softening = rec["chosen"]["angle_deg"]["from"]["softening"]["value"].get<double>();
    EXPECT_GT(softening, 0.0);
    EXPECT_LT(softening, 1.0);  // 5 MPa disks under ten layers overlap far less than the bound: softened
    EXPECT_NEAR(cal_scene.grains.components[0].material.young, 5e6 * softening, 1e-6 * 5e6 * softening);
    EXPECT_EQ(cal_scene.container.kind, ContainerKind::Open);
    const HeapMeasures cal_heap = heap_measures(cal.grains, 2, 0.0, 0.0);
    ASSERT_TRUE(cal_heap.valid) << cal_heap.note;
    const double angle = rec["chosen"]["angle_deg"]["value"].get<double>();
    EXPECT_DOUBLE_EQ(angle, cal_heap.angle_deg);
    EXPECT_GT(angle, 5.0);
    EXPECT_LT(angle, 45.0);  // a poured heap, far below the BTR heap's slope

    // Two rounds of draws: over the calibration's angle, then over that angle less the first round's mean bias
    // (recomputed here from the recorded flanks). The BTR heap kept is the draw of either round whose flank is
    // nearest the calibration's, and it is the one written.
    const nlohmann::json& build = rec["steps"][2];
    ASSERT_EQ(build["rounds"].size(), 2u) << build.dump();
    EXPECT_DOUBLE_EQ(build["rounds"][0]["surface_angle_deg"].get<double>(), angle);
    double sum = 0.0;
    int valid = 0;
    for (const nlohmann::json& a : build["rounds"][0]["draws_angle_deg"])
      if (!a.is_null()) {
        sum += a.get<double>();
        ++valid;
      }
    ASSERT_GT(valid, 0);
    const double bias = sum / valid - angle;
    EXPECT_NEAR(build["correction"]["bias_deg"].get<double>(), bias, 1e-9);
    EXPECT_NEAR(build["rounds"][1]["surface_angle_deg"].get<double>(), angle - bias, 1e-9);
    const double kept = build["built_angle_deg"].get<double>();
    for (const nlohmann::json& round : build["rounds"]) {
      ASSERT_EQ(round["draws_angle_deg"].size(), static_cast<std::size_t>(kHeapDraws));
      for (const nlohmann::json& a : round["draws_angle_deg"])
        if (!a.is_null()) {
          EXPECT_LE(std::abs(kept - angle), std::abs(a.get<double>() - angle) + 1e-12);
        }
    }

    // The settled heap: the BTR heap's grains (same radii in id order, none lost on this small floor), at the
    // scene's own stiffness, standing near the calibrated angle, and far flatter than the plain BTR heap.
    const Packing heap = read_packing((out / "btr_heap" / "tiny_heap.csv").string());
    const Packing plain = read_packing((out / "btr" / "tiny_heap.csv").string());
    const Packing settled = read_packing((out / "tiny_heap.csv").string());
    ASSERT_EQ(settled.grains.size(), heap.grains.size());
    for (std::size_t i = 0; i < settled.grains.size(); ++i) {
      ASSERT_EQ(settled.grains[i].r, heap.grains[i].r) << "grain " << i + 1;
      ASSERT_EQ(heap.grains[i].r, plain.grains[i].r) << "grain " << i + 1;
    }
    const Scene scene = scene_from_json(settled.meta["scene"], "tiny_heap.json");
    EXPECT_LT(largest_overlap(settled.grains, 2, scene.container).largest, 0.01);
    const HeapMeasures settled_heap = heap_measures(settled.grains, 2, 0.0, 0.0);
    const HeapMeasures plain_heap = heap_measures(plain.grains, 2, 0.0, 0.0);
    EXPECT_NEAR(heap_measures(heap.grains, 2, 0.0, 0.0).angle_deg, kept, 1e-9);
    ASSERT_TRUE(settled_heap.valid) << settled_heap.note;
    EXPECT_NEAR(settled_heap.angle_deg, angle, 6.0);
    EXPECT_GT(plain_heap.angle_deg, settled_heap.angle_deg + 10.0);
    EXPECT_NEAR(rec["angle_deg"]["settled"].get<double>(), settled_heap.angle_deg, 1e-9);
    EXPECT_TRUE(fs::exists(out / "dem_input" / (engine == "liggghts" ? "in.btr" : "relax_yade.py")));

    // A relaxation that ran to its max time is recorded as not at rest, with its fastest grain (checked against
    // the engine's final velocities); one stopped by its rule is not.
    const nlohmann::json& relax_step = rec["steps"][3];
    ASSERT_EQ(relax_step.contains("not_at_rest"), relax_step["stop_reason"] == "max-time") << relax_step.dump();
    if (relax_step.contains("not_at_rest")) {
      std::ifstream csv(out / "relax" / "velocities.csv");
      std::string line;
      std::getline(csv, line);
      double fastest = 0.0;
      long fastest_id = 0;
      while (std::getline(csv, line)) {
        long id;
        double vx, vy, vz;
        ASSERT_EQ(std::sscanf(line.c_str(), "%ld,%lf,%lf,%lf", &id, &vx, &vy, &vz), 4) << line;
        const double speed = std::sqrt(vx * vx + vy * vy + vz * vz);
        if (speed > fastest) fastest = speed, fastest_id = id;
      }
      const nlohmann::json& grain = relax_step["not_at_rest"]["fastest_grain"];
      EXPECT_EQ(grain["id"].get<long>(), fastest_id);
      EXPECT_NEAR(grain["speed"].get<double>(), fastest, 1e-12 + 1e-9 * fastest);
    }
  }
}

TEST_F(SettleCli, TargetErrorPoursTheCellAgainUntilTheTargetIsThatPrecise) {
  if (!btr_test::have_engine("liggghts")) {
    ADD_FAILURE() << "liggghts is not installed";
    return;
  }
  const std::string scene_path = scene_file("tiny_bed", kTinyBed);
  const fs::path one = dir_ / "one", more = dir_ / "more";
  fs::create_directories(one / "calibration_3");  // as a previous settle with --target-error would have left it
  std::ofstream(one / "calibration_3" / "poured.csv") << "id,x,y,z,radius,species\n";
  CliRun r = btr("settle " + scene_path + " -o " + one.string() + " --engine liggghts --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_FALSE(fs::exists(one / "calibration_3")) << "a stale calibration folder left beside this run's one pour";
  const nlohmann::json single = nlohmann::json::parse(slurp(one / "settle.json"))["chosen"]["target_phi"];
  const double e1 = single["from"]["standard_error"]["value"].get<double>();
  ASSERT_GT(e1, 0.0);
  EXPECT_FALSE(single["from"].contains("target_error"));  // not asked: one pour

  const double asked = 0.99 * e1;  // more precise than one pour gives
  r = btr("settle " + scene_path + " -o " + more.string() + " --engine liggghts --quiet --target-error " + g17(asked));
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const nlohmann::json rec = nlohmann::json::parse(slurp(more / "settle.json"));
  const nlohmann::json& target = rec["chosen"]["target_phi"];
  const nlohmann::json& asked_for = target["from"]["target_error"];
  const int pours = asked_for["pours"].get<int>();
  ASSERT_GE(pours, 2);
  ASSERT_EQ(asked_for["each"].size(), static_cast<std::size_t>(pours));
  int steps = 0;
  for (const nlohmann::json& step : rec["steps"]) steps += step["step"] == "calibration";
  EXPECT_EQ(steps, pours);  // every pour's cost is in the record

  // the target is the mean of the pours' packing fractions, each measured here from its own packing, at
  // consecutive seeds from the scene's; the first pour is the single-pour run's calibration
  double sum = 0.0;
  for (int k = 0; k < pours; ++k) {
    const std::string folder = k == 0 ? "calibration" : "calibration_" + std::to_string(k + 1);
    const Packing cal = read_packing((more / folder / "poured.csv").string());
    const double phi = bulk_packing_fraction(cal.grains, scene_from_json(cal.meta["scene"], "poured.json"), 2.0);
    EXPECT_EQ(asked_for["each"][k]["seed"].get<std::uint64_t>(), 4u + k) << folder;
    if (k == 0) {
      EXPECT_DOUBLE_EQ(phi, single["value"].get<double>());
    }
    sum += phi;
  }
  EXPECT_NEAR(target["value"].get<double>(), sum / pours, 1e-12);
  // it stopped as soon as the error was small enough, or at the most pours it runs
  const double e = target["from"]["standard_error"]["value"].get<double>();
  if (asked_for["met"].get<bool>()) {
    EXPECT_LE(e, asked);
  } else {
    EXPECT_EQ(pours, asked_for["most_pours"].get<int>());
  }
}

// The tiny bed's disks made very rough (friction 1, rolling friction 0.3, restitution 0.1): their pour stands near
// 0.78 where BTR places them at 0.83. Settle compacts and cannot loosen: it says so (exit 6, the record) and still
// writes the settled packing, instead of handing back BTR's bed as if it were the pour's.
TEST_F(SettleCli, AMaterialThatPoursLooserThanBtrIsReportedNotPassedOff) {
  if (!btr_test::have_engine("liggghts")) {
    ADD_FAILURE() << "liggghts is not installed";
    return;
  }
  const std::string body = replaced(replaced(kTinyBed, "restitution = 0.3", "restitution = 0.1"), "friction = 0.5\n",
                                    "friction = 1.0\nrolling_friction = 0.3\n");
  const std::string scene_path = scene_file("rough_bed", body);
  const fs::path out = dir_ / "rough";
  const CliRun r = btr("settle " + scene_path + " -o " + out.string() + " --engine liggghts --quiet");
  ASSERT_EQ(r.code, 6) << r.out << r.err;
  EXPECT_NE(r.err.find("looser"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(out / "rough_bed.csv"));

  // measured here: the calibration pour's packing fraction and the BTR bed's, each in its own window
  const nlohmann::json rec = nlohmann::json::parse(slurp(out / "settle.json"));
  const nlohmann::json& looser = rec["target_phi"]["looser_than_btr"];
  ASSERT_TRUE(looser.is_object()) << rec["target_phi"].dump();
  EXPECT_FALSE(rec["target_phi"]["reached"].get<bool>());
  const Packing cal = read_packing((out / "calibration" / "poured.csv").string());
  const double phi_cal = bulk_packing_fraction(cal.grains, scene_from_json(cal.meta["scene"], "poured.json"), 2.0);
  const Packing deposit = read_packing((out / "btr" / "rough_bed.csv").string());
  const double margin = rec["chosen"]["target_margin"]["value"].get<double>();
  const double phi_btr =
      bulk_packing_fraction(deposit.grains, scene_from_json(deposit.meta["scene"], "rough_bed.json"), margin);
  const double se = looser["standard_error"].get<double>();
  EXPECT_DOUBLE_EQ(looser["target"].get<double>(), phi_cal);
  EXPECT_DOUBLE_EQ(looser["btr_bulk_packing_fraction"].get<double>(), phi_btr);
  EXPECT_GT(phi_btr, phi_cal + 2.0 * se);
  EXPECT_FALSE(rec["target_phi"]["compaction_ran"].get<bool>());
}

// 400 spheres of radius 0.45-0.5 mm rained into a periodic cell 6 mm square: a bed about 10 diameters deep.
TEST_F(SettleCli, Bed3dCompactsAndSettlesAtTheirOwnStepsAndHandsTheUserTheScenesOwn) {
  if (!btr_test::have_engine("liggghts")) {
    ADD_FAILURE() << "liggghts is not installed";
    return;
  }
  std::string body = replaced(replaced(replaced(kTinyBed, "dimension = 2", "dimension = 3"), "size = [0.03]",
                                       "size = [0.006, 0.006]"),
                              "count = 300", "count = 400");
  body = replaced(body, "min = 0.4e-3, max = 0.5e-3", "min = 0.45e-3, max = 0.5e-3");
  body = replaced(body, "restitution = 0.3", "restitution = 0.5");  // the coarse settle step's (kCoarseSettleMinRestitution)
  const std::string scene_path = scene_file("tiny_bed3d", body);
  const fs::path out = dir_ / "settle3d";
  // a shallow calibration cell (10 diameters wide, about 6 deep): enough for a window, and quick
  const CliRun r = btr("settle " + scene_path + " -o " + out.string() + " --engine liggghts --quiet --calibration-grains 700");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const nlohmann::json rec = nlohmann::json::parse(slurp(out / "settle.json"));
  EXPECT_EQ(rec["chosen"]["timestep_fraction"]["value"].get<double>(), kSettleTimestepFraction3d);
  EXPECT_EQ(rec["chosen"]["compaction_timestep_fraction"]["value"].get<double>(), kLiggghtsCompactionTimestepFraction3d);

  // the compaction ran at its fraction and the settle after it at the settle's, by the same rule
  const nlohmann::json relaxed = nlohmann::json::parse(slurp(out / "relax" / "relaxed.json"));
  const double step = relaxed["relax"]["timestep"].get<double>();
  EXPECT_NEAR(relaxed["target_phi"]["compaction_timestep"].get<double>() / step,
              kLiggghtsCompactionTimestepFraction3d / kSettleTimestepFraction3d, 1e-12);
  // the user's own input keeps the scene's fraction, 0.2: half the step, by the same rule
  std::ifstream in(out / "dem_input" / "in.btr");
  std::string line;
  double user_step = 0.0;
  while (std::getline(in, line))
    if (line.rfind("timestep ", 0) == 0) user_step = std::stod(line.substr(9));
  ASSERT_GT(user_step, 0.0) << "no timestep line in dem_input/in.btr";
  EXPECT_NEAR(step / user_step, kSettleTimestepFraction3d / 0.2, 1e-12);
}

TEST_F(SettleCli, RefusalsNameTheFileAndTheFieldAndWriteNothing) {
  // A 3D region source on an open floor: its heap has no axis for btr measure's angle.
  const std::string region = replaced(replaced(replaced(kTinyBed, "dimension = 2", "dimension = 3"),
                                               "kind = \"periodic\"\nsize = [0.03]", "kind = \"open\""),
                                      "kind = \"rain\"", "kind = \"region\"\nx = [-1e-3, 1e-3]\ny = [-1e-3, 1e-3]");
  const std::string region_path = scene_file("region", region);
  CliRun r = btr("settle " + region_path + " -o " + (dir_ / "r1").string());
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find(region_path), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("source.kind"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("point source"), std::string::npos) << r.err;  // says what to do instead
  EXPECT_FALSE(fs::exists(dir_ / "r1" / "region.csv"));

  // A heap's calibration is the scene's own grains: no count to give.
  r = btr("settle " + scene_file("heap", tiny_heap()) + " -o " + (dir_ / "r2").string() + " --calibration-grains 100");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--calibration-grains"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r2" / "settle.json"));

  r = btr("settle " + scene_file("heap", tiny_heap()) + " -o " + (dir_ / "r4").string() + " --target-error 0.001");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--target-error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r4" / "settle.json"));

  r = btr("settle " + scene_file("few", kTinyBed) + " -o " + (dir_ / "r3").string() + " --calibration-grains 10");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--calibration-grains"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r3" / "settle.json"));
}

}  // namespace
}  // namespace btr
