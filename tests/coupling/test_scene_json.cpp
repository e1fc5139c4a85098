// Scene <-> JSON: every field survives, and bad JSON is named precisely.
#include <gtest/gtest.h>

#include <filesystem>

#include "btr/scene/scene_toml.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/io/scene_json.h"

namespace btr {
namespace {

Scene everything_set() {
  Scene s;
  s.name = "mix";
  s.file = "inputs/mix.toml";
  s.dimension = 2;
  s.seed = 18446744073709551615ull;
  s.grains.count = 1234;
  s.grains.fraction_by = GrainsSpec::FractionBy::Volume;
  Component a, b;
  a.species = 1, a.fraction = 0.3, a.density = 2500.5;
  a.radius.kind = RadiusSpec::Kind::ConstantMass, a.radius.min = 0.1 + 0.2, a.radius.max = 1.0 / 3.0;
  a.material = {1e7, 0.25, 0.4, 0.6, 0.05};
  b.species = 2, b.fraction = 0.7, b.density = 7800;
  b.radius.kind = RadiusSpec::Kind::List, b.radius.list = {1e-3, 2e-3, 1.5e-3};
  b.material = {2e11, 0.29, 0.9, 0.2, 0.0};
  s.grains.components = {a, b};
  s.container.kind = ContainerKind::HeleShaw;
  s.container.size_x = 0.1, s.container.size_y = 0.02, s.container.gap = 3e-3, s.container.radius = 0.5,
  s.container.height = 0.06;
  s.source.kind = SourceSpec::Kind::Region;
  s.source.x = 0.01, s.source.y = -0.02, s.source.scatter = 1e-3;
  s.source.x_min = -0.05, s.source.x_max = -0.04, s.source.y_min = -1e-3, s.source.y_max = 1e-3;
  s.source.file = "drops.csv";
  s.relax.engine = "yade", s.relax.model = "hooke", s.relax.max_time = 0.5, s.relax.stop_kinetic_ratio = 1e-7;
  s.relax.timestep_fraction = 0.15, s.relax.timestep = 1e-6;
  s.relax.stop_rule = "displacement", s.relax.stop_unbalanced_force = 2e-4, s.relax.stop_displacement = 3e-3;
  s.relax.damping = 0.25, s.relax.open_margin = 7.5;
  s.relax.preload = true;
  s.relax.target_phi = 0.61, s.relax.friction_scales = {0.3, 0.1, 0.0}, s.relax.compaction_damping = 0.05;
  s.relax.compaction_timestep_fraction = 0.35;
  return s;
}

TEST(SceneJson, EveryFieldSurvivesATextRoundTrip) {
  const Scene s = everything_set();
  const nlohmann::json j = scene_to_json(s);
  const Scene t = scene_from_json(nlohmann::json::parse(j.dump(2)), "test");
  EXPECT_EQ(t.name, s.name);
  EXPECT_EQ(t.file, s.file);
  EXPECT_EQ(t.dimension, 2);
  EXPECT_EQ(t.seed, s.seed);
  EXPECT_EQ(t.grains.count, 1234);
  EXPECT_EQ(t.grains.fraction_by, GrainsSpec::FractionBy::Volume);
  ASSERT_EQ(t.grains.components.size(), 2u);
  const Component& a = t.grains.components[0];
  const Component& b = t.grains.components[1];
  EXPECT_EQ(a.radius.kind, RadiusSpec::Kind::ConstantMass);
  EXPECT_EQ(a.radius.min, 0.1 + 0.2);  // exact: JSON numbers round-trip
  EXPECT_EQ(a.radius.max, 1.0 / 3.0);
  EXPECT_EQ(a.material.rolling_friction, 0.05);
  EXPECT_EQ(b.species, 2);
  EXPECT_EQ(b.fraction, 0.7);
  EXPECT_EQ(b.density, 7800);
  EXPECT_EQ(b.radius.list, (std::vector<double>{1e-3, 2e-3, 1.5e-3}));
  EXPECT_EQ(b.material.young, 2e11);
  EXPECT_EQ(t.container.kind, ContainerKind::HeleShaw);
  EXPECT_EQ(t.container.gap, 3e-3);
  EXPECT_EQ(t.container.height, 0.06);
  EXPECT_EQ(t.source.kind, SourceSpec::Kind::Region);
  EXPECT_EQ(t.source.scatter, 1e-3);
  EXPECT_EQ(t.source.y_max, 1e-3);
  EXPECT_EQ(t.source.file, "drops.csv");
  EXPECT_EQ(t.relax.engine, "yade");
  EXPECT_EQ(t.relax.model, "hooke");
  ASSERT_TRUE(t.relax.timestep.has_value());
  EXPECT_EQ(*t.relax.timestep, 1e-6);
  EXPECT_EQ(t.relax.stop_rule, "displacement");
  EXPECT_EQ(t.relax.stop_unbalanced_force, 2e-4);
  EXPECT_EQ(t.relax.stop_displacement, 3e-3);
  EXPECT_EQ(t.relax.damping, 0.25);
  EXPECT_EQ(t.relax.open_margin, 7.5);
  EXPECT_TRUE(t.relax.preload);
  EXPECT_EQ(t.relax.target_phi, 0.61);
  EXPECT_EQ(t.relax.friction_scales, (std::vector<double>{0.3, 0.1, 0.0}));
  EXPECT_EQ(t.relax.compaction_damping, 0.05);
  EXPECT_EQ(t.relax.compaction_timestep_fraction, 0.35);
  // A packing written before these keys existed reads with their defaults.
  nlohmann::json old = j;
  for (const char* k : {"stop_rule", "stop_unbalanced_force", "stop_displacement", "damping", "open_margin", "preload",
                        "target_phi", "friction_scales", "compaction_damping", "compaction_timestep_fraction"})
    old["relax"].erase(k);
  const Scene o = scene_from_json(old, "old");
  EXPECT_EQ(o.relax.stop_rule, "kinetic-energy");
  EXPECT_EQ(o.relax.damping, 0.0);
  EXPECT_EQ(o.relax.open_margin, 10.0);
  EXPECT_FALSE(o.relax.preload);
  EXPECT_FALSE(o.relax.target_phi.has_value());
  EXPECT_EQ(o.relax.friction_scales, (std::vector<double>{0.0}));
  EXPECT_EQ(o.relax.compaction_damping, 0.15);
  EXPECT_FALSE(o.relax.compaction_timestep_fraction.has_value());
  EXPECT_EQ(scene_to_json(t), j);

  Scene no_step = s;
  no_step.relax.timestep.reset();
  EXPECT_FALSE(scene_from_json(scene_to_json(no_step), "test").relax.timestep.has_value());
}

TEST(SceneJson, EveryShippedSceneRoundTrips) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(std::string(BTR_SOURCE_DIR) + "/inputs")) {
    if (e.path().extension() != ".toml") continue;
    const Scene s = load_scene(e.path().string());
    const nlohmann::json j = scene_to_json(s);
    EXPECT_EQ(scene_to_json(scene_from_json(j, e.path().string())), j) << e.path();
    ++n;
  }
  EXPECT_GT(n, 0);
}

std::string error_of(const nlohmann::json& j) {
  try {
    scene_from_json(j, "out/p.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneJson, ErrorsNameTheOriginAndTheKey) {
  const nlohmann::json good = scene_to_json(everything_set());
  nlohmann::json j = good;
  j["grains"]["components"][1]["radius"]["sise"] = 1;
  std::string msg = error_of(j);
  EXPECT_NE(msg.find("out/p.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("grains.components[1].radius.sise"), std::string::npos) << msg;
  EXPECT_NE(msg.find("allowed keys: kind, value, min, max, list"), std::string::npos) << msg;

  j = good;
  j["container"].erase("gap");
  EXPECT_NE(error_of(j).find("'container.gap': missing"), std::string::npos) << error_of(j);

  j = good;
  j["grains"]["count"] = "many";
  EXPECT_NE(error_of(j).find("'grains.count': expected an integer"), std::string::npos) << error_of(j);

  j = good;
  j["source"]["kind"] = "hose";
  EXPECT_NE(error_of(j).find("expected point, rain, region or list"), std::string::npos) << error_of(j);

  j = good;
  j["dimension"] = 4;
  EXPECT_NE(error_of(j).find("'dimension': expected 2 or 3"), std::string::npos) << error_of(j);
}

}  // namespace
}  // namespace btr

namespace btr {
namespace {

// A drum's ends and speed survive the JSON (a reader that dropped them would read "walls" back), ends are
// refused on another container, and the DEM walls of a drum are its surface alone: the exact cylinder, and the
// end walls only when it has them.
TEST(SceneJson, DrumEndsRoundTripAndDemWalls) {
  Scene s = load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/drum3d_periodic.toml");
  ASSERT_TRUE(s.container.periodic_ends);
  nlohmann::json j = scene_to_json(s);
  EXPECT_EQ(j["container"]["ends"], "periodic");
  EXPECT_TRUE(scene_from_json(j, "p.json").container.periodic_ends);
  j["container"]["ends"] = "walls";
  EXPECT_FALSE(scene_from_json(j, "p.json").container.periodic_ends);
  j["container"]["ends"] = "open";
  EXPECT_NE(error_of(j).find("'container.ends': expected \"walls\" or \"periodic\""), std::string::npos) << error_of(j);
  nlohmann::json box = scene_to_json(everything_set());
  EXPECT_FALSE(box["container"].contains("ends"));
  box["container"]["ends"] = "periodic";
  EXPECT_NE(error_of(box).find("in a hele-shaw container"), std::string::npos) << error_of(box);

  s.drum->froude = 0.004;
  EXPECT_EQ(scene_from_json(scene_to_json(s), "p.json").drum->froude, 0.004);
  EXPECT_FALSE(scene_from_json(scene_to_json(s), "p.json").drum->rpm);
  const double R = s.container.radius, half = 0.5 * s.container.size_y;
  s.container.periodic_ends = true;
  try {
    dem_walls(s.container, 3);
    ADD_FAILURE() << "a drum with periodic ends was exported";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("container 'drum' (periodic ends)"), std::string::npos) << e.what();
  }
  for (bool periodic : {false}) {
    s.container.periodic_ends = periodic;
    const std::vector<DemWall> walls = dem_walls(s.container, 3);
    ASSERT_EQ(walls.size(), 1u);  // no floor: the drum's lowest line turns with it
    EXPECT_EQ(walls[0].name, "drum");
    EXPECT_NEAR(walls[0].distance(Vec3(0.0, 0.0, R)), periodic ? R : std::min(R, half), 1e-15);
    EXPECT_NEAR(walls[0].distance(Vec3(0.3 * R, 0.0, R - 0.4 * R)), periodic ? 0.5 * R : std::min(0.5 * R, half), 1e-15);
    EXPECT_LT(walls[0].distance(Vec3(0.0, 0.0, -1e-4)), 0.0);  // below the lowest line: outside
    EXPECT_EQ(walls[0].distance(Vec3(0.0, half * 1.01, R)) < 0.0, !periodic);  // beyond an end wall
  }
}

TEST(SceneJson, TapGammaAndFrequencyRoundTripAndAreWrittenOnlyWhenSet) {
  Scene s = everything_set();
  s.shaking = ShakingSpec{};
  s.shaking->cycles = 5;
  s.shaking->lift = 1e-3;
  s.shaking->snapshot_every = 1;
  const nlohmann::json unset = scene_to_json(s);
  EXPECT_FALSE(unset["shaking"].contains("gamma"));  // dynamic BTR's records stay as they were
  EXPECT_FALSE(scene_from_json(unset, "test").shaking->gamma);
  s.shaking->gamma = 2.5;
  s.shaking->frequency = 1.0 / 3.0;
  const Scene t = scene_from_json(nlohmann::json::parse(scene_to_json(s).dump(2)), "test");
  ASSERT_TRUE(t.shaking && t.shaking->gamma && t.shaking->frequency);
  EXPECT_EQ(*t.shaking->gamma, 2.5);
  EXPECT_EQ(*t.shaking->frequency, 1.0 / 3.0);
}

}  // namespace
}  // namespace btr
