// Scene files: every shipped scene loads; bad scenes give an error naming file, line, key and expectation.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "btr/dynamics/redeposition.h"
#include "btr/placement/drops.h"
#include "btr/scene/scene_toml.h"
#include "btr/verify/cluster_check.h"

namespace btr {
namespace {

namespace fs = std::filesystem;

// A valid 3D scene that each bad-scene test breaks in one place.
const std::string kBase = R"([scene]
name = "t"
dimension = 3
seed = 1

[grains]
count = 100
density = 2500.0
radius = { distribution = "constant", value = 1e-3 }

[container]
kind = "box"
size = [0.02, 0.02]

[source]
kind = "rain"
)";

std::string replace(const std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("test bug: '" + from + "' not in the scene text");
  return text.substr(0, at) + to + text.substr(at + from.size());
}

// 1-based line of the first occurrence of `needle`.
int line_of(const std::string& text, const std::string& needle) {
  const auto at = text.find(needle);
  if (at == std::string::npos) throw std::logic_error("test bug: '" + needle + "' not in the scene text");
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

class SceneFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("btr_test_scene_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    path_ = (dir_ / "x.toml").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  // The message of the SceneError that loading `text` raises ("" if it loads).
  std::string error_of(const std::string& text, const std::string& name = "x.toml") {
    path_ = write(name, text);
    try {
      load_scene(path_);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  }
  // "FILE:LINE: " of the line holding `needle` in x.toml.
  std::string at(const std::string& text, const std::string& needle) const {
    return path_ + ":" + std::to_string(line_of(text, needle)) + ": ";
  }

  fs::path dir_;
  std::string path_;
};

TEST_F(SceneFile, BaseSceneLoads) {
  path_ = write("x.toml", kBase);
  const Scene s = load_scene(path_);
  EXPECT_EQ(s.name, "t");
  EXPECT_EQ(s.dimension, 3);
  EXPECT_EQ(s.grains.count, 100);
  ASSERT_EQ(s.grains.components.size(), 1u);
  EXPECT_EQ(s.grains.components[0].radius.kind, RadiusSpec::Kind::Constant);
  EXPECT_DOUBLE_EQ(s.grains.components[0].radius.value, 1e-3);
  EXPECT_EQ(s.container.kind, ContainerKind::Box);
  EXPECT_DOUBLE_EQ(s.container.size_y, 0.02);
  EXPECT_EQ(s.source.kind, SourceSpec::Kind::Rain);
}

// A dimer and an equilateral trimer of touching 1 mm grains, in a frame of their own.
const std::string kClusterList = R"(cluster,x,y,z,radius,species
7,0.0,0.0,0.0,1e-3,1
7,2e-3,0.0,0.0,1e-3,1
3,5.0,5.0,5.0,1e-3,1
3,5.002,5.0,5.0,1e-3,1
3,5.001,5.0017320508075689,5.0,1e-3,1
)";

TEST_F(SceneFile, ClusterListIsDroppedAsListed) {
  write("clusters.csv", kClusterList);
  const std::string text = replace(kBase, "count = 100", "count = 5") + "\n[clusters]\nfile = \"clusters.csv\"\n";
  path_ = write("x.toml", text);
  const Scene s = load_scene(path_);
  ASSERT_TRUE(s.clusters.has_value());
  EXPECT_EQ(fs::path(s.clusters->file), dir_ / "clusters.csv");
  Redeposition redeposition(s, 3);
  const Grains g = redeposition.initial();
  ASSERT_EQ(g.size(), 5u);
  const auto bodies = rigid_bodies(g);
  ASSERT_EQ(bodies.size(), 2u);
  EXPECT_EQ(bodies[0].size() + bodies[1].size(), 5u);
  // Every pair of members is as far apart as in the file (the grains touch: 2 radii).
  for (const auto& b : bodies)
    for (std::size_t i = 0; i < b.size(); ++i)
      for (std::size_t j = i + 1; j < b.size(); ++j) EXPECT_NEAR((g[b[i]].x - g[b[j]].x).norm(), 2e-3, 1e-12);
  const ClusterCheckReport rep = check_clusters(g, 3, s.container);
  EXPECT_TRUE(rep.ok()) << rep.overlaps << " overlaps, " << rep.unsupported << " unsupported";
}

TEST_F(SceneFile, ClusterListErrorsNameTheFileAndLine) {
  const std::string scene = replace(kBase, "count = 100", "count = 5") + "\n[clusters]\nfile = \"clusters.csv\"\n";
  auto error_with_list = [&](const std::string& list, const std::string& text) {
    write("clusters.csv", list);
    return error_of(text);
  };
  const std::string list = (dir_ / "clusters.csv").string();
  EXPECT_NE(error_with_list(replace(kClusterList, "cluster,x", "id,x"), scene).find(list + ":1: header"),
            std::string::npos);
  EXPECT_NE(error_with_list(replace(kClusterList, "7,2e-3,0.0,0.0", "7,1e-3,0.0,0.0"), scene)
                .find(list + ":3: cluster 7: this grain overlaps the one of line 2"),
            std::string::npos);
  EXPECT_NE(error_with_list(replace(kClusterList, "5.001,5.0017320508075689,5.0,1e-3,1", "5.001,5.0017320508075689,5.0,1e-3,2"),
                            scene).find("species 2 is not a species of the scene"),
            std::string::npos);
  const std::string wrong_count = error_with_list(kClusterList, replace(scene, "count = 5", "count = 6"));
  EXPECT_NE(wrong_count.find("lists 5 grains, but grains.count is 6"), std::string::npos) << wrong_count;
  EXPECT_NE(error_with_list(kClusterList, scene + "size = 3\n").find("either size"), std::string::npos);
  // 2D: disks in the x-z plane.
  const std::string scene2d =
      replace(replace(scene, "dimension = 3", "dimension = 2"), "size = [0.02, 0.02]", "size = [0.02]");
  EXPECT_NE(error_with_list(kClusterList, scene2d).find(list + ":4: y: expected 0 in 2D"), std::string::npos);
}

TEST(SceneInputs, EveryShippedSceneLoads) {
  int n = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(BTR_SOURCE_DIR) / "inputs")) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    ++n;
    Scene s;
    ASSERT_NO_THROW(s = load_scene(entry.path().string()));
    EXPECT_EQ(s.name, entry.path().stem().string());
    EXPECT_GT(s.grains.count, 0);
    DropSequence drops(s, s.seed);
    EXPECT_EQ(drops.count(), s.grains.count + (s.intruder ? 1 : 0));
    const Drop d = drops.next();
    EXPECT_GE(d.r, drops.r_min());
    EXPECT_LE(d.r, drops.r_max());
  }
  EXPECT_GE(n, 9);
}

TEST(SceneInputs, MixtureAndListScenesAreReadAsWritten) {
  const Scene bi = load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/bidisperse_heap.toml");
  EXPECT_EQ(bi.grains.fraction_by, GrainsSpec::FractionBy::Volume);
  ASSERT_EQ(bi.grains.components.size(), 2u);
  EXPECT_EQ(bi.grains.components[1].species, 2);
  EXPECT_DOUBLE_EQ(bi.grains.components[1].radius.value, 1.0e-3);

  const Scene list = load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/drops_list.toml");
  EXPECT_EQ(list.grains.count, 28);  // the CSV's data rows
  EXPECT_TRUE(fs::exists(list.source.file)) << list.source.file;
  ASSERT_EQ(list.grains.components.size(), 2u);
  // Species 2 overrides density and two material keys; the rest comes from [material].
  const Material& steel = list.grains.components[1].material;
  EXPECT_DOUBLE_EQ(list.grains.components[1].density, 7800.0);
  EXPECT_DOUBLE_EQ(steel.young, 2e7);
  EXPECT_DOUBLE_EQ(steel.restitution, 0.6);
  EXPECT_DOUBLE_EQ(steel.poisson, 0.25);
  EXPECT_DOUBLE_EQ(list.grains.components[0].material.young, 1e7);
  EXPECT_EQ(list.grains.components[1].radius.list.size(), 4u);   // 4 large rows
  EXPECT_EQ(list.grains.components[0].radius.list.size(), 24u);  // 24 small rows
}

TEST_F(SceneFile, UnknownKeyNamesFileLineAndAllowedKeys) {
  const std::string text = replace(kBase, "size = [0.02, 0.02]", "sise = [0.02, 0.02]");
  EXPECT_EQ(error_of(text),
            at(text, "sise") + "unknown key 'sise' in [container]; allowed: kind, size, gap, radius, height, length, ends, file, scale");
}

TEST_F(SceneFile, UnknownKeyInsideAnInlineTable) {
  const std::string text = replace(kBase, "value = 1e-3", "valeu = 1e-3");
  EXPECT_EQ(error_of(text), at(text, "valeu") +
                                "unknown key 'valeu' in grains.radius; allowed: distribution, value, min, max, values");
}

TEST_F(SceneFile, UnknownTableIsAnError) {
  const std::string text = kBase + "\n[materail]\nyoung = 1e7\n";
  EXPECT_NE(error_of(text).find(at(text, "[materail]") + "unknown key 'materail' in the top level of the file"), std::string::npos)
      << error_of(text);
}

TEST_F(SceneFile, WrongTypeNamesTheType) {
  const std::string text = replace(kBase, "count = 100", "count = \"100\"");
  EXPECT_EQ(error_of(text), at(text, "count") + "grains.count: expected a positive integer, got the string \"100\"");
}

TEST_F(SceneFile, FloatCountIsRejected) {
  const std::string text = replace(kBase, "count = 100", "count = 100.5");
  EXPECT_EQ(error_of(text), at(text, "count") + "grains.count: expected a positive integer, got 100.5");
}

TEST_F(SceneFile, CountZero) {
  const std::string text = replace(kBase, "count = 100", "count = 0");
  EXPECT_EQ(error_of(text), at(text, "count") + "grains.count: expected a positive integer, got 0");
}

TEST_F(SceneFile, MissingCount) {
  const std::string text = replace(kBase, "count = 100\n", "");
  EXPECT_EQ(error_of(text), at(text, "[grains]") + "grains.count: missing; expected a positive integer");
}

TEST_F(SceneFile, NegativeRadius) {
  const std::string text = replace(kBase, "value = 1e-3", "value = -1e-3");
  EXPECT_EQ(error_of(text), at(text, "value") + "grains.radius.value: expected a positive radius [m], got -0.001");
}

TEST_F(SceneFile, MinNotBelowMax) {
  const std::string text = replace(kBase, "{ distribution = \"constant\", value = 1e-3 }",
                                   "{ distribution = \"uniform\", min = 1e-3, max = 1e-3 }");
  EXPECT_EQ(error_of(text),
            at(text, "uniform") + "grains.radius.max: expected a radius [m] larger than min = 0.001, got 0.001");
}

TEST_F(SceneFile, KeyOfAnotherDistributionIsAnError) {
  const std::string text = replace(kBase, "value = 1e-3", "value = 1e-3, max = 2e-3");
  EXPECT_NE(error_of(text).find("grains.radius.max: not used by distribution = \"constant\""), std::string::npos)
      << error_of(text);
}

TEST_F(SceneFile, GrainWiderThanTheHeleShawGap) {
  const std::string text = replace(kBase, "kind = \"box\"\nsize = [0.02, 0.02]",
                                   "kind = \"hele-shaw\"\nsize = [0.05]\ngap = 1.5e-3");
  EXPECT_EQ(error_of(text), at(text, "gap") +
                                "container.gap: expected at least the diameter of the largest grain "
                                "(r_max = 0.001 m), 2 r_max = 0.002 m, got 0.0015");
}

TEST_F(SceneFile, GrainWiderThanTheBox) {
  const std::string text = replace(kBase, "size = [0.02, 0.02]", "size = [0.02, 0.0015]");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "size") + "container.size: expected widths of at least", 0), 0u) << msg;
}

TEST_F(SceneFile, CylinderIn2D) {
  std::string text = replace(kBase, "dimension = 3", "dimension = 2");
  text = replace(text, "kind = \"box\"\nsize = [0.02, 0.02]", "kind = \"cylinder\"\nradius = 0.01");
  EXPECT_EQ(error_of(text), at(text, "\"cylinder\"") +
                                "container.kind: expected \"open\", \"box\" or \"periodic\" for dimension 2 "
                                "(cylinder is 3D only), got \"cylinder\"");
}

// A drum's ends: "walls" (the default) or "periodic", in 3D only; anything else names the key and line.
TEST_F(SceneFile, DrumEndsAreReadAndChecked) {
  const std::string drum = replace(kBase, "kind = \"box\"\nsize = [0.02, 0.02]",
                                   "kind = \"drum\"\nradius = 0.01\nlength = 0.01");
  path_ = write("x.toml", drum);
  EXPECT_FALSE(load_scene(path_).container.periodic_ends);
  const std::string periodic = replace(drum, "length = 0.01", "length = 0.01\nends = \"periodic\"");
  path_ = write("x.toml", periodic);
  EXPECT_TRUE(load_scene(path_).container.periodic_ends);
  const std::string walls = replace(drum, "length = 0.01", "length = 0.01\nends = \"walls\"");
  path_ = write("x.toml", walls);
  EXPECT_FALSE(load_scene(path_).container.periodic_ends);

  const std::string open_ends = replace(drum, "length = 0.01", "length = 0.01\nends = \"open\"");
  EXPECT_EQ(error_of(open_ends), at(open_ends, "ends") +
                                     "container.ends: expected one of \"walls\", \"periodic\", got the string \"open\"");
  const std::string in_box = replace(kBase, "size = [0.02, 0.02]", "size = [0.02, 0.02]\nends = \"periodic\"");
  EXPECT_EQ(error_of(in_box),
            at(in_box, "ends") + "container.ends: not used by kind = \"box\" (only a 3D drum has ends)");
  std::string in_2d = replace(kBase, "dimension = 3", "dimension = 2");
  in_2d = replace(in_2d, "kind = \"box\"\nsize = [0.02, 0.02]", "kind = \"drum\"\nradius = 0.01\nends = \"periodic\"");
  EXPECT_EQ(error_of(in_2d),
            at(in_2d, "ends") + "container.ends: not used by kind = \"drum\" in 2D (only a 3D drum has ends)");
}

TEST_F(SceneFile, SizeVectorOfTheWrongLength) {
  const std::string text = replace(kBase, "dimension = 3", "dimension = 2");
  EXPECT_EQ(error_of(text), at(text, "size") +
                                "container.size: expected [x] for dimension 2: the positive width [m], "
                                "got an array of 2");
}

TEST_F(SceneFile, FractionsNotSummingToOne) {
  const std::string text = replace(kBase, "radius = { distribution = \"constant\", value = 1e-3 }\n",
                                   "radius = { distribution = \"constant\", value = 1e-3 }\n"
                                   "[[grains.component]]\nspecies = 1\nfraction = 0.5\n"
                                   "[[grains.component]]\nspecies = 2\nfraction = 0.4\n");
  EXPECT_EQ(error_of(text), at(text, "[[grains.component]]") +
                                "grains.component: expected fractions summing to 1 (within 1e-9), got a sum of 0.9");
}

TEST_F(SceneFile, DuplicateSpecies) {
  const std::string text = replace(kBase, "radius = { distribution = \"constant\", value = 1e-3 }\n",
                                   "radius = { distribution = \"constant\", value = 1e-3 }\n"
                                   "[[grains.component]]\nspecies = 2\nfraction = 0.5\n"
                                   "[[grains.component]]\nspecies = 2 # again\nfraction = 0.5\n");
  EXPECT_EQ(error_of(text), at(text, "species = 2 # again") +
                                "grains.component#2.species: expected distinct species ids 1..2, got 2 twice");
}

TEST_F(SceneFile, RestitutionZero) {
  const std::string text = kBase + "\n[material]\nrestitution = 0.0\n";
  EXPECT_EQ(error_of(text), at(text, "restitution") + "material.restitution: expected a restitution in (0, 1], got 0");
}

TEST_F(SceneFile, PoissonOutOfRange) {
  const std::string text = kBase + "\n[material]\npoisson = 0.5\n";
  EXPECT_EQ(error_of(text),
            at(text, "poisson") + "material.poisson: expected a Poisson ratio in (-1, 0.5), got 0.5");
}

TEST_F(SceneFile, RainOnAnOpenFloor) {
  const std::string text = replace(kBase, "kind = \"box\"\nsize = [0.02, 0.02]", "kind = \"open\"");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "\"rain\"") + "source.kind: expected \"point\" or \"region\" on an open floor", 0),
            0u)
      << msg;
}

TEST_F(SceneFile, PointSourceOutsideTheBox) {
  // Half-width 0.01, r = 0.001: centres must satisfy |x| + scatter <= 0.009.
  const std::string text = replace(kBase, "kind = \"rain\"", "kind = \"point\"\nposition = [0.0085, 0.0]\nscatter = 0.001");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "position") + "source.position: expected drops", 0), 0u) << msg;
  const std::string inside = replace(kBase, "kind = \"rain\"", "kind = \"point\"\nposition = [0.0075, 0.0]\nscatter = 0.001");
  EXPECT_EQ(error_of(inside), "");
}

TEST_F(SceneFile, RegionOutsideTheCylinder) {
  // Corner (0.006, 0.006) is 0.00849 from the axis; R - r = 0.008.
  const std::string text = replace(replace(kBase, "kind = \"box\"\nsize = [0.02, 0.02]", "kind = \"cylinder\"\nradius = 0.009"),
                                   "kind = \"rain\"", "kind = \"region\"\nx = [-0.006, 0.006]\ny = [-0.006, 0.006]");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "x = [") + "source.x, source.y: expected a region", 0), 0u) << msg;
  // The same region fits a wider cylinder.
  EXPECT_EQ(error_of(replace(text, "radius = 0.009", "radius = 0.0096")), "");
}

TEST_F(SceneFile, ListFileMissing) {
  std::string text = replace(kBase, "kind = \"rain\"", "kind = \"list\"\nfile = \"nope.csv\"");
  text = replace(text, "radius = { distribution = \"constant\", value = 1e-3 }\n", "");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg, at(text, "nope.csv") + "source.file: cannot open '" + (dir_ / "nope.csv").string() + "'");
}

TEST_F(SceneFile, ListFileMalformedNamesItsLine) {
  const std::string csv = write("d.csv", "x,y,r\n0,0,1e-3\n0.001,abc,1e-3\n");
  std::string text = replace(kBase, "kind = \"rain\"", "kind = \"list\"\nfile = \"d.csv\"");
  text = replace(text, "radius = { distribution = \"constant\", value = 1e-3 }\n", "");
  EXPECT_EQ(error_of(text), csv + ":3: y: expected a number, got 'abc'");
}

TEST_F(SceneFile, ListDropOutsideTheBox) {
  const std::string csv = write("d.csv", "# comment\n0,0,1e-3\n0.0095,0,1e-3\n");
  std::string text = replace(kBase, "kind = \"rain\"", "kind = \"list\"\nfile = \"d.csv\"");
  text = replace(text, "count = 100\n", "");
  text = replace(text, "radius = { distribution = \"constant\", value = 1e-3 }\n", "");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(csv + ":3: expected a drop that keeps its grain", 0), 0u) << msg;
}

TEST_F(SceneFile, ListCountLargerThanTheFile) {
  write("d.csv", "0,0,1e-3\n0.001,0,1e-3\n");
  std::string text = replace(kBase, "kind = \"rain\"", "kind = \"list\"\nfile = \"d.csv\"");
  text = replace(text, "radius = { distribution = \"constant\", value = 1e-3 }\n", "");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "count") + "grains.count: expected at most the 2 rows of", 0), 0u) << msg;
}

TEST_F(SceneFile, RadiusWithAListSourceIsAnError) {
  write("d.csv", "0,0,1e-3\n");
  const std::string text = replace(replace(kBase, "kind = \"rain\"", "kind = \"list\"\nfile = \"d.csv\""),
                                   "count = 100\n", "");
  EXPECT_EQ(error_of(text).rfind(at(text, "radius") + "grains.radius: not used with source.kind = \"list\"", 0), 0u)
      << error_of(text);
}

TEST_F(SceneFile, RelaxStopRuleDampingAndMarginAreReadAndChecked) {
  const std::string good = kBase + "\n[relax]\nstop_rule = \"unbalanced-force\"\nstop_unbalanced_force = 5e-4\n"
                                   "stop_displacement = 2e-3\ndamping = 0.2\nopen_margin = 4\nopen_heap_angle = 30\n";
  path_ = write("x.toml", good);
  const Scene s = load_scene(path_);
  EXPECT_EQ(s.relax.stop_rule, "unbalanced-force");
  EXPECT_EQ(s.relax.stop_unbalanced_force, 5e-4);
  EXPECT_EQ(s.relax.stop_displacement, 2e-3);
  EXPECT_EQ(s.relax.damping, 0.2);
  EXPECT_EQ(s.relax.open_margin, 4.0);
  EXPECT_EQ(s.relax.open_heap_angle, 30.0);
  const Scene d = load_scene(write("d.toml", kBase));
  EXPECT_EQ(d.relax.stop_rule, "kinetic-energy");
  EXPECT_EQ(d.relax.damping, 0.0) << "damping is off by default";

  std::string text = kBase + "\n[relax]\nstop_rule = \"still\"\n";
  std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "stop_rule") + "relax.stop_rule", 0), 0u) << msg;
  EXPECT_NE(msg.find("unbalanced-force"), std::string::npos) << msg;
  text = kBase + "\n[relax]\ndamping = 1.0\n";
  msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "damping") + "relax.damping", 0), 0u) << msg;
  EXPECT_NE(msg.find("[0, 1)"), std::string::npos) << msg;
  text = kBase + "\n[relax]\nstop_unbalanced_force = 0\n";
  EXPECT_NE(error_of(text).find("relax.stop_unbalanced_force"), std::string::npos);
  text = kBase + "\n[relax]\nstop_displacement = 2\n";
  EXPECT_NE(error_of(text).find("relax.stop_displacement"), std::string::npos);
  text = kBase + "\n[relax]\nopen_margin = -1\n";
  EXPECT_NE(error_of(text).find("relax.open_margin"), std::string::npos);
  for (const char* angle : {"0", "90", "-5"}) {
    text = kBase + "\n[relax]\nopen_heap_angle = " + angle + "\n";
    msg = error_of(text);
    EXPECT_EQ(msg.rfind(at(text, "open_heap_angle") + "relax.open_heap_angle", 0), 0u) << msg;
    EXPECT_NE(msg.find("(0, 90)"), std::string::npos) << msg;
  }
}

TEST_F(SceneFile, RelaxPreloadIsABoolean) {
  EXPECT_FALSE(load_scene(write("d.toml", kBase)).relax.preload) << "off by default";
  EXPECT_TRUE(load_scene(write("p.toml", kBase + "\n[relax]\npreload = true\n")).relax.preload);
  const std::string text = kBase + "\n[relax]\npreload = 1\n";
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "preload") + "relax.preload", 0), 0u) << msg;
  EXPECT_NE(msg.find("true or false"), std::string::npos) << msg;
}

TEST_F(SceneFile, TargetPhiCompactionKeys) {
  const Scene d = load_scene(write("d.toml", kBase));
  EXPECT_FALSE(d.relax.target_phi.has_value());
  EXPECT_EQ(d.relax.friction_scales, (std::vector<double>{0.0}));
  EXPECT_EQ(d.relax.compaction_damping, 0.15);
  const Scene s = load_scene(write("t.toml", kBase + "\n[relax]\ntarget_phi = 0.62\nfriction_scales = [0.5, 0]\n"
                                                        "compaction_damping = 0\ncompaction_timestep_fraction = 0.4\n"));
  EXPECT_EQ(*s.relax.target_phi, 0.62);
  EXPECT_EQ(s.relax.friction_scales, (std::vector<double>{0.5, 0.0}));
  EXPECT_EQ(s.relax.compaction_damping, 0.0);
  EXPECT_EQ(*s.relax.compaction_timestep_fraction, 0.4);
  EXPECT_FALSE(d.relax.compaction_timestep_fraction.has_value());
  std::string text = kBase + "\n[relax]\nfriction_scales = [0.2, 0.4]\n";
  EXPECT_NE(error_of(text).find("relax.friction_scales: expected decreasing scales"), std::string::npos) << error_of(text);
  text = kBase + "\n[relax]\nfriction_scales = [1.0]\n";
  EXPECT_EQ(error_of(text).rfind(at(text, "friction_scales") + "relax.friction_scales", 0), 0u) << error_of(text);
  text = kBase + "\n[relax]\ncompaction_timestep_fraction = 1.5\n";
  EXPECT_EQ(error_of(text).rfind(at(text, "compaction_timestep_fraction") + "relax.compaction_timestep_fraction", 0), 0u)
      << error_of(text);
  text = kBase + "\n[relax]\ncompaction_damping = 1\n";
  EXPECT_EQ(error_of(text).rfind(at(text, "compaction_damping") + "relax.compaction_damping", 0), 0u) << error_of(text);
}

TEST_F(SceneFile, TomlSyntaxErrorNamesTheLine) {
  const std::string text = replace(kBase, "count = 100", "count = = 100");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(at(text, "count") + "TOML syntax error", 0), 0u) << msg;
}

TEST_F(SceneFile, MissingTable) {
  const std::string text = replace(kBase, "[source]\nkind = \"rain\"\n", "");
  EXPECT_EQ(error_of(text), path_ + ": missing table [source]");
}

TEST_F(SceneFile, MissingFile) {
  try {
    load_scene((dir_ / "absent.toml").string());
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), (dir_ / "absent.toml").string() + ": cannot open the scene file");
  }
}

// relax.model = "hooke-stiffness" takes kn, kt, gamma_n, gamma_t, wall_gamma_t from [material];
// the other models refuse them, and hooke-stiffness refuses to run without kn and kt.
TEST_F(SceneFile, HookeStiffnessMaterial) {
  const std::string stiff = std::string(kBase) +
                            "\n[material]\nkn = 24.6\nkt = 7.0\ngamma_n = 4952.0\nwall_gamma_t = 4900.0\n"
                            "\n[relax]\nmodel = \"hooke-stiffness\"\n";
  path_ = write("x.toml", stiff);
  const Scene s = load_scene(path_);
  const Material& m = s.grains.components[0].material;
  EXPECT_EQ(s.relax.model, "hooke-stiffness");
  EXPECT_DOUBLE_EQ(m.kn, 24.6);
  EXPECT_DOUBLE_EQ(m.kt, 7.0);
  EXPECT_DOUBLE_EQ(m.gamma_n, 4952.0);
  EXPECT_DOUBLE_EQ(m.gamma_t, 0.0);
  EXPECT_DOUBLE_EQ(m.wall_gamma_t, 4900.0);
  // wall_gamma_t defaults to gamma_t
  const std::string same = replace(stiff, "wall_gamma_t = 4900.0", "gamma_t = 3.0");
  path_ = write("x.toml", same);
  EXPECT_DOUBLE_EQ(load_scene(path_).grains.components[0].material.wall_gamma_t, 3.0);

  const std::string no_kt = replace(stiff, "kt = 7.0\n", "");
  EXPECT_NE(error_of(no_kt).find("relax.model = \"hooke-stiffness\" needs kn and kt"), std::string::npos)
      << error_of(no_kt);
  const std::string negative = replace(stiff, "gamma_n = 4952.0", "gamma_n = -1.0");
  EXPECT_EQ(error_of(negative).rfind(at(negative, "gamma_n = -1.0") +
                                         "material.gamma_n: expected a normal damping rate >= 0 [1/s], got", 0),
            0u)
      << error_of(negative);
  const std::string hertz = replace(stiff, "model = \"hooke-stiffness\"", "model = \"hertz\"");
  EXPECT_NE(error_of(hertz).find("material.kn: not used unless relax.model = \"hooke-stiffness\""), std::string::npos)
      << error_of(hertz);
}

}  // namespace
}  // namespace btr
