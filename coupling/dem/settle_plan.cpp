#include "coupling/dem/settle_plan.h"

#include <algorithm>
#include <cmath>

#include "btr/model/number_text.h"
#include "btr/placement/drops.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/preload.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/relax_target.h"
#include "coupling/dem/timestep.h"

namespace btr {
namespace {

// Every Young's modulus of the scene's materials x s (Hertz: the damping follows from the restitution, kept).
Scene softened(const Scene& scene, double s) {
  Scene out = scene;
  for (Component& c : out.grains.components) c.material.young *= s;
  out.relax.timestep.reset();  // the rule's step for the softer contact: the point of softening
  return out;
}

// settle.json's record of the quasi-static settle's stop rule, beds and heaps alike.
nlohmann::json stop_rule_record(const Scene& scene, const std::string& rule) {
  return {{"value", rule},
          {"from", "btr settle: unbalanced force below the scene's relax.stop_unbalanced_force (" +
                       g6(scene.relax.stop_unbalanced_force) + ")"}};
}

// settle.json's record of the scene's own step, `why` appended to where it came from.
nlohmann::json scenes_step(const Scene& scene, const std::string& why = "") {
  return {{"value", scene.relax.timestep ? nlohmann::json(nullptr) : nlohmann::json(scene.relax.timestep_fraction)},
          {"from", (scene.relax.timestep ? "the scene's relax.timestep" : "the scene's relax.timestep_fraction") + why}};
}

// A 3D step fraction settle measured to leave the structure as it was: `scene` takes it unless its own step is
// coarser or explicit (2D keeps the scene's: not measured there). Returns settle.json's record of the fraction used.
nlohmann::json coarser_step_3d(Scene& scene, double fraction, const std::string& why) {
  if (scene.dimension == 3 && !scene.relax.timestep && scene.relax.timestep_fraction < fraction) {
    scene.relax.timestep_fraction = fraction;
    return {{"value", fraction}, {"from", why}};
  }
  return scenes_step(scene);
}

// The frictionless compaction's step: LIGGGHTS' one compaction of a 3D bed takes kLiggghtsCompactionTimestepFraction3d,
// YADE, 2D beds and beds compacted in slabs kSettleCompactionTimestepFraction. Returns settle.json's record of it.
nlohmann::json compaction_step(const Scene& scene, bool yade, int slabs) {
  if (!yade && scene.dimension == 3 && slabs == 1)
    return {{"value", kLiggghtsCompactionTimestepFraction3d},
            {"from", "btr settle: LIGGGHTS' one compaction of a 3D bed, three times the scene's usual 0.2, measured on "
                     "bed3d and docs/settle's periodic beds to give the same structure as 0.4 (docs/guide/settle.md)"}};
  return {{"value", kSettleCompactionTimestepFraction},
          {"from", "btr settle: twice the scene's usual 0.2, measured on bed3d to give the same structure (0.6, taken "
                   "for LIGGGHTS' one compaction of a 3D bed, was not measured in YADE, in 2D or in slabs)"}};
}

// The settle's step after a bed's compaction: `scene` takes the coarse 3D fraction unless the bed is compacted in
// slabs or has grains of low restitution, where the coarse step was seen to keep the bed moving (or to crash
// LIGGGHTS). Returns settle.json's record of the fraction used.
nlohmann::json settle_step(Scene& scene, int slabs) {
  if (slabs > 1)
    return scenes_step(scene, ": a bed compacted in slabs keeps it after the compaction, since at 0.4 a held-out bed "
                              "23 largest diameters deep (restitution 0.3) still moved at the max time in both "
                              "engines, and at 0.2 came to rest 0.02-0.03 s after the compaction (docs/guide/settle.md)");
  const double restitution = lowest_restitution(scene);
  if (restitution < kCoarseSettleMinRestitution)
    return scenes_step(scene, ": restitution " + g6(restitution) + " (below " + g6(kCoarseSettleMinRestitution) +
                                  ") keeps it after the compaction, since at 0.4 beds of restitution 0.1 did not "
                                  "come to rest or crashed LIGGGHTS, and at 0.2 came to rest (docs/guide/settle.md)");
  return coarser_step_3d(scene, kSettleTimestepFraction3d,
                         "btr settle: the settled beds' packing fraction and coordination are those at 0.2 (to 1e-4 "
                         "and 0.02, 8 beds in LIGGGHTS and 1 in YADE, up to 14 largest diameters deep) for 0.66-0.94x "
                         "the relaxation's time (docs/guide/settle.md)");
}

}  // namespace

bool settle_builds_heap(const Scene& scene) {
  return scene.source.kind == SourceSpec::Kind::Point || scene.source.kind == SourceSpec::Kind::Region;
}

void check_settle_scene(const Scene& scene) {
  if (scene.clusters) refuse_scene_field(scene, "[clusters]", "btr settle releases single grains, not rigid clusters");
  if (scene.drum) refuse_scene_field(scene, "[drum]", "a rotating drum is dynamic BTR, not a bed at rest");
  if (scene.shaking) refuse_scene_field(scene, "[shaking]", "a shaken packing is dynamic BTR, not a poured bed");
  if (scene.intruder)
    refuse_scene_field(scene, "[intruder]", "the calibration pour holds the scene's bed grains only; an intruder is not served");
  const ContainerKind kind = scene.container.kind;
  if (kind == ContainerKind::Drum) refuse_scene_field(scene, "container.kind", "\"drum\": dynamic BTR, not a bed at rest");
  if (kind == ContainerKind::Mesh)
    refuse_scene_field(scene, "container.kind",
           "\"mesh\": btr measure has no bulk window or heap angle in a mesh, so no target can be measured or "
           "checked there; relax the BTR fill with `btr relax`");
  switch (scene.source.kind) {
    case SourceSpec::Kind::List:
      refuse_scene_field(scene, "source.kind",
                         "\"list\" places given positions; settle builds a bed (rain) or a heap (a point or region source)");
    case SourceSpec::Kind::Rain:
      if (kind == ContainerKind::HeleShaw)
        refuse_scene_field(scene, "source.kind",
               "rain into a Hele-Shaw cell: the plates set the packing across the whole gap, which the periodic "
               "calibration cell does not have; pour the cell's heaps from a point or region source");
      // Before the deposit and the calibration pour: the relaxation would refuse it only after them (relax.cpp).
      if (scene.relax.engine == "yade" && uses_rolling_friction(scene))
        refuse_scene_field(scene, "material.rolling_friction",
               "a bed is compacted to its target with its friction scaled down, and YADE's Hertz-Mindlin moment law "
               "takes its rolling friction once for every contact, so it cannot be scaled with it; settle this bed "
               "with LIGGGHTS (--engine liggghts), or without rolling friction");
      return;  // an open floor has no rain (the scene refuses it)
    case SourceSpec::Kind::Region:
      if (scene.dimension == 3 && kind != ContainerKind::HeleShaw)
        refuse_scene_field(scene, "source.kind",
               "\"region\" over a 3D floor: btr measure fits a heap's angle about a point source (or by sides in 2D "
               "and Hele-Shaw cells), so a region source's heap has no angle to calibrate or check; use a point "
               "source");
      break;
    case SourceSpec::Kind::Point: break;
  }
  if (scene.relax.model != "hertz")
    refuse_scene_field(scene, "relax.model",
           "\"" + scene.relax.model + "\": a heap's calibration pours the scene with softened grains, and a linear "
           "(Hooke) contact's heap changes its angle with the stiffness (Hele-Shaw cell 5 d wide, LIGGGHTS: 20.6 deg "
           "at the scene's stiffness, 19.0 at 0.3x, 15.6 at 0.031x, where Hertz grains stood at 25.3 and 25.0 at "
           "0.013x; docs/guide/settle.md), so its calibration would not stand for a pour. Pour it with `btr pour`, or "
           "settle it with relax.model = \"hertz\"");
}

void check_settle_window(const Grains& btr_bed, const Scene& scene) {
  MetricsOptions o;
  o.margin_diameters = kCalibrationMargin;
  const BulkMeasures b = bulk_measures(btr_bed, scene.dimension, scene.container, o);
  if (b.valid && b.grains_in_window >= kMinBedWindowGrains) return;
  const std::string needs = "settle needs at least " + std::to_string(kMinBedWindowGrains) +
                            " there to measure a packing fraction to compact to and to judge the bed by: ";
  const std::string window = "the bed's bulk window (" + g6(kCalibrationMargin) +
                             " largest diameters from the floor, walls and surface) holds ";
  if (!b.valid)  // too shallow: no window at all
    refuse_scene_field(scene, "grains.count", window + "no grain (" + b.note + "); " + needs +
                                                  "give more grains, or pour the scene (`btr pour`)");
  refuse_scene_field(scene, "container", window + std::to_string(b.grains_in_window) + " grains; " + needs +
                                             "widen the container, give more grains, or pour the scene (`btr pour`)");
}

CalibrationPlan calibration_plan(const Scene& scene, std::int64_t grains) {
  CalibrationPlan plan;
  const int dim = scene.dimension;
  const std::vector<double> fraction = number_fractions(scene.grains, dim);
  double mean_volume = 0.0, mean_radius = 0.0;
  for (std::size_t c = 0; c < scene.grains.components.size(); ++c) {
    const RadiusSpec& r = scene.grains.components[c].radius;
    mean_volume += fraction[c] * (dim == 3 ? 4.0 / 3.0 * M_PI * radius_moment(r, 3) : M_PI * radius_moment(r, 2));
    mean_radius += fraction[c] * radius_moment(r, 1);
  }
  Scene cell = scene;
  cell.name = scene.name + "_calibration";
  cell.container = Container{};
  cell.container.kind = ContainerKind::Periodic;
  cell.source = SourceSpec{};
  cell.source.kind = SourceSpec::Kind::Rain;
  cell.relax.target_phi.reset();
  const double d_max = 2.0 * DropSequence(cell, scene.seed).r_max();
  plan.largest_diameter = d_max;
  plan.mean_grain_volume = mean_volume;
  plan.width = dim == 3 ? std::max(kCalibrationWidth3d * d_max, kCalibrationMeanDiameters3d * 2.0 * mean_radius)
                        : kCalibrationWidth2d * d_max;
  cell.container.size_x = plan.width;
  cell.container.size_y = dim == 3 ? plan.width : 0.0;
  plan.record = {{"width", {{"value", plan.width},
                            {"from", dim == 3 ? "the wider of " + g6(kCalibrationWidth3d) + " largest and " +
                                                    g6(kCalibrationMeanDiameters3d) + " number-mean diameters"
                                              : g6(kCalibrationWidth2d) + " largest diameters"}}}};
  plan.record["timestep_fraction"] =
      coarser_step_3d(cell, kCalibrationTimestepFraction3d,
                      "btr settle: the pours' packing fraction is the same at this fraction as at 0.2, for 0.58x the "
                      "processor time (docs/guide/settle.md)");
  cell.relax.stop_kinetic_ratio = kCalibrationStopRatio;
  plan.record["stop_kinetic_ratio"] = {
      {"value", kCalibrationStopRatio},
      {"from", "btr settle: the cell's bulk packing fraction is final by then (docs/guide/settle.md)"}};
  if (grains > 0) {
    if (grains < kMinCalibrationGrains)
      throw RelaxRefused("--calibration-grains: expected at least " + std::to_string(kMinCalibrationGrains) +
                         " grains (fewer leave the bulk window nearly empty), got " + std::to_string(grains));
    plan.grains = grains;
  } else {
    const double footprint = dim == 3 ? plan.width * plan.width : plan.width;
    const double phi = dim == 3 ? kCalibrationSizingPhi3d : kCalibrationSizingPhi2d;
    plan.grains = static_cast<std::int64_t>(std::ceil(phi * footprint * kCalibrationDepth * d_max / mean_volume));
  }
  cell.grains.count = plan.grains;
  plan.scene = cell;
  return plan;
}

std::string settle_depth_warning(double depth, int slabs, bool yade) {
  if (!(depth > kDeepBedDepth)) return "";
  const std::string deep = "this bed is " + g6(depth) + " largest diameters deep, beyond the " + g6(kDeepBedDepth) +
                           " settle was validated to (9.3-14.1): ";
  if (slabs > 1)
    return deep + "compacted in " + std::to_string(slabs) + " slabs from the floor up, as a pour builds it; " +
           (yade ? "measured in YADE on two such beds of 2 slabs (26.9 largest diameters of bed3d's grains, and 23 of "
                   "held-out grains, docs/guide/settle.md): on the mean of three settles coordination within 0.05 of "
                   "the pours and packing fraction up to 0.0027 over them (a bed compacted in slabs lands "
                   "0.0010-0.0022 over its target), each settle off by its calibration's draw too"
                 : "measured on one such bed in LIGGGHTS (39 largest diameters, docs/settle/deep): coordination and "
                   "density against height within its pours' scatter, packing fraction +0.002 over them (the target "
                   "0.0015 under them, the settle 0.003 over its target)") +
           "; `btr pour` gives the reference";
  return deep + "deeper beds overshoot the target (bed3d at 42.3: phi +0.006 and Z "
         "+0.15 over its pours; at 141: +0.014, still moving 0.3 s after the switch), since the upper bed keeps "
         "collapsing after the compaction stops; `btr pour` gives the reference (docs/settle/README.md, \"Deep beds\")";
}

double bed_depth_in_largest_diameters(const Grains& grains, const Scene& scene, double packing_fraction) {
  const int dim = scene.dimension;
  const double solid = solid_volume(grains, dim);
  const double r_max = max_radius(grains);
  const Container& c = scene.container;
  const double floor = c.kind == ContainerKind::Cylinder ? (dim == 3 ? M_PI * c.radius * c.radius : 2.0 * c.radius)
                       : dim == 3                        ? c.size_x * c.size_y
                                                         : c.size_x;
  return solid / (floor * packing_fraction) / (2.0 * r_max);
}

TargetMargin settle_target_margin(const Grains& btr_grains, const Scene& scene, double target) {
  const CompactionWindow judged = compaction_window(btr_grains, scene, kSettleTargetMargin, target);
  if (judged.valid && judged.grains >= kMinBedWindowGrains)
    return {kSettleTargetMargin,
            {{"value", kSettleTargetMargin},
             {"from", "btr measure's bulk window (largest diameters from the floor, walls and surface), where the "
                      "settled bed is measured: the BTR bed keeps it through the compaction"}}};
  return {kCalibrationMargin,
          {{"value", kCalibrationMargin},
           {"from", "the calibration's bulk window: the BTR bed has no window to watch at btr measure's " +
                        g6(kSettleTargetMargin) + " largest diameters (" +
                        (!judged.measured ? "no bulk window: " + judged.why
                         : !judged.valid  ? judged.why
                                          : "its window holds " + std::to_string(judged.grains) + " grains, fewer than " +
                                                std::to_string(kMinBedWindowGrains)) +
                        ")"}}};
}

SettleChoices settle_choices(const Scene& scene, double target_phi, const nlohmann::json& target_from,
                             double depth, const TargetMargin& margin) {
  const bool yade = scene.relax.engine == "yade";
  SettleChoices c;
  c.settings.target_phi = target_phi;
  c.settings.damping = yade ? kSettleDamping : kLiggghtsSettleDamping;
  c.settings.target_margin = margin.value;
  c.scene = scene;
  // YADE's depth rule was measured on 3D beds compacted at once; a 2D bed keeps its own value, a bed compacted in slabs
  // the slabs' (kYadeSlabCompactionDamping): after YADE's collider fix the depth rule's values no longer land slabs.
  const bool yade_3d = yade && scene.dimension == 3;
  const int slabs = settle_compaction_slabs(depth);
  const nlohmann::json compaction_step_record = compaction_step(scene, yade, slabs);
  c.settings.compaction_timestep_fraction = compaction_step_record["value"].get<double>();
  const nlohmann::json step_record = settle_step(c.scene, slabs);
  // The value and where it came from, chosen together.
  const std::string depth_text = g6(depth) + " largest diameters";
  double compaction_damping = kCompactionDamping;
  std::string damping_from;
  if (!yade) {
    const bool measured_depth = depth >= 0.75 * kDampingAnchorDepth && depth <= kDeepBedDepth;
    damping_from = "btr settle's LIGGGHTS compaction damping, measured against the engine's own pours of bed3d at " +
                   g6(kDampingAnchorDepth) + " largest diameters deep (this bed: " + depth_text +
                   (measured_depth ? ")" : ", away from that depth: not measured there)");
  } else if (!yade_3d) {
    compaction_damping = kYade2dCompactionDamping;
    damping_from = "btr settle's YADE compaction damping in 2D (" + g6(kYade2dCompactionDamping) +
                   "): its depth rule, measured on 3D beds, is not used in 2D, where 0.4 landed the held-out 2D "
                   "bed's coordination at 19.6 and 0.5 did not "
                   "(docs/guide/settle.md; this bed: " + depth_text + ", not measured in 2D otherwise)";
  } else if (slabs > 1) {
    compaction_damping = kYadeSlabCompactionDamping;
    damping_from = "btr settle's YADE compaction damping of a bed compacted in slabs (this bed: " + depth_text + ", " +
                   std::to_string(slabs) + " slabs of " + g6(depth / slabs) +
                   "): measured after YADE's collider fix against YADE's pours of bed3d's grains 26.9 largest "
                   "diameters deep in 2 slabs (crossing 0.55 +- 0.05; at 0.5 the mean coordination 0.019 under the "
                   "pours, within their reach), and what landed a held-out deep bed (2 slabs of 11.5) on its pours' "
                   "mean coordination (docs/guide/settle.md, \"YADE's slabs after the collider fix\")";
  } else {
    compaction_damping = yade_compaction_damping(depth);
    const bool between = depth >= kYadeShallowDepth && depth <= kYadeDeepDepth;
    damping_from = "btr settle's YADE compaction damping, measured against YADE's own pours of bed3d's grains at " +
                   g6(kYadeShallowDepth) + " largest diameters deep (" + g6(kYadeShallowCompactionDamping) + "), " +
                   g6(kDampingAnchorDepth) + " (" + g6(kYadeCompactionDamping) + ") and " + g6(kYadeDeepDepth) + " (" +
                   g6(kYadeDeepCompactionDamping) + "), linear between (this bed: " + depth_text +
                   (between ? ")" : ", outside them: the nearer end's value, not measured there)");
  }
  c.settings.compaction_damping = compaction_damping;
  c.record = {
      {"target_phi", {{"value", target_phi}, {"from", target_from}}},
      {"compaction_damping",
       {{"value", compaction_damping}, {"bed_depth_largest_diameters", depth}, {"from", damping_from}}},
      {"compaction_timestep_fraction", compaction_step_record},
      {"timestep_fraction", step_record},
      {"target_margin", margin.record},
      {"friction_scales", {{"value", scene.relax.friction_scales}, {"from", "the scene's relax.friction_scales"}}},
      {"damping",
       {{"value", *c.settings.damping},
        {"from", std::string("btr settle: quasi-static settle after the compaction, under YADE's local damping in both "
                             "engines (LIGGGHTS: the same law by fix addforce, so that no grain is left hanging in a "
                             "pore); ") +
                     (yade ? "YADE keeps the value it was measured at"
                           : "LIGGGHTS: 0.77x the time of 0.5 on bed3d, the same packing fraction, Z 0.02 lower on "
                             "average (coupling/README.md)")}}},
      {"stop_rule", stop_rule_record(scene, c.stop_rule)},
  };
  c.settings.compaction_slabs = slabs;
  if (c.settings.compaction_slabs > 1)
    c.record["compaction_slabs"] = {
        {"value", c.settings.compaction_slabs},
        {"from", "btr settle: a bed deeper than " + g6(kDeepBedDepth) + " largest diameters is compacted slab by slab "
                 "from the floor up, each at most " + g6(kDampingAnchorDepth) + " largest diameters deep (where the "
                 "compaction damping was measured), as a pour builds it (docs/settle/deep/README.md)"}};
  const std::string warning = settle_depth_warning(depth, c.settings.compaction_slabs, yade);
  if (!warning.empty()) c.record["compaction_damping"]["warning"] = warning;
  return c;
}

double yade_compaction_damping(double depth) {
  constexpr double depths[] = {kYadeShallowDepth, kDampingAnchorDepth, kYadeDeepDepth};
  constexpr double dampings[] = {kYadeShallowCompactionDamping, kYadeCompactionDamping, kYadeDeepCompactionDamping};
  if (!(depth > depths[0])) return dampings[0];
  for (int i = 1; i < 3; ++i)
    if (depth <= depths[i]) {
      const double t = (depth - depths[i - 1]) / (depths[i] - depths[i - 1]);
      return dampings[i - 1] + t * (dampings[i] - dampings[i - 1]);
    }
  return dampings[2];
}

int settle_compaction_slabs(double depth) {
  if (!(depth > kDeepBedDepth)) return 1;
  return static_cast<int>(std::ceil(depth / kDampingAnchorDepth));
}

HeapCalibrationPlan heap_calibration_plan(const Scene& scene, const Grains& btr_heap) {
  if (btr_heap.empty()) throw RelaxRefused("heap calibration: the BTR heap has no grains");
  HeapCalibrationPlan plan;
  auto overlap = [&](double s) { return predict_static_overlap(btr_heap, softened(scene, s)).column.mean_relative; };
  plan.column_overlap_scene = overlap(1.0);
  if (!(plan.column_overlap_scene > 0.0))
    throw RelaxRefused("heap calibration: the BTR heap puts no load on the floor");
  // Hertz overlap under a given force goes as Young's modulus^-2/3 (heaps are Hertz only: check_settle_scene).
  const double s = std::min(1.0, std::pow(plan.column_overlap_scene / kHeapCalibrationColumnOverlap, 1.5));
  plan.softening = s;
  plan.scene = softened(scene, s);
  plan.scene.name = scene.name + "_calibration";
  plan.column_overlap = overlap(s);
  plan.record = {
      {"value", s},
      {"column_overlap_at_scene_stiffness", plan.column_overlap_scene},
      {"column_overlap", plan.column_overlap},
      {"from", "btr settle: the scene poured with every Young's modulus x this (the same restitution), until the "
               "Hertz law's static overlap of a floor grain under the BTR heap's mean column is " +
                   g6(kHeapCalibrationColumnOverlap) +
                   " of its radius (never stiffer than the scene): a Hertz heap's angle does not depend on the "
                   "stiffness at such overlaps (docs/guide/settle.md, \"Heaps\")"}};
  return plan;
}

SettleChoices heap_settle_choices(const Scene& scene, double angle_deg, const nlohmann::json& angle_from) {
  SettleChoices c;
  c.scene = scene;
  c.settings.damping = kSettleDamping;
  c.record = {
      {"angle_deg", {{"value", angle_deg}, {"from", angle_from}}},
      {"damping",
       {{"value", *c.settings.damping}, {"from", "btr settle: a quasi-static settle that holds the heap's shape"}}},
      {"stop_rule", stop_rule_record(scene, c.stop_rule)},
  };
  return c;
}

}  // namespace btr
