// `btr settle`'s plan (coupling/dem/settle_plan.h): the scenes it refuses, named by file and field; the
// calibration cell's size and grain count against hand arithmetic; the relaxation settings it chooses.
#include <gtest/gtest.h>

#include <cmath>

#include "coupling/dem/relax_plan.h"
#include "coupling/dem/relax_target.h"
#include "coupling/dem/settle_plan.h"

namespace btr {
namespace {

Scene bed(int dimension) {
  Scene s;
  s.name = "bed";
  s.file = "/scenes/bed.toml";
  s.dimension = dimension;
  s.grains.count = 1000;
  Component c;
  c.radius.kind = RadiusSpec::Kind::Constant;
  c.radius.value = 1e-3;
  s.grains.components = {c};
  s.container.kind = ContainerKind::Periodic;
  s.container.size_x = 0.03;
  s.container.size_y = dimension == 3 ? 0.03 : 0.0;
  s.source.kind = SourceSpec::Kind::Rain;
  return s;
}

// The refusal's message, or "" when the scene is served.
std::string refusal(const Scene& s) {
  try {
    check_settle_scene(s);
    return "";
  } catch (const RelaxRefused& e) {
    return e.what();
  }
}

TEST(SettlePlan, ServesBedsInPeriodicBoxAndCylinderContainers) {
  for (ContainerKind k : {ContainerKind::Periodic, ContainerKind::Box, ContainerKind::Cylinder}) {
    Scene s = bed(3);
    s.container.kind = k;
    s.container.radius = 0.015;
    EXPECT_EQ(refusal(s), "");
  }
}

TEST(SettlePlan, ServesHeapsFromPointSourcesAndRegionSourcesWhereTheirAngleIsMeasured) {
  struct Case {
    int dimension;
    ContainerKind container;
    SourceSpec::Kind source;
  };
  const Case served[] = {
      {3, ContainerKind::Open, SourceSpec::Kind::Point},     {3, ContainerKind::HeleShaw, SourceSpec::Kind::Point},
      {3, ContainerKind::Box, SourceSpec::Kind::Point},      {3, ContainerKind::Cylinder, SourceSpec::Kind::Point},
      {3, ContainerKind::HeleShaw, SourceSpec::Kind::Region}, {2, ContainerKind::Open, SourceSpec::Kind::Region},
      {2, ContainerKind::Box, SourceSpec::Kind::Point},
  };
  for (const Case& c : served) {
    Scene s = bed(c.dimension);
    s.container.kind = c.container;
    s.source.kind = c.source;
    EXPECT_EQ(refusal(s), "");
    EXPECT_TRUE(settle_builds_heap(s));
  }
  EXPECT_FALSE(settle_builds_heap(bed(3)));
}

TEST(SettlePlan, RefusesWhatItCannotMeasureAndDynamicScenesNamingFileAndField) {
  struct Case {
    const char* field;
    void (*make)(Scene&);
  };
  const Case cases[] = {
      {"source.kind", [](Scene& s) { s.container.kind = ContainerKind::HeleShaw; }},  // rain between plates
      {"container.kind", [](Scene& s) { s.container.kind = ContainerKind::Drum; }},
      {"container.kind", [](Scene& s) { s.container.kind = ContainerKind::Mesh; }},
      {"source.kind", [](Scene& s) { s.source.kind = SourceSpec::Kind::List; }},
      {"source.kind", [](Scene& s) { s.container.kind = ContainerKind::Open, s.source.kind = SourceSpec::Kind::Region; }},
      {"[clusters]", [](Scene& s) { s.clusters = ClustersSpec{}; }},
      {"[shaking]", [](Scene& s) { s.shaking = ShakingSpec{}; }},
      {"[intruder]", [](Scene& s) { s.intruder = IntruderSpec{}; }},
  };
  for (const Case& c : cases) {
    Scene s = bed(3);
    c.make(s);
    const std::string why = refusal(s);
    SCOPED_TRACE(c.field);
    EXPECT_EQ(why.rfind("/scenes/bed.toml: ", 0), 0u) << why;
    EXPECT_NE(why.find(c.field), std::string::npos) << why;
  }
}

TEST(SettlePlan, CalibrationCellOfEqualSpheresIsTenDiametersWideAndTenDeep) {
  Scene s = bed(3);
  s.seed = 7;
  s.relax.target_phi = 0.7;  // a scene's own target is not the calibration's
  const CalibrationPlan p = calibration_plan(s);
  const double d = 2e-3, v = 4.0 / 3.0 * M_PI * 1e-9;
  EXPECT_DOUBLE_EQ(p.largest_diameter, d);
  EXPECT_DOUBLE_EQ(p.width, 10 * d);  // 10 mean diameters beat 5 largest ones
  EXPECT_NEAR(p.mean_grain_volume, v, 1e-24);
  // 0.6 (10 d)^2 (10 d) / (pi d^3 / 6) = 600 / (pi / 6) = 1145.9..., rounded up
  EXPECT_EQ(p.grains, 1146);
  EXPECT_EQ(p.scene.grains.count, 1146);
  EXPECT_EQ(p.scene.container.kind, ContainerKind::Periodic);
  EXPECT_DOUBLE_EQ(p.scene.container.size_x, 10 * d);
  EXPECT_DOUBLE_EQ(p.scene.container.size_y, 10 * d);
  EXPECT_EQ(p.scene.source.kind, SourceSpec::Kind::Rain);
  EXPECT_FALSE(p.scene.relax.target_phi.has_value());
  EXPECT_EQ(p.scene.seed, 7u);
}

TEST(SettlePlan, CalibrationCellOfAWideMixtureIsFiveLargestDiametersWide) {
  Scene s = bed(3);
  RadiusSpec& r = s.grains.components[0].radius;
  r.kind = RadiusSpec::Kind::ConstantMass;
  r.min = 0.25e-3;
  r.max = 1e-3;
  // number-mean radius of the constant-mass law on [a, b]: a b ln(b / a) / (b - a) = 0.462 mm, so 10 mean
  // diameters are 9.24 mm, under 5 largest ones (10 mm)
  EXPECT_LT(10 * 2 * 0.25e-3 * 1e-3 * std::log(4.0) / 0.75e-3, 10e-3);
  EXPECT_DOUBLE_EQ(calibration_plan(s).width, 10e-3);
  r.min = 0.5e-3;  // a ratio of 2: mean radius 0.693 mm, 10 mean diameters 13.9 mm
  const double mean_r = 0.5e-3 * 1e-3 * std::log(2.0) / 0.5e-3;
  EXPECT_NEAR(calibration_plan(s).width, 10 * 2 * mean_r, 1e-15);
}

TEST(SettlePlan, Calibration3dStepsAtTheMeasuredFractionUnlessTheSceneAsksForMore) {
  Scene s = bed(3);
  ASSERT_LT(s.relax.timestep_fraction, kCalibrationTimestepFraction3d);
  CalibrationPlan p = calibration_plan(s);
  EXPECT_EQ(p.scene.relax.timestep_fraction, kCalibrationTimestepFraction3d);
  EXPECT_EQ(p.record["timestep_fraction"]["value"].get<double>(), kCalibrationTimestepFraction3d);
  s.relax.timestep_fraction = 0.5;  // a coarser step of the scene's own is kept
  EXPECT_EQ(calibration_plan(s).scene.relax.timestep_fraction, 0.5);
  s.relax.timestep_fraction = 0.1;
  s.relax.timestep = 1e-6;  // so is an explicit step
  p = calibration_plan(s);
  EXPECT_EQ(p.scene.relax.timestep_fraction, 0.1);
  EXPECT_EQ(p.scene.relax.timestep, 1e-6);
  EXPECT_NE(p.record["timestep_fraction"]["from"].get<std::string>().find("relax.timestep"), std::string::npos);
  Scene flat = bed(2);  // 2D: measured in 3D only, so the scene's
  EXPECT_EQ(calibration_plan(flat).scene.relax.timestep_fraction, flat.relax.timestep_fraction);
}

TEST(SettlePlan, CalibrationPourStopsAtItsOwnKineticRatioNotTheScenes) {
  Scene s = bed(3);
  s.relax.stop_kinetic_ratio = 1e-6;
  const CalibrationPlan p = calibration_plan(s);
  ASSERT_NE(kCalibrationStopRatio, s.relax.stop_kinetic_ratio);
  EXPECT_EQ(pour_scene(p.scene, PourSettings{}).relax.stop_kinetic_ratio, kCalibrationStopRatio);
  EXPECT_EQ(p.record["stop_kinetic_ratio"]["value"].get<double>(), kCalibrationStopRatio);
  EXPECT_EQ(settle_choices(s, 0.63, {}, 14.0).scene.relax.stop_kinetic_ratio, 1e-6);  // the relaxation keeps the scene's
}

TEST(SettlePlan, CalibrationOfA2dMixtureCountsEachComponentsArea) {
  Scene s = bed(2);
  Component big = s.grains.components[0];
  big.species = 2;
  big.radius.value = 2e-3;
  s.grains.components[0].fraction = 0.75;
  big.fraction = 0.25;
  s.grains.components.push_back(big);
  const CalibrationPlan p = calibration_plan(s);
  const double d = 4e-3, area = 0.75 * M_PI * 1e-6 + 0.25 * M_PI * 4e-6;  // number-weighted mean disk area
  EXPECT_DOUBLE_EQ(p.width, 20 * d);
  EXPECT_NEAR(p.mean_grain_volume, area, 1e-18);
  EXPECT_EQ(p.grains, static_cast<std::int64_t>(std::ceil(0.8 * (20 * d) * (10 * d) / area)));  // 466
  EXPECT_EQ(p.scene.container.size_y, 0.0);
}

TEST(SettlePlan, CalibrationGrainsCanBeGivenButNotTooFew) {
  EXPECT_EQ(calibration_plan(bed(3), 120).grains, 120);
  try {
    calibration_plan(bed(3), 10);
    FAIL() << "10 calibration grains accepted";
  } catch (const RelaxRefused& e) {
    EXPECT_NE(std::string(e.what()).find("--calibration-grains"), std::string::npos) << e.what();
  }
}

TEST(SettlePlan, BedDepthIsTheSolidVolumeOverTheFloorAtThePackingFraction) {
  Scene s = bed(3);  // 3 cm x 3 cm floor
  Grains g(1000);
  for (Grain& x : g) x.r = 1e-3;
  // 1000 (4/3 pi mm^3) / (900 mm^2 0.5) = 9.308 mm, in 2 mm diameters
  EXPECT_NEAR(bed_depth_in_largest_diameters(g, s, 0.5), 4000.0 / 3.0 * M_PI / 450.0 / 2.0, 1e-9);
  s.container.kind = ContainerKind::Cylinder;
  s.container.radius = 0.01;
  EXPECT_NEAR(bed_depth_in_largest_diameters(g, s, 0.5), 4000.0 / 3.0 * M_PI / (M_PI * 100.0 * 0.5) / 2.0, 1e-9);
}

// One measured value at every depth; the record says when the bed lies away from the depth it was measured at.
TEST(SettlePlan, CompactionDampingIsTheMeasuredValueAndSaysWhereItWasMeasured) {
  const Scene s = bed(3);
  for (double depth : {5.0, 14.1, 42.3})
    EXPECT_EQ(*settle_choices(s, 0.63, {}, depth).settings.compaction_damping, kCompactionDamping);
  const std::string away = settle_choices(s, 0.63, {}, 42.3).record["compaction_damping"]["from"];
  EXPECT_NE(away.find("not measured there"), std::string::npos) << away;
  const std::string near = settle_choices(s, 0.63, {}, 15.0).record["compaction_damping"]["from"];
  EXPECT_EQ(near.find("not measured"), std::string::npos) << near;
  EXPECT_NE(near.find("this bed: 15 largest diameters"), std::string::npos) << near;
}

// YADE's value for a bed compacted at once was measured at three depths (after YADE's collider fix), 0.71 at 9.4
// largest diameters, 0.78 at 14.1 and 0.75 at 19.7: linear between, the nearer value outside, and the record says
// when the bed lies outside them; a bed compacted in slabs (deeper than 21.15) takes the slabs' 0.5 at any depth.
TEST(SettlePlan, YadeCompactionDampingFollowsTheBedsDepthBetweenTheThreeMeasured) {
  constexpr double deep = 0.75;
  Scene y = bed(3);
  y.relax.engine = "yade";
  auto damping = [&](double depth) { return *settle_choices(y, 0.63, {}, depth).settings.compaction_damping; };
  auto from = [&](double depth) -> std::string { return settle_choices(y, 0.63, {}, depth).record["compaction_damping"]["from"]; };
  EXPECT_DOUBLE_EQ(damping(14.1), 0.78);
  EXPECT_DOUBLE_EQ(damping(9.4), 0.71);
  EXPECT_NEAR(damping(0.5 * (9.4 + 14.1)), 0.745, 1e-12);  // half way: half way
  EXPECT_NEAR(damping(9.7), 0.71 + 0.07 * 0.3 / 4.7, 1e-12);
  EXPECT_DOUBLE_EQ(damping(19.7), deep);
  EXPECT_NEAR(damping(16.9), 0.5 * (0.78 + deep), 1e-12);  // half way between 14.1 and 19.7
  EXPECT_DOUBLE_EQ(damping(21.0), deep);  // one compaction up to 21.15: the nearer end's value
  for (const double slabbed : {21.2, 30.0, 42.3}) EXPECT_DOUBLE_EQ(damping(slabbed), 0.5) << slabbed;
  EXPECT_DOUBLE_EQ(damping(5.0), 0.71);
  EXPECT_NE(from(9.7).find("YADE"), std::string::npos) << from(9.7);
  EXPECT_EQ(from(9.7).find("not measured"), std::string::npos) << from(9.7);
  EXPECT_EQ(from(19.0).find("not measured"), std::string::npos) << from(19.0);
  EXPECT_NE(from(5.0).find("not measured there"), std::string::npos) << from(5.0);
  EXPECT_NE(from(20.0).find("not measured there"), std::string::npos) << from(20.0);
  EXPECT_NE(from(21.0).find("not measured there"), std::string::npos) << from(21.0);
  EXPECT_NE(from(42.3).find("3 slabs of 14.1"), std::string::npos) << from(42.3);
  EXPECT_EQ(from(42.3).find("not measured"), std::string::npos) << from(42.3);
  EXPECT_NE(from(42.3).find("collider fix"), std::string::npos) << from(42.3);
  // A 2D bed keeps its own value (0.4) at any depth: the depth rule was measured in 3D.
  Scene y2 = bed(2);
  y2.relax.engine = "yade";
  for (const double depth : {9.4, 19.6}) {
    const SettleChoices c2 = settle_choices(y2, 0.83, {}, depth);
    EXPECT_DOUBLE_EQ(*c2.settings.compaction_damping, 0.4) << depth;
    EXPECT_NE(c2.record["compaction_damping"]["from"].get<std::string>().find("2D"), std::string::npos);
  }
}

// A bed deeper than 1.5x the depth settle was measured at gets a warning naming its depth, in settle.json too;
// one within it does not.
TEST(SettlePlan, DeepBedsAreServedWithAWarningNamingTheirDepth) {
  const Scene s = bed(3);
  EXPECT_EQ(settle_depth_warning(5.0), "");
  EXPECT_EQ(settle_depth_warning(1.5 * 14.1), "");
  const std::string w = settle_depth_warning(141.0);
  EXPECT_NE(w.find("141 largest diameters deep"), std::string::npos) << w;
  EXPECT_NE(w.find("overshoot"), std::string::npos) << w;
  EXPECT_FALSE(settle_choices(s, 0.63, {}, 15.0).record["compaction_damping"].contains("warning"));
  EXPECT_EQ(settle_choices(s, 0.63, {}, 42.3).record["compaction_damping"]["warning"], settle_depth_warning(42.3, settle_compaction_slabs(42.3)))
      << "LIGGGHTS compacts it in slabs";
  Scene y = s;
  y.relax.engine = "yade";
  EXPECT_EQ(settle_choices(y, 0.63, {}, 42.3).record["compaction_damping"]["warning"],
            settle_depth_warning(42.3, settle_compaction_slabs(42.3), true))
      << "YADE too, with what was measured in YADE";
}

TEST(SettlePlan, ChoicesRecordTheTargetAndWhereEachValueCameFrom) {
  Scene s = bed(3);
  const SettleChoices c = settle_choices(s, 0.63, {{"source", "calibration pour"}}, 15.0);
  EXPECT_EQ(c.settings.target_phi, 0.63);
  EXPECT_EQ(c.settings.damping, 0.7);
  EXPECT_EQ(c.settings.target_margin, kCalibrationMargin);
  EXPECT_EQ(c.stop_rule, "unbalanced-force");
  for (const char* key : {"target_phi", "compaction_damping", "damping", "stop_rule", "target_margin",
                          "compaction_timestep_fraction", "timestep_fraction"}) {
    ASSERT_TRUE(c.record.contains(key)) << key;
    EXPECT_TRUE(c.record[key].contains("from")) << key;
  }
  EXPECT_EQ(c.record["target_phi"]["from"]["source"], "calibration pour");
  s.relax.engine = "yade";
  // YADE compacts at its own damping, measured against YADE's pours of bed3d (docs/guide/settle.md), not LIGGGHTS'
  EXPECT_EQ(settle_choices(s, 0.63, {}, 14.1).settings.compaction_damping, 0.78);
  EXPECT_EQ(settle_choices(s, 0.63, {}, 15.0).settings.damping, 0.5) << "YADE's settle keeps the damping it was measured at";
}

TEST(SettlePlan, LiggghtsCompactsA3dBedInOneGoAtThreeTimesTheUsualStepAndEverythingElseAtTwice) {
  Scene s = bed(3);
  ASSERT_EQ(s.relax.engine, "liggghts");
  SettleChoices c = settle_choices(s, 0.63, {}, 15.0);
  EXPECT_EQ(*c.settings.compaction_timestep_fraction, 0.6);
  EXPECT_EQ(c.record["compaction_timestep_fraction"]["value"].get<double>(), 0.6);
  EXPECT_EQ(c.scene.relax.timestep_fraction, 0.4) << "the settle after it keeps 0.4";
  // a bed compacted in slabs (kDeepBedDepth = 21.15 largest diameters), YADE and 2D beds keep 0.4: not measured there
  EXPECT_EQ(*settle_choices(s, 0.63, {}, 30.0).settings.compaction_timestep_fraction, 0.4);
  EXPECT_EQ(*settle_choices(s, 0.63, {}, 21.0).settings.compaction_timestep_fraction, 0.6);
  const std::string slab_from = settle_choices(s, 0.63, {}, 30.0).record["compaction_timestep_fraction"]["from"];
  EXPECT_NE(slab_from.find("not measured"), std::string::npos) << slab_from;
  Scene y = s;
  y.relax.engine = "yade";
  EXPECT_EQ(*settle_choices(y, 0.63, {}, 15.0).settings.compaction_timestep_fraction, 0.4);
  EXPECT_EQ(*settle_choices(bed(2), 0.85, {}, 15.0).settings.compaction_timestep_fraction, 0.4);
}

TEST(SettlePlan, LowRestitutionSettlesAtTheScenesStepAfterItsCompaction) {
  Scene s = bed(3);
  ASSERT_EQ(s.grains.components.front().material.restitution, 0.5);
  ASSERT_EQ(settle_choices(s, 0.63, {}, 15.0).scene.relax.timestep_fraction, 0.4);
  s.grains.components.front().material.restitution = 0.4;  // the lowest measured to come to rest at 0.4
  EXPECT_EQ(settle_choices(s, 0.63, {}, 15.0).scene.relax.timestep_fraction, 0.4);
  Component bouncy = s.grains.components.front();
  bouncy.material.restitution = 0.9;
  s.grains.components.front().material.restitution = 0.1;  // one species of low restitution is enough
  s.grains.components.push_back(bouncy);
  const SettleChoices c = settle_choices(s, 0.63, {}, 15.0);
  EXPECT_EQ(c.scene.relax.timestep_fraction, s.relax.timestep_fraction);
  EXPECT_EQ(c.scene.relax.timestep_fraction, 0.2);
  const std::string from = c.record["timestep_fraction"]["from"];
  EXPECT_NE(from.find("restitution 0.1 (below 0.4)"), std::string::npos) << from;
  EXPECT_EQ(*c.settings.compaction_timestep_fraction, 0.6) << "the frictionless compaction keeps its own step";
}

TEST(SettlePlan, Bed3dSettlesAtTheCoarseStepUnlessTheSceneAsksForMoreOrIsCompactedInSlabs) {
  Scene s = bed(3);
  ASSERT_LT(s.relax.timestep_fraction, kSettleTimestepFraction3d);
  SettleChoices c = settle_choices(s, 0.63, {}, 15.0);
  EXPECT_EQ(c.scene.relax.timestep_fraction, kSettleTimestepFraction3d);
  EXPECT_EQ(c.record["timestep_fraction"]["value"].get<double>(), kSettleTimestepFraction3d);
  EXPECT_EQ(c.scene.grains.count, s.grains.count);  // the rest of the scene as it was
  EXPECT_EQ(c.scene.relax.stop_unbalanced_force, s.relax.stop_unbalanced_force);
  // A bed deeper than one compaction serves (kDeepBedDepth: compacted in slabs) settles at the scene's step, in
  // either engine; its compaction keeps the coarser one.
  for (const char* engine : {"liggghts", "yade"}) {
    s.relax.engine = engine;
    const SettleChoices deep = settle_choices(s, 0.63, {}, kDeepBedDepth + 1.0);
    ASSERT_GT(deep.settings.compaction_slabs, 1) << engine;
    EXPECT_EQ(deep.scene.relax.timestep_fraction, s.relax.timestep_fraction) << engine;
    EXPECT_EQ(deep.record["timestep_fraction"]["value"].get<double>(), s.relax.timestep_fraction) << engine;
    EXPECT_NE(deep.record["timestep_fraction"]["from"].get<std::string>().find("slabs"), std::string::npos);
    EXPECT_EQ(*deep.settings.compaction_timestep_fraction, kSettleCompactionTimestepFraction) << engine;
    EXPECT_EQ(settle_choices(s, 0.63, {}, kDeepBedDepth).scene.relax.timestep_fraction, kSettleTimestepFraction3d)
        << engine << ": one compaction up to kDeepBedDepth";
  }
  s.relax.engine = "liggghts";
  s.relax.timestep_fraction = 0.5;  // a coarser step of the scene's own is kept
  EXPECT_EQ(settle_choices(s, 0.63, {}, 15.0).scene.relax.timestep_fraction, 0.5);
  s.relax.timestep_fraction = 0.1;
  s.relax.timestep = 1e-6;  // so is an explicit step
  c = settle_choices(s, 0.63, {}, 15.0);
  EXPECT_EQ(c.scene.relax.timestep_fraction, 0.1);
  EXPECT_EQ(c.scene.relax.timestep, 1e-6);
  EXPECT_NE(c.record["timestep_fraction"]["from"].get<std::string>().find("relax.timestep"), std::string::npos);
  const Scene flat = bed(2);  // 2D: measured in 3D only, so the scene's
  EXPECT_EQ(settle_choices(flat, 0.85, {}, 15.0).scene.relax.timestep_fraction, flat.relax.timestep_fraction);
  EXPECT_EQ(heap_settle_choices(bed(3), 21.0, {}).scene.relax.timestep_fraction, bed(3).relax.timestep_fraction);
}

// A simple cubic lattice of spheres of radius 1 mm, `layers` high, filling bed(3)'s 30 mm period: packing fraction
// pi / 6 in the bulk. To compact it to 0.65 the window's top (the surface 2 mm x layers less the margin m) sinks to
// (top + m) (pi / 6) / 0.65 - m = 2 mm x layers x 0.8055 - m: with margin 3 (m = 6 mm) it stays above the window's
// floor (6 mm) at 12 layers (13.3 mm) and not at 7 (5.3 mm); margin 2 (m = 4 mm) keeps 7 layers (7.3 mm over 4).
Grains cubic_lattice(int layers) {
  Grains g;
  for (int k = 0; k < layers; ++k)
    for (int i = 0; i < 15; ++i)
      for (int j = 0; j < 15; ++j) {
        Grain a;
        a.x = Vec3((2 * i - 14) * 1e-3, (2 * j - 14) * 1e-3, (2 * k + 1) * 1e-3);  // the period is centred on 0
        a.r = 1e-3;
        g.push_back(a);
      }
  return g;
}

TEST(SettlePlan, CompactionWatchesTheMeasuredWindowWhereTheBedKeepsIt) {
  const Scene s = bed(3);
  const TargetMargin deep = settle_target_margin(cubic_lattice(12), s, 0.65);
  EXPECT_EQ(deep.value, kSettleTargetMargin);
  EXPECT_EQ(deep.value, MetricsOptions{}.margin_diameters);  // btr measure's own
  EXPECT_EQ(settle_choices(s, 0.6, {}, 15.0, deep).settings.target_margin, kSettleTargetMargin);
  EXPECT_EQ(settle_choices(s, 0.6, {}, 15.0, deep).record["target_margin"]["value"].get<double>(), kSettleTargetMargin);
  const TargetMargin shallow = settle_target_margin(cubic_lattice(7), s, 0.65);
  EXPECT_EQ(shallow.value, kCalibrationMargin);
  EXPECT_NE(shallow.record["from"].get<std::string>().find("too shallow"), std::string::npos) << shallow.record;
  EXPECT_EQ(settle_choices(s, 0.6, {}, 15.0, shallow).settings.target_margin, kCalibrationMargin);
  // the window's own arithmetic, margin 3 at 12 layers: (18 mm + 6 mm) (pi / 6) / 0.65 - 6 mm = 13.33 mm
  const CompactionWindow w = compaction_window(cubic_lattice(12), s, 3.0, 0.65);
  ASSERT_TRUE(w.valid) << w.why;
  EXPECT_NEAR(w.initial_phi, M_PI / 6.0, 1e-9);
  EXPECT_NEAR(w.hi.z(), 24e-3 * (M_PI / 6.0) / 0.65 - 6e-3, 1e-12);
  EXPECT_NEAR(w.lo.z(), 6e-3, 1e-12);
}

// Spheres of radius 1 mm on a cubic lattice filling a walled square box n diameters wide, 12 layers deep (top at
// 24 mm). Centres sit at odd millimetres; btr measure's window keeps those at least `margin` largest diameters
// (2 margin mm) from the walls, the floor and the top.
Scene narrow_box(int n) {
  Scene s = bed(3);
  s.container.kind = ContainerKind::Box;
  s.container.size_x = s.container.size_y = 2e-3 * n;
  return s;
}
Grains box_lattice(int n) {
  Grains g;
  for (int k = 0; k < 12; ++k)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        Grain a;
        a.x = Vec3((2 * i + 1 - n) * 1e-3, (2 * j + 1 - n) * 1e-3, (2 * k + 1) * 1e-3);
        a.r = 1e-3;
        g.push_back(a);
      }
  return g;
}

TEST(SettlePlan, ANarrowBedIsWatchedInTheWiderWindowAndOneTooNarrowForThatIsRefused) {
  // 8 wide: margin 3 keeps |x|, |y| < 2 mm and z in (6, 18) mm: 2 x 2 columns x 6 layers = 24 grains, fewer than the
  // least settle judges by; margin 2 keeps |x|, |y| < 4 mm and z in (4, 20) mm: 4 x 4 x 8 = 128
  const Scene eight = narrow_box(8);
  MetricsOptions o;
  EXPECT_EQ(bulk_measures(box_lattice(8), 3, eight.container, o).grains_in_window, 24);
  o.margin_diameters = kCalibrationMargin;
  EXPECT_EQ(bulk_measures(box_lattice(8), 3, eight.container, o).grains_in_window, 128);
  const TargetMargin m = settle_target_margin(box_lattice(8), eight, 0.6);
  EXPECT_EQ(m.value, kCalibrationMargin);
  EXPECT_NE(m.record["from"].get<std::string>().find("holds 24 grains"), std::string::npos) << m.record;
  EXPECT_NO_THROW(check_settle_window(box_lattice(8), eight));

  // 6 wide: margin 2 keeps 2 x 2 columns x 8 layers = 32 grains
  const Scene six = narrow_box(6);
  try {
    check_settle_window(box_lattice(6), six);
    ADD_FAILURE() << "a window of 32 grains was served";
  } catch (const RelaxRefused& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(six.file), std::string::npos) << what;
    EXPECT_NE(what.find("container"), std::string::npos) << what;
    EXPECT_NE(what.find("holds 32 grains"), std::string::npos) << what;
  }
}

// Four grains on the floor, four stacked on them: the mean column is two weights. Hertz on the floor (R* = r,
// 1/Y* = 2 (1 - nu^2) / E): F = 4/3 Y* sqrt(r) delta^3/2, so the softening s that gives delta = 0.04 r under
// F = 2 m g is s = 3 F / (4 Y* sqrt(r) (0.04 r)^3/2).
TEST(SettlePlan, HeapCalibrationSoftensTheSceneUntilTheColumnOverlapIsItsBound) {
  Scene s = bed(3);
  s.container.kind = ContainerKind::Open;
  s.source.kind = SourceSpec::Kind::Point;
  Material& m = s.grains.components[0].material;
  m.young = 1e9, m.poisson = 0.3;
  const double r = 1e-3, mass = s.grains.components[0].density * 4.0 / 3.0 * M_PI * r * r * r;
  Grains heap;
  for (int layer = 0; layer < 2; ++layer)
    for (int k = 0; k < 4; ++k) heap.push_back(Grain{Vec3(4 * r * (k % 2), 4 * r * (k / 2), r + 2 * r * layer), r, 1});
  const double y_star = m.young / (2.0 * (1.0 - 0.09)), force = 2.0 * mass * 9.81;
  const double expected = 3.0 * force / (4.0 * y_star * std::sqrt(r) * std::pow(kHeapCalibrationColumnOverlap * r, 1.5));
  const HeapCalibrationPlan plan = heap_calibration_plan(s, heap);
  EXPECT_NEAR(plan.softening, expected, 1e-6 * expected);
  EXPECT_NEAR(plan.scene.grains.components[0].material.young, expected * 1e9, 1e-6 * expected * 1e9);
  EXPECT_NEAR(plan.column_overlap, kHeapCalibrationColumnOverlap, 1e-6);
  EXPECT_NEAR(plan.column_overlap_scene, kHeapCalibrationColumnOverlap * std::pow(expected, 2.0 / 3.0), 1e-9);
  EXPECT_TRUE(plan.record.contains("from"));
  // Grains already softer than the bound are never stiffened.
  m.young = 1e9 * expected * 0.5;
  EXPECT_EQ(heap_calibration_plan(s, heap).softening, 1.0);
}

TEST(SettlePlan, RefusesHeapsOfLinearContactsWhoseAngleFollowsTheStiffness) {
  for (const char* model : {"hooke", "hooke-stiffness"}) {
    Scene s = bed(3);
    s.container.kind = ContainerKind::Open;
    s.source.kind = SourceSpec::Kind::Point;
    s.relax.model = model;
    std::string why = refusal(s);
    EXPECT_NE(why.find("relax.model"), std::string::npos) << why;
    EXPECT_NE(why.find("btr pour"), std::string::npos) << why;
    s.container.kind = ContainerKind::HeleShaw;  // a region source between the plates, as inputs/hele_shaw.toml
    s.source.kind = SourceSpec::Kind::Region;
    why = refusal(s);
    EXPECT_NE(why.find("relax.model"), std::string::npos) << why;
    s = bed(3);
    s.relax.model = model;
    EXPECT_EQ(refusal(s), "");  // a bed's calibration is not softened
  }
}

// YADE cannot scale rolling friction in a bed's compaction: refused before any work, not after the calibration pour.
// LIGGGHTS serves the same bed, and YADE serves a heap of those grains (its relaxation has no compaction).
TEST(SettlePlan, RefusesABedWithRollingFrictionInYadeBeforeTheCalibration) {
  Scene s = bed(3);
  s.grains.components[0].material.rolling_friction = 0.05;
  s.relax.engine = "yade";
  const std::string why = refusal(s);
  EXPECT_EQ(why.rfind("/scenes/bed.toml: material.rolling_friction: ", 0), 0u) << why;
  EXPECT_NE(why.find("--engine liggghts"), std::string::npos) << why;
  s.relax.engine = "liggghts";
  EXPECT_EQ(refusal(s), "");
  s.relax.engine = "yade";
  s.container.kind = ContainerKind::Open;
  s.source.kind = SourceSpec::Kind::Point;
  EXPECT_EQ(refusal(s), "");
  s = bed(3);
  s.relax.engine = "yade";
  EXPECT_EQ(refusal(s), "");
}

TEST(SettlePlan, HeapChoicesHoldTheShapeQuasiStatically) {
  Scene s = bed(3);
  const SettleChoices c = heap_settle_choices(s, 21.0, {{"source", "calibration pour"}});
  EXPECT_FALSE(c.settings.target_phi.has_value());
  EXPECT_EQ(c.settings.damping, 0.5);
  EXPECT_EQ(c.stop_rule, "unbalanced-force");
  EXPECT_EQ(c.record["angle_deg"]["value"], 21.0);
  EXPECT_EQ(c.record["angle_deg"]["from"]["source"], "calibration pour");
}

}  // namespace
}  // namespace btr
