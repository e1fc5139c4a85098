// YADE coupling: the generated script (walls, materials, how it is run), real relaxations in every
// container, and failures (broken packing, broken script, blow-up, grains leaving) reported as such.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <regex>
#include <set>
#include <sstream>

#include "btr/model/number_text.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/relax.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/engines.h"
#include "coupling/yade/yade_script.h"
#include "relax_fixtures.h"
#include "relaxation_checks.h"

namespace fs = std::filesystem;
using btr::ContainerKind;
using btr_test::container;
using btr_test::Case;
using btr_test::all_cases;
using btr_test::largest_pair_overlap;
using btr_test::largest_wall_overlap;
using btr_test::threshold_by_hand;
using btr_test::check_velocities_file;
using btr_test::line_starting;
using btr_test::read_text;

namespace {

bool have_yade() { return fs::exists(std::string(btr::kYadePythonPath) + "/yade/__init__.py"); }

using btr::g17;

// The walls the script must create, computed here from the container: "plane AXIS POSITION" and
// "cylinder RADIUS".
std::multiset<std::string> expected_walls(const Case& c) {
  std::multiset<std::string> w{"plane 2 0"};
  const btr::Container& k = c.container;
  auto plane = [&](int axis, double pos) { w.insert("plane " + std::to_string(axis) + " " + g17(pos)); };
  switch (k.kind) {
    case ContainerKind::Box:
      plane(0, -k.size_x / 2), plane(0, k.size_x / 2);
      if (c.dimension == 3) plane(1, -k.size_y / 2), plane(1, k.size_y / 2);
      break;
    case ContainerKind::HeleShaw:
      plane(0, -k.size_x / 2), plane(0, k.size_x / 2), plane(1, -k.gap / 2), plane(1, k.gap / 2);
      break;
    case ContainerKind::Cylinder: w.insert("cylinder " + g17(k.radius)); break;
    default: break;
  }
  return w;
}

// The walls a generated script creates (calls inside scene()).
std::multiset<std::string> walls_in_script(const std::string& script) {
  std::multiset<std::string> w;
  std::istringstream in(script);
  std::string line;
  const std::regex plane(R"(^    add_plane\(axis=(\d), position=([^)]+)\))");
  const std::regex cylinder(R"(^    add_cylinder\(radius=([^,]+), height=([^,]+), segments=(\d+)\))");
  std::smatch m;
  while (std::getline(in, line)) {
    if (line.rfind("    add_plane(", 0) != 0 && line.rfind("    add_cylinder(", 0) != 0) continue;
    if (std::regex_search(line, m, plane)) w.insert("plane " + std::string(m[1]) + " " + std::string(m[2]));
    else if (std::regex_search(line, m, cylinder)) w.insert("cylinder " + std::string(m[1]));
    else w.insert("unparsed: " + line);
  }
  return w;
}

void check_relaxation(const Case& c, const btr::Scene& scene, const btr::Packing& in, const btr::RelaxResult& r,
                      const std::string& dir) {
  btr::Packing out;
  btr_test::check_relaxed_packing(c, scene, in, r, dir, out);
  if (::testing::Test::HasFatalFailure()) return;
  // YADE's kinTrans is taken half a step before the final velocities (leapfrog): the same order of
  // magnitude, and at rest by the stop rule's measure.
  const double ke = check_velocities_file(scene, in, r, dir), last = r.kinetic_history.back().second;
  EXPECT_GT(ke, 0.1 * last);
  EXPECT_LT(ke, 10.0 * last);
  EXPECT_LT(ke, 10.0 * threshold_by_hand(in.grains, scene));
  EXPECT_EQ(out.meta["relax"]["engine"], "yade");
  // The script's own status agrees.
  const auto status = nlohmann::json::parse(read_text(dir + "/" + btr::yade_files::kStatus));
  EXPECT_EQ(status["status"], "ok");
  EXPECT_EQ(status["stop_reason"], "kinetic-energy");
  EXPECT_EQ(status["threads"], 1);
}

class YadeContainers : public ::testing::TestWithParam<Case> {};

}  // namespace

// Each script has exactly the container's walls (periodic cell instead of lateral walls), the 2D
// constraint only in 2D, no rolling term unless asked, and is valid Python.
TEST_P(YadeContainers, ScriptMatchesTheContainer) {
  const Case c = GetParam();
  const btr::Scene scene = btr_test::make_scene(c.name, c.dimension, c.container);
  const btr::Packing p = btr_test::layered_packing(scene, c.grains, 7);
  const std::string dir = btr_test::fresh_dir("yade_inputs_" + c.name);
  const auto files = btr::export_inputs(p, scene, "yade", {}, dir);
  ASSERT_EQ(files.size(), 2u);
  const std::string script = read_text(dir + "/relax_yade.py");
  EXPECT_EQ(walls_in_script(script), expected_walls(c)) << script.substr(script.find("def scene():"));
  const std::string cell = line_starting(script, "    periodic_cell(");
  if (c.container.kind == ContainerKind::Periodic) {
    const std::string period_y = c.dimension == 3 ? g17(c.container.size_y) : "";
    EXPECT_EQ(cell.rfind("    periodic_cell(" + g17(c.container.size_x) + ", " + period_y, 0), 0u) << cell;
  } else {
    EXPECT_EQ(cell, "");
  }
  // The collider's margin: YADE's default 0.5 r_min, less if needed to keep every grain's bounding box
  // below half of each period (else YADE may pair grains across the boundary with the wrong image).
  const std::string verlet = line_starting(script, "VERLET_DIST = ");
  ASSERT_FALSE(verlet.empty());
  const double vd = std::stod(verlet.substr(14));
  double r_min = 1, r_max = 0;
  for (const btr::Grain& q : p.grains) r_min = std::min(r_min, q.r), r_max = std::max(r_max, q.r);
  EXPECT_GT(vd, 0.0);
  EXPECT_LE(vd, 0.5 * r_min);
  if (c.container.kind == ContainerKind::Periodic) {
    EXPECT_LT(2 * (r_max + vd), 0.5 * c.container.size_x);
    if (c.dimension == 3) {
      EXPECT_LT(2 * (r_max + vd), 0.5 * c.container.size_y);
    }
  } else {
    EXPECT_EQ(vd, 0.5 * r_min);
  }
  EXPECT_EQ(line_starting(script, "DIMENSION = "), "DIMENSION = " + std::to_string(c.dimension));
  EXPECT_EQ(line_starting(script, "MODEL = "), "MODEL = \"hertz\"");
  EXPECT_EQ(line_starting(script, "    set_rolling("), "") << "no rolling term unless the scene sets one";
  EXPECT_EQ(line_starting(script, "DAMPING = "), "DAMPING = 0  # NewtonIntegrator damping (0 = off)")
      << "no numerical damping unless asked";
  EXPECT_NE(script.find("damping=COMPACTION[\"damping\"] if COMPACTION else DAMPING"), std::string::npos);
  EXPECT_EQ(line_starting(script, "COMPACTION = "), "COMPACTION = None  # no target packing fraction");
  // The packing file: header and one line per grain, ids 1..N.
  const std::string csv = read_text(dir + "/yade_packing.csv");
  EXPECT_EQ(csv.rfind("id,x,y,z,radius,species\n1,", 0), 0u);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), c.grains + 1);
  EXPECT_NE(csv.find("\n" + std::to_string(c.grains) + ","), std::string::npos);
  // Valid Python (parsed without importing yade).
  const std::string cmd = "/usr/bin/python3 -c \"import ast,sys; ast.parse(open(sys.argv[1]).read())\" " + dir +
                          "/relax_yade.py";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
}

TEST_P(YadeContainers, RelaxesToTheStopRule) {
  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  const Case c = GetParam();
  // Open floors get rolling friction: a sphere rolling on a flat floor never stops otherwise.
  btr::Scene scene = c.container.kind == ContainerKind::Open
                         ? btr_test::settling_scene(c.name, c.dimension, c.container)
                         : btr_test::make_scene(c.name, c.dimension, c.container);
  // Softer than the fixture's 5e7 Pa: a 2.2x longer stable step keeps each run short; the static
  // overlaps of these few layers stay far below 1% of the radius.
  scene.grains.components[0].material.young = 1e7;
  // Every grain must come back here (removal on open floors is tested in test_stop_rules.cpp): in open2d
  // a few disks roll 0.25 m (100 diameters) before the bed settles at t = 1.4 s.
  scene.relax.open_margin = 1000;
  const btr::Packing p = btr_test::layered_packing(scene, c.grains, 11);
  const std::string dir = btr_test::fresh_dir("yade_relax_" + c.name);
  const btr::RelaxResult r = btr::relax(p, scene, "yade", {}, dir);
  check_relaxation(c, scene, p, r, dir);
  const auto status = nlohmann::json::parse(read_text(dir + "/" + btr::yade_files::kStatus));
  std::cout << c.name << ": " << c.grains << " grains, stop at t = " << r.simulated_time << " s after "
            << status["steps"] << " steps, wall " << r.wall_seconds << " s ("
            << status["steps_per_second"].get<double>() << " steps/s)\n";
}

INSTANTIATE_TEST_SUITE_P(AllContainers, YadeContainers, ::testing::ValuesIn(all_cases()),
                         [](const auto& info) { return info.param.name; });

// btr runs the script by importing the yade module into /usr/bin/python3, never through the `yade`
// launcher (which opens a Python console and an XML-RPC server on the network).
TEST(Yade, CommandImportsTheModule) {
  const auto adapter = btr::make_adapter("yade");
  btr::RelaxSettings settings;
  settings.np = 3;
  const btr::EngineCommand cmd = adapter->command("/tmp/some run", settings);
  ASSERT_EQ(cmd.argv.size(), 2u);
  EXPECT_EQ(cmd.argv[0], "/usr/bin/python3");
  EXPECT_EQ(cmd.argv[1], "/tmp/some run/relax_yade.py");
  EXPECT_EQ(cmd.env.at("PYTHONPATH"), "/usr/lib/x86_64-linux-gnu/yade-double/py");
  EXPECT_EQ(cmd.env.at("OMP_NUM_THREADS"), "3");
  EXPECT_EQ(adapter->log_file("/tmp/x"), "/tmp/x/yade.log");
}

// Two species, linear contacts: the script's Young's moduli make YADE's kn = E r equal LIGGGHTS'
// model hooke k_n (computed here from its formula), unlike pairs take the mean friction and
// restitution, wall contacts the grain's; the run settles.
TEST(Yade, HookeMixture) {
  const Case c{"yade_mix", 3, container(ContainerKind::Box, 0.02, 0.02), 300};
  btr::Scene scene = btr_test::make_scene("mix", 3, c.container);
  btr::Component second = scene.grains.components[0];
  second.species = 2;
  second.material.young = 2e8;
  second.material.friction = 0.3;
  second.material.restitution = 0.7;
  scene.grains.components.push_back(second);
  scene.grains.components[0].fraction = scene.grains.components[1].fraction = 0.5;
  scene.relax.model = "hooke";
  const btr::Packing p = btr_test::layered_packing(scene, c.grains, 5, {1, 2});
  const std::string dir = btr_test::fresh_dir("yade_mix");
  btr::export_inputs(p, scene, "yade", {}, dir);
  const std::string script = read_text(dir + "/relax_yade.py");

  double d_max = 0;
  for (const btr::Grain& q : p.grains) d_max = std::max(d_max, 2 * q.r);
  const double v = std::sqrt(2 * 9.81 * d_max);
  auto hooke_young = [&](double young, double nu) {  // k_n(r) / r for two grains of radius r = 1 mm
    const double r = 1e-3, r_eff = r / 2, m_eff = 4.0 / 3.0 * M_PI * r * r * r * 2500 / 2;
    const double y_eff = young / (2 * (1 - nu * nu));
    return 16.0 / 15.0 * std::sqrt(r_eff) * y_eff *
           std::pow(15 * m_eff * v * v / (16 * std::sqrt(r_eff) * y_eff), 0.2) / r;
  };
  std::smatch m;
  const std::string s1 = line_starting(script, "    add_material(\"species1\"");
  const std::string s2 = line_starting(script, "    add_material(\"species2\"");
  const std::regex young(R"(young=([^,]+), poisson=([^,]+),)");
  ASSERT_TRUE(std::regex_search(s1, m, young)) << s1;
  EXPECT_NEAR(std::stod(m[1]), hooke_young(5e7, 0.3), 1e-9 * hooke_young(5e7, 0.3));
  EXPECT_EQ(std::stod(m[2]), 1.0) << "ks = kn";
  ASSERT_TRUE(std::regex_search(s2, m, young)) << s2;
  EXPECT_NEAR(std::stod(m[1]), hooke_young(2e8, 0.3), 1e-9 * hooke_young(2e8, 0.3));
  EXPECT_NE(script.find("    pair(\"species1\", \"species2\", restitution=0.59999999999999998, friction=0.40000000000000002)"),
            std::string::npos);
  EXPECT_NE(script.find("    pair(\"species2\", \"walls\", restitution=0.69999999999999996, friction=0.29999999999999999)"),
            std::string::npos);
  EXPECT_NE(script.find("    pair(\"species1\", \"walls\", restitution=0.5, friction=0.5)"), std::string::npos);

  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  const std::string run_dir = btr_test::fresh_dir("yade_mix_run");
  const btr::RelaxResult r = btr::relax(p, scene, "yade", {}, run_dir);
  check_relaxation(c, scene, p, r, run_dir);
}

// What YADE cannot do is refused before anything is written, naming the field.
TEST(Yade, RollingFrictionWithTheLinearLawIsRefused) {
  btr::Scene scene = btr_test::settling_scene("roll", 3, container(ContainerKind::Box, 0.02, 0.02));
  scene.relax.model = "hooke";
  const btr::Packing p = btr_test::layered_packing(scene, 50, 2);
  const std::string dir = btr_test::fresh_dir("yade_roll");
  try {
    btr::export_inputs(p, scene, "yade", {}, dir);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rolling_friction"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir + "/relax_yade.py"));
}

// hooke-stiffness is LIGGGHTS-only: YADE refuses it, saying why, before writing anything.
TEST(Yade, HookeStiffnessIsRefused) {
  btr::Scene scene = btr_test::make_scene("stiff", 3, container(ContainerKind::Box, 0.02, 0.02));
  scene.relax.model = "hooke-stiffness";
  scene.grains.components[0].material.kn = 24.6;
  scene.grains.components[0].material.kt = 7.0;
  const btr::Packing p = btr_test::layered_packing(scene, 50, 2);
  const std::string dir = btr_test::fresh_dir("yade_stiff");
  try {
    btr::export_inputs(p, scene, "yade", {}, dir);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("LIGGGHTS-only"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("relax.model"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir + "/relax_yade.py"));
}

// Rolling friction with Hertz-Mindlin: one moment law for all contacts.
TEST(Yade, RollingFrictionUsesTheMindlinMomentLaw) {
  const btr::Scene scene = btr_test::settling_scene("roll", 3, container(ContainerKind::Open));
  const btr::Packing p = btr_test::layered_packing(scene, 50, 2);
  const std::string dir = btr_test::fresh_dir("yade_roll_hertz");
  btr::export_inputs(p, scene, "yade", {}, dir);
  const std::string line = line_starting(read_text(dir + "/relax_yade.py"), "    set_rolling(");
  EXPECT_NE(line.find("eta=0.050000000000000003"), std::string::npos) << line;  // mu_r / 2
}

namespace {

// What a broken run failed with: the message, the kind, and the run folder's relax_failure.json.
struct Broken {
  std::string msg;
  btr::FailureKind kind = btr::FailureKind::EngineError;
  nlohmann::json record;
  std::size_t find(const std::string& s) const { return msg.find(s); }
};

// Writes the inputs for a small packing, lets `edit` break a file, runs them; returns the failure.
Broken run_broken(const std::string& name, const std::string& file,
                  const std::function<std::string(std::string)>& edit) {
  const btr::Scene scene = btr_test::make_scene(name, 3, container(ContainerKind::Box, 0.02, 0.02));
  const btr::Packing p = btr_test::layered_packing(scene, 100, 9);
  const std::string dir = btr_test::fresh_dir(name);
  const auto adapter = btr::make_adapter("yade");
  const btr::RelaxPlan plan = btr::make_plan(p, scene, {}, "yade");
  btr::write_engine_inputs(p, scene, *adapter, {}, plan, dir);
  const std::string path = dir + "/" + file;
  const std::string broken = edit(read_text(path));
  std::ofstream(path) << broken;
  Broken b;
  try {
    btr::run_engine_inputs(p, scene, *adapter, "yade", {}, plan, dir);
    ADD_FAILURE() << "the broken run was accepted";
  } catch (const btr::EngineFailure& e) {
    b.msg = e.what();
    b.kind = e.kind();
    b.record = nlohmann::json::parse(read_text(dir + "/" + btr::kRelaxFailureFile));
    EXPECT_EQ(b.record["kind"], btr::failure_kind_name(e.kind()));
    EXPECT_EQ(b.record["engine"], "yade");
    EXPECT_EQ(b.record["log"], "yade.log");
  }
  EXPECT_FALSE(fs::exists(dir + "/relaxed.csv")) << "a failed run is never a result";
  return b;
}

std::string replace_once(std::string s, const std::string& what, const std::string& with) {
  const auto at = s.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  return at == std::string::npos ? s : s.replace(at, what.size(), with);
}

}  // namespace

TEST(Yade, BrokenPackingIsReported) {
  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  const Broken msg = run_broken("yade_broken_packing", "yade_packing.csv", [](std::string s) {
    const auto line3 = s.find("\n3,");
    return s.replace(line3 + 1, s.find(',', line3 + 3) - line3 - 1, "3,not-a-number");
  });
  EXPECT_NE(msg.find("yade_packing.csv line 4"), std::string::npos) << msg.msg;
  EXPECT_NE(msg.find("last lines of"), std::string::npos) << msg.msg;
  EXPECT_EQ(msg.kind, btr::FailureKind::EngineError);
  EXPECT_EQ(msg.record["values"]["exit_status"], 1);
}

TEST(Yade, BrokenScriptIsReported) {
  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  const Broken msg = run_broken("yade_broken_script", "relax_yade.py",
                                [](std::string s) { return replace_once(s, "    add_grains(", "    add_grainz("); });
  EXPECT_NE(msg.find("NameError"), std::string::npos) << msg.msg;
  EXPECT_EQ(msg.kind, btr::FailureKind::EngineError);
}

TEST(Yade, BlowUpIsAFailure) {
  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  // 40 times the stable step: Hertz contacts gain energy at every collision.
  const Broken msg = run_broken("yade_blowup", "relax_yade.py", [](std::string s) {
    const std::string line = line_starting(s, "TIMESTEP = ");
    const double dt = std::stod(line.substr(11));
    return replace_once(s, line, "TIMESTEP = " + g17(40 * dt));
  });
  EXPECT_TRUE(msg.find("blow-up") != std::string::npos || msg.find("fell through the floor") != std::string::npos ||
              msg.find("left the container") != std::string::npos || msg.find("outside the container") != std::string::npos)
      << msg.msg;
  // The script's own checks name the kind (its status file's failure_kind).
  EXPECT_TRUE(msg.kind == btr::FailureKind::BlowUp || msg.kind == btr::FailureKind::OutsideContainer ||
              msg.kind == btr::FailureKind::NonFinite)
      << msg.record.dump();
  if (msg.kind == btr::FailureKind::BlowUp) {
    EXPECT_GT(msg.record["values"]["kinetic_energy"].get<double>(), msg.record["values"]["bound"].get<double>());
  }
}

// Without its floor the bed falls forever: the run reports grains below the floor.
TEST(Yade, GrainsLeavingTheContainerAreAFailure) {
  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  const Broken msg = run_broken("yade_no_floor", "relax_yade.py", [](std::string s) {
    s = replace_once(s, "    add_plane(axis=2, position=0)  # floor", "    pass  # floor removed");
    const std::string checks = line_starting(s, "MAX_CHECKS = ");
    return replace_once(s, checks, "MAX_CHECKS = 5");  // the lowest grains fall below z = 0, the bound is not reached
  });
  EXPECT_NE(msg.find("fell through the floor"), std::string::npos) << msg.msg;
  EXPECT_EQ(msg.kind, btr::FailureKind::OutsideContainer) << msg.record.dump();
}

// read_back alone: no status means the script did not finish; outputs that contradict the
// container or the packing are failures, whatever the status says.
TEST(Yade, ReadBackRejectsMissingAndBadOutputs) {
  const btr::Scene scene = btr_test::make_scene("rb", 3, container(ContainerKind::Box, 0.02, 0.02));
  const btr::Packing p = btr_test::layered_packing(scene, 3, 1);
  const auto adapter = btr::make_adapter("yade");
  btr::RelaxPlan plan;
  plan.timestep = 1e-6;
  plan.max_time = 0.1;
  plan.kinetic_threshold = 1e-9;
  const std::string dir = btr_test::fresh_dir("yade_read_back");
  auto expect_failure = [&](const std::string& needle, btr::FailureKind kind) {
    try {
      adapter->read_back(dir, p, scene, plan);
      ADD_FAILURE() << "accepted; expected a failure mentioning " << needle;
    } catch (const btr::EngineFailure& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_EQ(btr::failure_kind_name(e.kind()), std::string(btr::failure_kind_name(kind))) << e.what();
    }
  };
  expect_failure("no status file", btr::FailureKind::BadOutput);

  std::ofstream(dir + "/yade_status.json") << R"({"status": "ok", "stop_reason": "kinetic-energy", "time": 0.05,
                                                  "steps": 50000, "wall_seconds": 1.0})";
  expect_failure("missing output", btr::FailureKind::BadOutput);

  // Grains 4 mm apart along x on the floor (grain 2 at x_of_grain_2), velocity (i, -2i, 3i) mm/s.
  auto final_rows = [&](double x_of_grain_2) {
    std::ofstream f(dir + "/yade_final.csv");
    f << "id,x,y,z,vx,vy,vz\n";
    for (std::size_t i = 0; i < p.grains.size(); ++i) {
      const double v = 1e-3 * static_cast<double>(i + 1);
      f << i + 1 << "," << g17(i == 1 ? x_of_grain_2 : 0.004 * (static_cast<double>(i) - 1.0)) << ",0,"
        << g17(p.grains[i].r) << "," << g17(v) << "," << g17(-2 * v) << "," << g17(3 * v) << "\n";
    }
  };
  std::ofstream(dir + "/yade_kinetic.csv") << "time,kinetic_energy\n0,0\n0.05,1e-12\n";
  std::ofstream(dir + "/yade_contacts.csv") << "i,j,fn,overlap\n1,0,1e-4,1e-7\n";
  final_rows(0.011);  // beyond the wall x = +0.01
  expect_failure("grain 2 left the container", btr::FailureKind::OutsideContainer);
  final_rows(-0.0039);  // nearly on top of grain 1: a contact YADE missed
  expect_failure("grains went into each other", btr::FailureKind::MissedContact);
  final_rows(0.0);
  const btr::RelaxResult ok = adapter->read_back(dir, p, scene, plan);
  EXPECT_EQ(ok.stop_reason, "kinetic-energy");
  EXPECT_EQ(ok.relaxed.grains.size(), 3u);
  ASSERT_EQ(ok.velocities.size(), 3u);
  const double v3 = 1e-3 * 3.0;  // as written for grain 3
  EXPECT_EQ(ok.velocities[2], btr::Vec3(v3, -2 * v3, 3 * v3));
  EXPECT_EQ(ok.relaxed.grains[2].x, btr::Vec3(0.004, 0, p.grains[2].r));
  ASSERT_EQ(ok.contacts.size(), 1u);
  EXPECT_EQ(ok.contacts[0].j, 0);
  EXPECT_EQ(ok.kinetic_history.size(), 2u);

  std::ofstream(dir + "/yade_kinetic.csv") << "time,kinetic_energy\n0,0\n0.05,nan\n";
  expect_failure("non-finite", btr::FailureKind::NonFinite);
  std::ofstream(dir + "/yade_kinetic.csv") << "time,kinetic_energy\n0,0\n0.05,1e-6\n";
  expect_failure("is not below the threshold", btr::FailureKind::BadOutput);
  std::ofstream(dir + "/yade_kinetic.csv") << "time,kinetic_energy\n0,0\n0.05,1e-12\n";
  {
    std::ofstream f(dir + "/yade_final.csv");
    f << "id,x,y,z,vx,vy,vz\n1,0,0,0.001,0,0,0\n2,0,0,0.001,0,0,0\n";  // grain 3 lost
  }
  expect_failure("lost grains", btr::FailureKind::LostGrains);
  // A failed status: the kind is the script's failure_kind (engine_error without one).
  std::ofstream(dir + "/yade_status.json") << R"({"status": "failed", "message": "something broke"})";
  expect_failure("something broke", btr::FailureKind::EngineError);
  std::ofstream(dir + "/yade_status.json") << R"({"status": "failed", "message": "bodies were lost",
                                                  "failure_kind": "lost_grains"})";
  expect_failure("bodies were lost", btr::FailureKind::LostGrains);
  // A blow-up gets the last sample of the history and the bound (the script writes the history before failing).
  std::ofstream(dir + "/yade_kinetic.csv") << "time,kinetic_energy\n0,0\n0.0125,7.5\n";
  std::ofstream(dir + "/yade_status.json") << R"({"status": "failed", "message": "blow-up: ...",
                                                  "failure_kind": "blow_up", "time": 0.0125, "steps": 12500})";
  try {
    adapter->read_back(dir, p, scene, plan);
    ADD_FAILURE() << "a failed status was accepted";
  } catch (const btr::EngineFailure& e) {
    EXPECT_EQ(e.kind(), btr::FailureKind::BlowUp);
    EXPECT_EQ(e.values()["kinetic_energy"].get<double>(), 7.5);
    EXPECT_EQ(e.values()["time"].get<double>(), 0.0125);
    EXPECT_DOUBLE_EQ(e.values()["bound"].get<double>(), btr::kinetic_energy_bound(p.grains, scene));
    EXPECT_EQ(e.values()["steps"].get<int>(), 12500);
  }
  // An unknown kind name is no kind: engine_error.
  std::ofstream(dir + "/yade_status.json") << R"({"status": "failed", "message": "odd", "failure_kind": "gremlins"})";
  expect_failure("odd", btr::FailureKind::EngineError);
}

// A period of at most 4 largest radii cannot be given to YADE: a grain there spans half the period and
// may touch two images of another grain, and YADE keeps one interaction (one image) per pair.
TEST(Yade, PeriodNarrowerThanFourRadiiIsRefused) {
  const btr::Scene scene = btr_test::make_scene("narrow", 3, container(ContainerKind::Periodic, 0.02, 0.0038));
  btr::Packing p = btr_test::layered_packing(scene, 2, 3);
  for (btr::Grain& g : p.grains) g.r = 1e-3;  // 4 r_max = 4 mm > 3.8 mm; no overlap (2 grains, 3.8 mm apart at least)
  p.grains[0].x = btr::Vec3(-0.004, 0, 1.1e-3);
  p.grains[1].x = btr::Vec3(0.004, 0, 1.1e-3);
  const std::string dir = btr_test::fresh_dir("yade_narrow");
  try {
    btr::export_inputs(p, scene, "yade", {}, dir);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("container.size"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.0038"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir + "/relax_yade.py"));
}

namespace {

// The stability sweep's case: equal grains of radius 1 mm rained into a 6 mm periodic cell.
btr::Scene equal_grains_periodic_scene() {
  btr::Scene scene = btr::load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/bed3d.toml");
  scene.grains.components[0].radius.kind = btr::RadiusSpec::Kind::Constant;
  scene.grains.components[0].radius.value = 1e-3;
  scene.container.size_x = scene.container.size_y = 0.006;
  scene.relax.max_time = 0.1;
  return scene;
}

}  // namespace

// Regression: with YADE's default collider margin (0.5 r_min) each grain's bounding box spans half of
// this 6 mm period; YADE's collider then pairs two grains touching across the y boundary with the wrong
// image, and one fell through the other (overlap 1.99 r, the grains nearly at the same place).
TEST(Yade, EqualGrainsMeetAcrossThePeriodicBoundary) {
  if (!have_yade()) FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  const btr::Scene scene = equal_grains_periodic_scene();
  btr::Packing p;
  p.grains = btr::run_scene(scene, 1, 60, {}).grains;
  p.meta = {{"scene", btr::scene_to_json(scene)}};
  ASSERT_LT(largest_pair_overlap(p.grains, scene.container, 3), 1e-9) << "a BTR packing touches exactly";

  const std::string dir = btr_test::fresh_dir("yade_equal_periodic");
  const btr::RelaxResult r = btr::relax(p, scene, "yade", {}, dir);
  EXPECT_LT(largest_pair_overlap(r.relaxed.grains, scene.container, 3), 0.02);
  EXPECT_LT(largest_wall_overlap(r.relaxed.grains, scene.container, 3), 0.02);
  const std::string verlet = line_starting(read_text(dir + "/relax_yade.py"), "VERLET_DIST = ");
  ASSERT_FALSE(verlet.empty());
  EXPECT_LT(2 * (1e-3 + std::stod(verlet.substr(14))), 0.5 * 0.006);

  // The same run with YADE's default margin: the read-back reports the grains that went into each other.
  const std::string bad = btr_test::fresh_dir("yade_equal_periodic_default_margin");
  const auto adapter = btr::make_adapter("yade");
  const btr::RelaxPlan plan = btr::make_plan(p, scene, {}, "yade");
  btr::write_engine_inputs(p, scene, *adapter, {}, plan, bad);
  const std::string script = read_text(bad + "/relax_yade.py");
  std::ofstream(bad + "/relax_yade.py") << replace_once(script, verlet, "VERLET_DIST = 0.0005");
  try {
    btr::run_engine_inputs(p, scene, *adapter, "yade", {}, plan, bad);
    ADD_FAILURE() << "YADE's default margin gave no lost contact here; the regression no longer shows";
  } catch (const btr::EngineFailure& e) {
    EXPECT_NE(std::string(e.what()).find("grains went into each other"), std::string::npos) << e.what();
    EXPECT_EQ(e.kind(), btr::FailureKind::MissedContact);
    EXPECT_NE(read_text(bad + "/" + btr::kRelaxFailureFile).find("\"missed_contact\""), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(bad + "/relaxed.csv"));
}
