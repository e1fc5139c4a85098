// Engine-independent parts of the relaxation: overlaps, stop threshold, plan refusals, the process
// runner, and relax.cpp's checks of whatever an engine returns (through a fake engine).
#include <gtest/gtest.h>

#include <signal.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>

#include "coupling/dem/overlap.h"
#include "coupling/dem/process.h"
#include "coupling/dem/relax.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/engines.h"
#include "relax_fixtures.h"

namespace fs = std::filesystem;
using btr::ContainerKind;
using btr_test::container;

namespace {

btr::Grain grain(double x, double y, double z, double r) {
  btr::Grain g;
  g.x = btr::Vec3(x, y, z);
  g.r = r;
  return g;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

// ---- overlaps ----

TEST(Overlap, AcrossThePeriodicBoundary) {
  const btr::Container c = container(ContainerKind::Periodic, 0.01, 0.01);
  // 0.2 mm apart through the boundary x = +-5 mm; radii 0.2 and 0.1 mm: overlap 0.1 mm = 1.0 x 0.1 mm
  const btr::Grains g{grain(-0.0049, 0, 0.0002, 0.0002), grain(0.0049, 0, 0.0002, 0.0001)};
  const btr::OverlapReport rep = btr::largest_overlap(g, 3, c);
  EXPECT_NEAR(rep.largest, 1.0, 1e-9);
  EXPECT_NEAR(rep.depth, 1e-4, 1e-13);
  EXPECT_EQ(rep.id_a, 1);
  EXPECT_EQ(rep.id_b, 2);
  EXPECT_EQ(rep.count, 1);
  // on an open floor the same two grains are far apart
  EXPECT_EQ(btr::largest_overlap(g, 3, container(ContainerKind::Open)).count, 0);
}

TEST(Overlap, Walls) {
  const double r = 1e-3;
  {  // box side wall at x = +5 mm, grain 0.1 r into it; floor exactly touched (no overlap)
    const btr::OverlapReport rep =
        btr::largest_overlap({grain(0.005 - 0.9 * r, 0, r, r)}, 3, container(ContainerKind::Box, 0.01, 0.01));
    EXPECT_NEAR(rep.largest, 0.1, 1e-9);
    EXPECT_EQ(rep.id_b, 0);
    EXPECT_EQ(rep.wall, "x+");
  }
  {  // cylinder R = 5 mm, grain centre at 5 mm - 0.95 r on the diagonal
    const double rho = 0.005 - 0.95 * r;
    const btr::OverlapReport rep = btr::largest_overlap({grain(rho / std::sqrt(2.0), rho / std::sqrt(2.0), 2 * r, r)}, 3,
                                                        container(ContainerKind::Cylinder, 0.005));
    EXPECT_NEAR(rep.largest, 0.05, 1e-9);
    EXPECT_EQ(rep.wall, "cylinder");
  }
  {  // Hele-Shaw plate at y = -1.5 mm; floor 0.2 r deep is the larger one
    const btr::OverlapReport rep = btr::largest_overlap({grain(0, -0.0015 + 0.97 * r, 0.8 * r, r)}, 3,
                                                        container(ContainerKind::HeleShaw, 0.02, 0.003));
    EXPECT_NEAR(rep.largest, 0.2, 1e-9);
    EXPECT_EQ(rep.wall, "floor");
    EXPECT_EQ(rep.count, 2);
  }
}

// The grid search finds exactly what a brute-force search over all pairs finds.
TEST(Overlap, GridAgreesWithBruteForce) {
  for (ContainerKind kind : {ContainerKind::Periodic, ContainerKind::Open}) {
    const btr::Container c = container(kind, 0.01, 0.008);
    btr_test::Rng rng(42);
    btr::Grains g;
    for (int i = 0; i < 600; ++i)
      g.push_back(grain(rng.uniform(-0.005, 0.005), rng.uniform(-0.004, 0.004), rng.uniform(0.001, 0.006),
                        rng.uniform(0.0002, 0.0006)));
    double worst = 0;
    long count = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
      if (g[i].x.z() < g[i].r) ++count, worst = std::max(worst, 1 - g[i].x.z() / g[i].r);
      for (std::size_t j = i + 1; j < g.size(); ++j) {
        btr::Vec3 d = g[j].x - g[i].x;
        if (kind == ContainerKind::Periodic) {
          d.x() -= 0.01 * std::round(d.x() / 0.01);
          d.y() -= 0.008 * std::round(d.y() / 0.008);
        }
        const double depth = g[i].r + g[j].r - d.norm();
        if (depth > 0) ++count, worst = std::max(worst, depth / std::min(g[i].r, g[j].r));
      }
    }
    const btr::OverlapReport rep = btr::largest_overlap(g, 3, c);
    EXPECT_EQ(rep.count, count) << btr::to_string(kind);
    EXPECT_NEAR(rep.largest, worst, 1e-12) << btr::to_string(kind);
    EXPECT_GT(count, 100);
  }
}

// ---- stop threshold and plan ----

TEST(Plan, KineticThresholdByHand) {
  btr::Scene s = btr_test::make_scene("k", 3, container(ContainerKind::Periodic));
  s.relax.stop_kinetic_ratio = 1e-6;
  const btr::Grains g{grain(0, 0, 1e-3, 1e-3), grain(0.005, 0, 2e-3, 2e-3)};
  // m = 4/3 pi r^3 2500: 1.0471976e-5 and 8.3775804e-5 kg; sum m g d = 2.05460e-7 + 3.28736e-6 J
  EXPECT_NEAR(btr::kinetic_threshold(g, s), 1e-6 * (2.0546017e-7 + 3.2873627e-6), 1e-18);
}

TEST(Plan, RequestedTimestepAboveTheStableOneIsRefusedWithTheStableValue) {
  btr::Scene s = btr_test::make_scene("ts", 3, container(ContainerKind::Periodic));
  const btr::Packing p = btr_test::layered_packing(s, 40, 1);
  const btr::RelaxPlan free_plan = btr::make_plan(p, s, {}, "liggghts");
  const double stable = free_plan.timestep;
  char stable_text[32];
  std::snprintf(stable_text, sizeof stable_text, "%.6g", stable);

  btr::RelaxSettings too_big;
  too_big.timestep = 1.01 * stable;
  try {
    btr::make_plan(p, s, too_big, "liggghts");
    FAIL() << "accepted a step above the stable one";
  } catch (const btr::RelaxRefused& e) {
    EXPECT_NE(std::string(e.what()).find(stable_text), std::string::npos) << e.what();
  }
  btr::RelaxSettings fine;
  fine.timestep = 0.5 * stable;
  EXPECT_EQ(btr::make_plan(p, s, fine, "liggghts").timestep, 0.5 * stable);
  s.relax.timestep = 0.25 * stable;  // the scene may ask too; the command line wins
  EXPECT_EQ(btr::make_plan(p, s, {}, "liggghts").timestep, 0.25 * stable);
  EXPECT_EQ(btr::make_plan(p, s, fine, "liggghts").timestep, 0.5 * stable);
  s.relax.timestep = 2 * stable;
  EXPECT_THROW(btr::make_plan(p, s, {}, "liggghts"), btr::RelaxRefused);
}

TEST(Plan, OverlapLimitAndOtherRefusals) {
  btr::Scene s = btr_test::make_scene("ov", 3, container(ContainerKind::Box, 0.01, 0.01));
  btr::Packing p;
  p.grains = {grain(0, 0, 1e-3, 1e-3), grain(1.96e-3, 0, 1e-3, 1e-3)};  // overlap 0.04 r
  EXPECT_NEAR(btr::make_plan(p, s, {}, "liggghts").largest_overlap, 0.04, 1e-9);
  btr::RelaxSettings strict;
  strict.max_overlap = 0.03;
  EXPECT_THROW(btr::make_plan(p, s, strict, "liggghts"), btr::RelaxRefused);
  p.grains[1].species = 7;
  EXPECT_THROW(btr::make_plan(p, s, {}, "liggghts"), btr::RelaxRefused);  // a species the scene does not have
  p.grains[1].species = 1;
  btr::Scene flat = btr_test::make_scene("2d", 2, container(ContainerKind::Box, 0.01));
  EXPECT_NO_THROW(btr::make_plan(p, flat, {}, "liggghts"));  // disks in y = 0
  p.grains[1].x.y() = 1e-9;
  EXPECT_THROW(btr::make_plan(p, flat, {}, "liggghts"), btr::RelaxRefused);
  EXPECT_THROW(btr::make_adapter("lammps"), btr::RelaxRefused);
}

// ---- process runner ----

TEST(Process, ExitStatusOutputEnvironmentAndFolder) {
  const std::string dir = btr_test::fresh_dir("process");
  btr::EngineCommand c;
  c.argv = {"sh", "-c", "echo out $BTR_TEST_VAR; echo err >&2; pwd; exit 3"};
  c.env["BTR_TEST_VAR"] = "hello";
  const btr::ProcessOutcome o = btr::run_process(c, dir, 10, dir + "/out.txt");
  EXPECT_TRUE(o.started);
  EXPECT_EQ(o.exit_code, 3);
  EXPECT_FALSE(o.ok());
  const std::string out = read_text(dir + "/out.txt");
  EXPECT_NE(out.find("out hello"), std::string::npos) << out;
  EXPECT_NE(out.find("err"), std::string::npos) << out;
  EXPECT_NE(out.find(fs::canonical(dir).string()), std::string::npos) << out;
  EXPECT_EQ(btr::tail_lines(dir + "/out.txt", 1), fs::canonical(dir).string() + "\n");
}

TEST(Process, TimeLimitKillsTheWholeGroup) {
  const std::string dir = btr_test::fresh_dir("timeout");
  btr::EngineCommand c;
  // The background sleep is the group's other member: it must be gone too, not only the shell.
  c.argv = {"sh", "-c", "sleep 30 & echo $! > bg.pid; sleep 30; echo never"};
  const btr::ProcessOutcome o = btr::run_process(c, dir, 0.5, dir + "/out.txt");
  EXPECT_TRUE(o.timed_out);
  EXPECT_FALSE(o.ok());
  EXPECT_EQ(read_text(dir + "/out.txt").find("never"), std::string::npos);
  const pid_t background = static_cast<pid_t>(std::stol(read_text(dir + "/bg.pid")));
  EXPECT_NE(::kill(background, 0), 0) << "the background member of the group survived";
}

TEST(Process, MissingProgram) {
  const std::string dir = btr_test::fresh_dir("missing");
  btr::EngineCommand c;
  c.argv = {"btr-no-such-program"};
  const btr::ProcessOutcome o = btr::run_process(c, dir, 5, dir + "/out.txt");
  EXPECT_FALSE(o.started);
  EXPECT_NE(o.describe().find("btr-no-such-program"), std::string::npos) << o.describe();
}

// ---- relax.cpp's checks, with a fake engine ----

namespace {

// An engine whose command and result the test chooses.
class FakeAdapter : public btr::EngineAdapter {
 public:
  std::string shell = "echo 'all good' > fake.log";
  std::function<btr::RelaxResult(const btr::Packing&)> result;
  // What the engine's own outputs report after a non-zero exit (none unless set).
  std::function<std::optional<btr::EngineFailure>()> after_exit;

  std::vector<std::string> write_inputs(const btr::Packing&, const btr::Scene&, const btr::RelaxSettings&,
                                        const btr::RelaxPlan&, const std::string& dir) const override {
    std::ofstream(dir + "/fake.in") << "fake\n";
    return {dir + "/fake.in"};
  }
  btr::EngineCommand command(const std::string&, const btr::RelaxSettings&) const override {
    btr::EngineCommand c;
    c.argv = {"sh", "-c", shell};
    return c;
  }
  std::string log_file(const std::string& dir) const override { return dir + "/fake.log"; }
  btr::RelaxResult read_back(const std::string&, const btr::Packing& original, const btr::Scene&,
                             const btr::RelaxPlan&) const override {
    return result(original);
  }
  std::optional<btr::EngineFailure> failure_after_exit(const std::string&, const btr::Packing&, const btr::Scene&,
                                                       const btr::RelaxPlan&) const override {
    return after_exit ? after_exit() : std::nullopt;
  }
};

struct FakeRun {
  btr::Scene scene = btr_test::make_scene("fake", 3, container(ContainerKind::Periodic, 0.02, 0.02));
  btr::Packing packing = btr_test::layered_packing(scene, 60, 3);
  std::string dir;
  FakeAdapter adapter;
  btr::RelaxSettings settings;

  explicit FakeRun(const std::string& name) : dir(btr_test::fresh_dir(name)) {
    adapter.result = [](const btr::Packing& p) {
      btr::RelaxResult r;
      r.relaxed = p;
      for (btr::Grain& g : r.relaxed.grains) g.x.z() -= 1e-5;
      r.stop_reason = "kinetic-energy";
      r.simulated_time = 0.1;
      r.kinetic_history = {{0.0, 0.0}, {0.05, 1e-9}, {0.1, 1e-15}};
      r.contacts = {{2, 1, 0.5}, {1, 0, 0.25}};
      return r;
    };
  }
  btr::RelaxResult run() {
    const btr::RelaxPlan plan = btr::make_plan(packing, scene, settings, "liggghts");
    btr::write_engine_inputs(packing, scene, adapter, settings, plan, dir);
    return btr::run_engine_inputs(packing, scene, adapter, "fake", settings, plan, dir);
  }
  nlohmann::json record;  // the relax_failure.json of the last failure()
  // Runs, expects an EngineFailure of this kind, reads its relax_failure.json into `record`; returns the message.
  std::string failure(btr::FailureKind kind) {
    const bool earlier_result = fs::exists(dir + "/relaxed.csv");  // an earlier run's, into the same folder
    try {
      run();
    } catch (const btr::EngineFailure& e) {
      if (!earlier_result) {
        EXPECT_FALSE(fs::exists(dir + "/relaxed.csv")) << "a failed run is never a result";
      }
      EXPECT_EQ(btr::failure_kind_name(e.kind()), std::string(btr::failure_kind_name(kind))) << e.what();
      record = nlohmann::json::parse(read_text(dir + "/" + btr::kRelaxFailureFile));
      EXPECT_EQ(record["kind"], btr::failure_kind_name(kind));
      EXPECT_EQ(record["engine"], "fake");
      EXPECT_EQ(record["log"], "fake.log");
      EXPECT_EQ(record["values"], e.values());
      // The record's message is why, without the log tails the exception's message carries.
      EXPECT_NE(std::string(e.what()).find(record["message"].get<std::string>()), std::string::npos);
      EXPECT_EQ(record["message"].get<std::string>().find("last lines of"), std::string::npos);
      return e.what();
    }
    ADD_FAILURE() << "the run was accepted";
    return "";
  }
};

}  // namespace

TEST(RelaxChecks, SuccessWritesTheOutputs) {
  FakeRun f("fake_ok");
  // a grain that crossed the periodic boundary comes back wrapped into [-L/2, L/2)
  f.adapter.result = [inner = f.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.relaxed.grains[0].x.x() = 0.0101;
    return r;
  };
  const btr::RelaxResult r = f.run();
  EXPECT_NEAR(r.relaxed.grains[0].x.x(), -0.0099, 1e-15);
  const btr::Packing out = btr::read_packing(f.dir + "/relaxed.csv");
  ASSERT_EQ(out.grains.size(), f.packing.grains.size());
  EXPECT_EQ(out.meta["relax"]["stop_reason"], "kinetic-energy");
  EXPECT_EQ(out.meta["relax"]["engine"], "fake");
  EXPECT_TRUE(out.meta.contains("scene"));
  EXPECT_EQ(read_text(f.dir + "/kinetic.csv"), "time,kinetic_energy\n0,0\n0.050000000000000003,1.0000000000000001e-09\n"
                                               "0.10000000000000001,1.0000000000000001e-15\n");
  EXPECT_EQ(read_text(f.dir + "/contacts.csv"), "id1,id2,normal_force\n1,0,0.25\n2,1,0.5\n");
  EXPECT_TRUE(fs::exists(f.dir + "/relaxed.vtp"));
}

TEST(RelaxChecks, FinalOverlapsInRelaxedJson) {
  // Three grains placed by hand in the relaxed result: grain 1 (r 1 mm) 0.03 r into the floor, grain 2
  // (r 0.5 mm) 0.02 r into it, grain 3 (r 0.5 mm) on grain 1 with a pair overlap of 0.1 of the smaller
  // radius: the floor overlap is 0.03 of grain 1's radius, the largest overlap the pair's 0.1.
  FakeRun f("fake_floor_overlap");
  f.packing.grains = {grain(0, 0, 1e-3, 1e-3), grain(0.005, 0, 0.5e-3, 0.5e-3), grain(0, 0, 2.6e-3, 0.5e-3)};
  f.adapter.result = [inner = f.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.relaxed.grains = {grain(0, 0, 0.97e-3, 1e-3), grain(0.005, 0, 0.49e-3, 0.5e-3),
                        grain(0, 0, 0.97e-3 + 1.5e-3 - 0.05e-3, 0.5e-3)};
    return r;
  };
  f.run();
  const btr::Packing out = btr::read_packing(f.dir + "/relaxed.csv");
  EXPECT_NEAR(out.meta["relax"]["final_largest_floor_overlap"].get<double>(), 0.03, 1e-9);
  EXPECT_NEAR(out.meta["relax"]["final_largest_overlap"].get<double>(), 0.1, 1e-9);
}

TEST(RelaxChecks, FailedCommandCarriesTheLogTail) {
  FakeRun f("fake_exit");
  f.adapter.shell = "echo 'ERROR: boom at step 12' > fake.log; exit 2";
  const std::string msg = f.failure(btr::FailureKind::EngineError);
  EXPECT_NE(msg.find("exit status 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ERROR: boom at step 12"), std::string::npos) << msg;
  EXPECT_EQ(f.record["values"]["exit_status"], 2);
}

// After a non-zero exit the engine's own outputs decide the kind, and their numbers join the exit status.
TEST(RelaxChecks, KindReportedByTheEngineAfterItsExit) {
  FakeRun f("fake_exit_reported");
  f.adapter.shell = "echo 'ERROR: Lost atoms: original 60 current 58' > fake.log; exit 1";
  f.adapter.after_exit = [] {
    return btr::EngineFailure(btr::FailureKind::LostGrains, "fake.log: the run failed: ERROR: Lost atoms",
                              {{"original", 60}, {"current", 58}});
  };
  const std::string msg = f.failure(btr::FailureKind::LostGrains);
  EXPECT_NE(msg.find("exit status 1: fake.log: the run failed: ERROR: Lost atoms"), std::string::npos) << msg;
  EXPECT_EQ(f.record["values"]["exit_status"], 1);
  EXPECT_EQ(f.record["values"]["original"], 60);
  EXPECT_EQ(f.record["values"]["current"], 58);
}

TEST(RelaxChecks, FailureKindNamesAreStable) {
  const std::pair<btr::FailureKind, const char*> names[] = {
      {btr::FailureKind::EngineError, "engine_error"},   {btr::FailureKind::TimeLimit, "time_limit"},
      {btr::FailureKind::BlowUp, "blow_up"},             {btr::FailureKind::NonFinite, "non_finite"},
      {btr::FailureKind::LostGrains, "lost_grains"},     {btr::FailureKind::OutsideContainer, "outside_container"},
      {btr::FailureKind::MissedContact, "missed_contact"}, {btr::FailureKind::BadOutput, "bad_output"}};
  for (const auto& [kind, name] : names) {
    EXPECT_STREQ(btr::failure_kind_name(kind), name);
    EXPECT_EQ(btr::failure_kind_from_name(name), kind);
  }
  EXPECT_FALSE(btr::failure_kind_from_name("blew up").has_value());
}

TEST(RelaxChecks, WallTimeLimit) {
  FakeRun f("fake_slow");
  f.adapter.shell = "sleep 30";
  f.settings.wall_time_limit = 0.5;
  EXPECT_NE(f.failure(btr::FailureKind::TimeLimit).find("wall-time limit"), std::string::npos);
  EXPECT_EQ(f.record["values"]["time_limit"], 0.5);
  EXPECT_GE(f.record["values"]["wall_seconds"].get<double>(), 0.5);
}

TEST(RelaxChecks, GrainOutsideTheContainer) {
  FakeRun f("fake_outside");
  f.adapter.result = [inner = f.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.relaxed.grains[5].x.z() = -1e-4;
    return r;
  };
  const std::string msg = f.failure(btr::FailureKind::OutsideContainer);
  EXPECT_NE(msg.find("grain 6 is outside the container"), std::string::npos) << msg;
  EXPECT_EQ(f.record["values"]["grain"], 6);
  EXPECT_EQ(f.record["values"]["wall"], "floor");
}

TEST(RelaxChecks, KineticEnergyBlowUp) {
  FakeRun f("fake_blowup");
  const double bound = btr::kinetic_energy_bound(f.packing.grains, f.scene);
  // The bound is twice sum m g z (no initial overlaps here).
  double mgz = 0;
  for (const btr::Grain& g : f.packing.grains) mgz += 4.0 / 3.0 * M_PI * std::pow(g.r, 3) * 2500 * 9.81 * g.x.z();
  EXPECT_NEAR(bound, 2 * mgz, 1e-9 * bound);
  f.adapter.result = [inner = f.adapter.result, bound](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.kinetic_history.push_back({0.2, 3 * bound});
    return r;
  };
  const std::string msg = f.failure(btr::FailureKind::BlowUp);
  EXPECT_NE(msg.find("blew up"), std::string::npos) << msg;
  EXPECT_EQ(f.record["values"]["kinetic_energy"].get<double>(), 3 * bound);
  EXPECT_EQ(f.record["values"]["bound"].get<double>(), bound);
  EXPECT_EQ(f.record["values"]["time"].get<double>(), 0.2);
}

TEST(RelaxChecks, LostGrainsAndNonFiniteValues) {
  FakeRun f("fake_lost");
  f.adapter.result = [inner = f.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.relaxed.grains.pop_back();
    return r;
  };
  EXPECT_NE(f.failure(btr::FailureKind::LostGrains).find("lost grains"), std::string::npos);
  EXPECT_EQ(f.record["values"]["grains"], f.packing.grains.size());
  EXPECT_EQ(f.record["values"]["returned"], f.packing.grains.size() - 1);
  FakeRun g("fake_nan");
  g.adapter.result = [inner = g.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.relaxed.grains[3].x.x() = std::nan("");
    return r;
  };
  EXPECT_NE(g.failure(btr::FailureKind::NonFinite).find("grain 4 has a non-finite position"), std::string::npos);
  FakeRun h("fake_nan_energy");
  h.adapter.result = [inner = h.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.kinetic_history.push_back({0.2, std::nan("")});
    return r;
  };
  EXPECT_NE(h.failure(btr::FailureKind::NonFinite).find("kinetic energy nan"), std::string::npos);
  EXPECT_TRUE(h.record["values"]["kinetic_energy"].is_null()) << "JSON has no NaN: null";
}

// relax_failure.json is renamed into place (a reader never sees half a record; a link to the old file keeps
// the old bytes), is there exactly after a failed run, and never outlives the run it describes: a successful
// run and a refused one into the same folder remove it.
TEST(RelaxChecks, FailureRecordIsAtomicAndNeverStale) {
  FakeRun f("fake_record");
  const std::string record = f.dir + "/" + btr::kRelaxFailureFile;
  const std::string stale = R"({"kind": "blow_up", "engine": "earlier"})";
  std::ofstream(record) << stale;
  fs::create_hard_link(record, f.dir + "/earlier_record.json");
  f.adapter.result = [inner = f.adapter.result](const btr::Packing& p) {
    btr::RelaxResult r = inner(p);
    r.relaxed.grains.pop_back();
    return r;
  };
  f.failure(btr::FailureKind::LostGrains);
  EXPECT_EQ(read_text(f.dir + "/earlier_record.json"), stale) << "the record was rewritten in place";
  EXPECT_EQ(f.record["kind"], "lost_grains");
  for (const auto& e : fs::directory_iterator(f.dir))
    EXPECT_NE(e.path().extension(), ".tmp") << "a temporary file was left: " << e.path();

  // A successful run into the same folder removes it.
  f.adapter.result = FakeRun("fake_record_ok").adapter.result;
  f.run();
  EXPECT_FALSE(fs::exists(record)) << "a successful run left an earlier run's failure record";
  EXPECT_TRUE(fs::exists(f.dir + "/relaxed.json"));

  // A failure after a failure replaces it with its own.
  f.adapter.shell = "sleep 30";
  f.settings.wall_time_limit = 0.2;
  f.failure(btr::FailureKind::TimeLimit);
  f.adapter.shell = "exit 3";
  f.failure(btr::FailureKind::EngineError);
  EXPECT_EQ(f.record["values"]["exit_status"], 3);
  EXPECT_FALSE(f.record["values"].contains("time_limit"));

  // A run refused before any engine starts (an overlap above --max-overlap) removes it too.
  btr::Packing overlapping = f.packing;
  overlapping.grains[1].x = overlapping.grains[0].x + btr::Vec3(overlapping.grains[0].r, 0, 0);
  EXPECT_THROW(btr::relax(overlapping, f.scene, "liggghts", {}, f.dir), btr::RelaxRefused);
  EXPECT_FALSE(fs::exists(record)) << "a refused run left an earlier run's failure record";
}
