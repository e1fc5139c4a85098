// Dynamic BTR by shaking: the engine's start height against hand cases, the [intruder] and
// [shaking] tables, and invariants of a shaking cycle (checked packings, grain identity kept,
// determinism, the Brazil-nut rise of a large intruder).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <fstream>
#include <unistd.h>

#include "btr/dynamics/shaking.h"
#include "btr/measures/metrics.h"
#include "btr/placement/deposition.h"
#include "btr/placement/drops.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "btr/verify/check.h"

namespace btr {
namespace {

namespace fs = std::filesystem;

Container box2d(double width) {
  Container c;
  c.kind = ContainerKind::Box;
  c.size_x = width;
  return c;
}

Drop at(double x, double r, double z) {
  Drop d{x, 0.0, r, 1};
  d.z = z;
  return d;
}

// Under an arch the grain falls from its start, not from above the pile.
TEST(StartHeight, GrainStartedUnderAnArchStaysUnderIt) {
  Deposition dep(2, box2d(20.0), 1.0);
  dep.place(Drop{-1.5, 0.0, 1.0, 1});
  dep.place(Drop{1.5, 0.0, 1.0, 1});
  const Vec3 top = dep.place(Drop{0.0, 0.0, 1.0, 1}).x;  // rests on both: z = 1 + sqrt(4 - 1.5^2)
  ASSERT_NEAR(top.z(), 1.0 + std::sqrt(4.0 - 2.25), 1e-12);
  const Vec3 small = dep.place(at(0.0, 0.2, 0.9)).x;
  EXPECT_NEAR(small.x(), 0.0, 1e-12);
  EXPECT_NEAR(small.z(), 0.2, 1e-12);
  // The same grain without a start height comes down on the arch's top grain and stays up there.
  const Vec3 above = dep.place(Drop{0.0, 0.0, 0.2, 1}).x;
  EXPECT_GT(above.z(), 2.0);
}

// A start inside a fixed grain is moved straight up out of it; the grain then rolls off it onto the
// floor beside it: two unit disks touching on the floor, x = 2.
TEST(StartHeight, StartInsideAGrainIsLiftedOutOfIt) {
  Deposition dep(2, box2d(20.0), 1.0);
  dep.place(Drop{0.0, 0.0, 1.0, 1});
  const Vec3 p = dep.place(at(0.5, 1.0, 0.8)).x;
  EXPECT_NEAR(p.x(), 2.0, 1e-9);
  EXPECT_NEAR(p.z(), 1.0, 1e-9);
  EXPECT_TRUE(check_packing(dep.grains(), 2, box2d(20.0)).ok());
}

// 3D: a sphere started below the floor height is put on the floor (z = r) right there.
TEST(StartHeight, StartBelowTheFloorRestsOnTheFloor) {
  Container c;
  c.kind = ContainerKind::Periodic;
  c.size_x = c.size_y = 10.0;
  Deposition dep(3, c, 1.0);
  Drop d{1.0, 2.0, 0.5, 1};
  d.z = -3.0;
  const Vec3 p = dep.place(d).x;
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 2.0, 1e-12);
  EXPECT_NEAR(p.z(), 0.5, 1e-12);
}

TEST(Shaker, HeightOrderBreaksTiesByIndex) {
  Grains g = {{Vec3(0, 0, 2.0), 1.0, 1}, {Vec3(0, 0, 1.0), 1.0, 1}, {Vec3(0, 0, 2.0), 1.0, 1}};
  EXPECT_EQ(Shaker::height_order(g), (std::vector<std::size_t>{1, 0, 2}));
}

// A 2D row of touching disks on the floor is a fixed point of the deterministic cycle (each falls
// back where it was), whatever the lift.
TEST(Shaker, FloorRowIsAFixedPointWithoutNoise) {
  const Container c = box2d(8.0);
  Grains row;
  for (int i = 0; i < 4; ++i) row.push_back({Vec3(-3.0 + 2.0 * i, 0.0, 1.0), 1.0, 1});
  Shaker shaker(2, c, 5.0, 0.0, 1);
  const Grains after = shaker.cycle(row);
  for (std::size_t i = 0; i < row.size(); ++i) EXPECT_NEAR((after[i].x - row[i].x).norm(), 0.0, 1e-12) << i;
}

class ShakenScene : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("btr_test_shaking_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  Scene scene(const std::string& text) {
    const std::string path = (dir_ / "s.toml").string();
    std::ofstream(path) << text;
    return load_scene(path);
  }
  std::string error_of(const std::string& text) {
    try {
      scene(text);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

const char* kNut = R"([scene]
name = "nut"
dimension = 3
seed = 2
[grains]
count = 700
radius = { distribution = "constant", value = 1.0 }
[container]
kind = "periodic"
size = [10.0, 10.0]
[source]
kind = "rain"
[intruder]
diameter_ratio = 4.0
position = [1.0, -1.0]
[shaking]
cycles = 12
lift = 4.0
noise = 0.2
)";

TEST_F(ShakenScene, IntruderIsTheFirstDropAndRestsOnTheFloor) {
  const Scene s = scene(kNut);
  ASSERT_TRUE(s.intruder && s.shaking);
  EXPECT_EQ(s.intruder->species, 2);
  EXPECT_EQ(s.shaking->snapshot_every, 12);  // default: the number of cycles
  const Grains g = run_scene(s, s.seed, s.grains.count, {}).grains;
  ASSERT_EQ(g.size(), 701u);
  EXPECT_EQ(g[0].species, 2);
  EXPECT_DOUBLE_EQ(g[0].r, 4.0);
  EXPECT_NEAR((g[0].x - Vec3(1.0, -1.0, 4.0)).norm(), 0.0, 1e-12);
  // The bed's drops are those of the scene without the intruder (it draws no random numbers).
  Scene plain = s;
  plain.intruder.reset();
  DropSequence with(s, 5), without(plain, 5);
  with.next();
  for (int i = 0; i < 50; ++i) {
    const Drop a = with.next(), b = without.next();
    ASSERT_EQ(a.x, b.x);
    ASSERT_EQ(a.y, b.y);
  }
}

TEST_F(ShakenScene, CyclesKeepGrainsCheckedDeterministicAndTheNutRises) {
  const Scene s = scene(kNut);
  const Grains start = run_scene(s, s.seed, s.grains.count, {}).grains;
  Shaker a(3, s.container, s.shaking->lift, s.shaking->noise, 9), b(3, s.container, s.shaking->lift, s.shaking->noise, 9);
  Grains ga = start, gb = start;
  for (int c = 0; c < s.shaking->cycles; ++c) {
    ga = a.cycle(ga);
    gb = b.cycle(gb);
    const CheckReport rep = check_packing(ga, 3, s.container);
    ASSERT_TRUE(rep.ok()) << "cycle " << c << ": " << rep.overlaps << " overlaps, " << rep.unsupported
                          << " unsupported, " << rep.outside << " outside";
  }
  ASSERT_EQ(ga.size(), start.size());
  for (std::size_t i = 0; i < ga.size(); ++i) {
    ASSERT_EQ(ga[i].r, start[i].r);
    ASSERT_EQ(ga[i].species, start[i].species);
    ASSERT_EQ(ga[i].x, gb[i].x) << "same seed, different result at grain " << i;
  }
  // Phi = 4 is well above the critical ratio 2.8 (3D): the intruder climbs from the floor.
  EXPECT_GT(ga[0].x.z(), start[0].x.z() + 4.0);
  // Another noise seed gives another packing.
  Shaker other(3, s.container, s.shaking->lift, s.shaking->noise, 10);
  const Grains go = other.cycle(start);
  const Grains ga1 = Shaker(3, s.container, s.shaking->lift, s.shaking->noise, 9).cycle(start);
  bool differs = false;
  for (std::size_t i = 0; i < go.size(); ++i) differs |= go[i].x != ga1[i].x;
  EXPECT_TRUE(differs);
}

// With noise in a box, displaced grains are kept inside the walls (the self-check counts grains outside).
TEST_F(ShakenScene, NoiseNearWallsKeepsGrainsInside) {
  std::string text = kNut;
  text.replace(text.find("kind = \"periodic\""), 17, "kind = \"box\"");
  text.replace(text.find("noise = 0.2"), 11, "noise = 1.5");
  text.replace(text.find("position = [1.0, -1.0]"), 22, "position = [0.0, 0.0]");
  const Scene s = scene(text);
  Grains g = run_scene(s, s.seed, 300, {}).grains;
  Shaker sh(3, s.container, s.shaking->lift, s.shaking->noise, 3);
  for (int c = 0; c < 4; ++c) {
    g = sh.cycle(g);
    const CheckReport rep = check_packing(g, 3, s.container);
    ASSERT_TRUE(rep.ok()) << "cycle " << c << ": " << rep.outside << " outside, " << rep.overlaps << " overlaps";
  }
}

TEST_F(ShakenScene, BadTablesAreRefusedWithTheField) {
  std::string t = kNut;
  t.replace(t.find("lift = 4.0"), 10, "lift = 0.0");
  EXPECT_NE(error_of(t).find("shaking.lift: expected a positive lift"), std::string::npos) << error_of(t);
  t = kNut;
  t.replace(t.find("cycles = 12"), 11, "cycles = 0");
  EXPECT_NE(error_of(t).find("shaking.cycles"), std::string::npos) << error_of(t);
  t = kNut;
  t.replace(t.find("radius = { distribution = \"constant\", value = 1.0 }"), 51,
            "radius = { distribution = \"uniform\", min = 0.5, max = 1.0 }");
  EXPECT_NE(error_of(t).find("[intruder]: expected a bed of equal grains"), std::string::npos) << error_of(t);
  t = kNut;
  t.replace(t.find("diameter_ratio = 4.0"), 20, "diameter_ratio = 6.0");  // r = 6 > 10/2
  EXPECT_NE(error_of(t).find("container.size: expected widths of at least the diameter of the largest grain (r_max = 6"),
            std::string::npos)
      << error_of(t);
  t = kNut;
  t.replace(t.find("noise = 0.2"), 11, "nois = 0.2");
  EXPECT_NE(error_of(t).find("unknown key 'nois'"), std::string::npos) << error_of(t);
}

// mean_surface_height of a square lattice layer: every column top is z + r.
TEST(SurfaceHeight, SquareLayerTopIsItsGrainTops) {
  Container c;
  c.kind = ContainerKind::Periodic;
  c.size_x = c.size_y = 8.0;
  Grains g;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 2; ++k) g.push_back({Vec3(-3.0 + 2 * i, -3.0 + 2 * j, 1.0 + 2 * k), 1.0, 1});
  EXPECT_NEAR(mean_surface_height(g, 3, c, 2.0), 4.0, 1e-12);
  EXPECT_EQ(mean_surface_height({}, 3, c, 2.0), 0.0);
}

}  // namespace
}  // namespace btr

namespace btr {
namespace {

// Shaking with noise in every container the issue names (and 2D): each cycle's packing passes the
// self-check, and the intruder (Phi = 3) is still grain 1 with its radius.
TEST(ShakerContainers, EveryContainerStaysValid) {
  struct Kind { int dim; ContainerKind kind; };
  for (const Kind k : {Kind{3, ContainerKind::Box}, Kind{3, ContainerKind::Periodic}, Kind{3, ContainerKind::HeleShaw},
                       Kind{3, ContainerKind::Cylinder}, Kind{2, ContainerKind::Box}, Kind{2, ContainerKind::Periodic}}) {
    SCOPED_TRACE(std::string(to_string(k.kind)) + " " + std::to_string(k.dim) + "D");
    Container c;
    c.kind = k.kind;
    c.size_x = k.dim == 3 ? 12.0 : 30.0;
    c.size_y = k.dim == 3 ? 12.0 : 0.0;
    c.gap = 3.0;
    c.radius = 6.0;
    const double r_in = k.kind == ContainerKind::HeleShaw ? 1.4 : 3.0;
    Deposition dep(k.dim, c, r_in);
    dep.place(Drop{0.0, 0.0, r_in, 2});
    std::mt19937_64 rng(5);
    auto u = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
    for (int i = 0; i < 250; ++i) {
      double x = (u() - 0.5) * (c.size_x - 2.0), y = 0.0;
      if (k.dim == 3) y = (u() - 0.5) * ((k.kind == ContainerKind::HeleShaw ? c.gap : c.size_y) - 2.0);
      if (k.kind == ContainerKind::Cylinder) x *= 0.6, y *= 0.6;
      dep.place(Drop{x, y, 1.0, 1});
    }
    Grains g = dep.grains();
    Shaker sh(k.dim, c, 2.0 * r_in, 0.4, 11);
    for (int cycle = 0; cycle < 4; ++cycle) {
      g = sh.cycle(g);
      const CheckReport rep = check_packing(g, k.dim, c);
      ASSERT_TRUE(rep.ok()) << "cycle " << cycle << ": " << rep.overlaps << " overlaps, " << rep.unsupported
                            << " unsupported, " << rep.outside << " outside";
      ASSERT_EQ(g[0].r, r_in);
      ASSERT_EQ(g[0].species, 2);
    }
  }
}

TEST_F(ShakenScene, TapGammaAndFrequencyAreOptionalAndChecked) {
  const Scene plain = scene(kNut);
  EXPECT_FALSE(plain.shaking->gamma);  // unset: the tapping's defaults apply
  EXPECT_FALSE(plain.shaking->frequency);
  const Scene set = scene(std::string(kNut) + "gamma = 2.5\nfrequency = 45\n");
  ASSERT_TRUE(set.shaking->gamma && set.shaking->frequency);
  EXPECT_EQ(*set.shaking->gamma, 2.5);
  EXPECT_EQ(*set.shaking->frequency, 45.0);
  for (const char* bad : {"gamma = 0.0\n", "gamma = -1.0\n", "gamma = 101.0\n", "gamma = \"3\"\n"}) {
    const std::string e = error_of(std::string(kNut) + bad);
    EXPECT_NE(e.find("s.toml"), std::string::npos) << e;
    EXPECT_NE(e.find("shaking.gamma"), std::string::npos) << bad << ": " << e;
  }
  for (const char* bad : {"frequency = 0\n", "frequency = -30.0\n", "frequency = 2e4\n"}) {
    const std::string e = error_of(std::string(kNut) + bad);
    EXPECT_NE(e.find("shaking.frequency"), std::string::npos) << bad << ": " << e;
  }
}

}  // namespace
}  // namespace btr
