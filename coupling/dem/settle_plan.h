#pragma once
// `btr settle`'s plan, engine-independent (docs/guide/settle.md): which scenes it serves, the calibration
// pour that sets the target packing fraction, and the relaxation settings it chooses, each with where it
// came from. Nothing here reads a reference pour of the scene: the target comes from a small periodic pour
// of the scene's own grains and material, run in the same engine, whose cost is part of the settle's.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "btr/scene/scene.h"
#include "coupling/dem/pour_plan.h"
#include "coupling/dem/relax.h"

namespace btr {

// Bed depth of the calibration cell, in largest diameters, at the packing fraction it is sized with.
inline constexpr double kCalibrationDepth = 10.0;
// Width of the calibration cell in largest diameters: 3D square, 2D a line of this length.
inline constexpr double kCalibrationWidth3d = 5.0;
inline constexpr double kCalibrationWidth2d = 20.0;
// ... and at least this many number-mean diameters in 3D: a narrow period orders the grains and packs them
// denser. Equal spheres: a cell 5 diameters wide came out 0.007 above pours 10 wide, 7 wide 0.002 above. A size
// ratio of 2 (constant mass, mean diameter 0.69 d_max): pours 5 largest (7.2 mean) diameters wide came out
// 0.0035 above pours 7 largest (10 mean) diameters wide (friction 0.3, 5 and 12 seeds; docs/guide/settle.md),
// as the matrix's calibrations did against its 7-diameter pours, so the cell is 10 mean diameters wide. Pours
// 10 largest diameters wide stood 0.002-0.0035 above this cell again with friction 0.3, rolling friction and equal
// spheres (not with friction 0.5): the width effect is not settled (docs/guide/settle.md).
inline constexpr double kCalibrationMeanDiameters3d = 10.0;
// The calibration pour's time step in 3D, as a fraction of the Rayleigh / contact time (the scene's own when
// larger): the pours' packing fraction at 0.4 was that at 0.2 (0.6307 and 0.6308, 6 seeds each, friction 0.3,
// docs/guide/settle.md) for 0.58x the processor time, which pays for most of the wider cell. 2D keeps the scene's.
inline constexpr double kCalibrationTimestepFraction3d = 0.4;
// The packing fraction the cell's grain count is sized with (a random loose packing): only the depth follows.
inline constexpr double kCalibrationSizingPhi3d = 0.60;
inline constexpr double kCalibrationSizingPhi2d = 0.80;
// Bulk window of the calibration's measure: this many largest diameters from the floor and the free surface
// (the settle's own bulk window keeps btr measure's 3; the cell is shallow, and a floor's layering dies out
// within two largest diameters).
inline constexpr double kCalibrationMargin = 2.0;
// The calibration pour stops once its kinetic energy (and its mean over a check window) is below this ratio of
// sum m g d, not the scene's relax.stop_kinetic_ratio (1e-6 in the inputs): only its bulk packing fraction is
// used, and that is final well before. Traced check by check on seven calibrations (bed3d; the matrix's friction
// 0.1, rolling friction, equal spheres, friction 0.8, ratio 4; a 2D bed): where the kinetic energy crossed 1e-4,
// the bulk packing fraction was within 8e-5 of the one at rest (docs/guide/settle.md, "When the calibration
// stops").
inline constexpr double kCalibrationStopRatio = 1e-4;
// Fewest grains a calibration may have: below this the window holds too few grains to measure.
inline constexpr std::int64_t kMinCalibrationGrains = 50;

// Throws RelaxRefused, naming the scene file and field, for a scene `btr settle` does not serve. It serves beds
// (a periodic, box or cylinder container filled by rain) and heaps (a point source in any of those, on an open
// floor or in a Hele-Shaw cell; a region source where `btr measure` fits the heap by sides: 2D, Hele-Shaw; Hertz
// contacts only) of single grains; drums, shaking, intruders, clusters, meshes and list sources are refused with
// the reason.
void check_settle_scene(const Scene& scene);

// Whether settle builds a heap (a point or region source) rather than a bed (rain).
bool settle_builds_heap(const Scene& scene);

// Fewest grains a bed's bulk window may hold, at the calibration's margin (the widest window settle watches): fewer
// do not measure a packing fraction to compact to or to judge by. The beds settle was checked on hold 81 (a walled
// box 10 largest diameters wide) to several thousand (docs/settle/README.md); a box 7 diameters wide holds 3 at
// the judged margin.
inline constexpr std::int64_t kMinBedWindowGrains = 50;
// Throws RelaxRefused, naming the scene file and its container, when the BTR bed's bulk window holds fewer than
// kMinBedWindowGrains grains (or none).
void check_settle_window(const Grains& btr_bed, const Scene& scene);

struct CalibrationPlan {
  Scene scene;              // the cell: the scene's grains and material in a periodic container, rain, `grains`
  std::int64_t grains = 0;  // count
  double width = 0.0;       // m, the period along x (and y in 3D)
  double largest_diameter = 0.0;
  double mean_grain_volume = 0.0;  // m^3 (2D: m^2), exact from the scene's radius distributions
  nlohmann::json record;           // settle.json: the cell's width and time step, and where each came from
};

// The calibration cell of a scene served by settle: periodic, kCalibrationWidth largest diameters wide (3D: and at
// least kCalibrationMeanDiameters3d mean diameters), with the
// count that fills it kCalibrationDepth largest diameters deep at the sizing packing fraction (or `grains`
// when given: at least kMinCalibrationGrains). Same seed, relax section (engine, model, max time) and material as
// the scene, the stop ratio kCalibrationStopRatio; in 3D the time-step fraction is at least kCalibrationTimestepFraction3d (a scene's
// explicit relax.timestep is kept).
CalibrationPlan calibration_plan(const Scene& scene, std::int64_t grains = 0);

// LIGGGHTS' compaction damping: a value that lands bed3d's settled coordination on its pours' at 10 000 grains,
// 3 cm = 14.1 largest diameters deep. Measured again once the compaction's checks ran without LIGGGHTS set-ups
// (docs/guide/settle.md, "The compaction's checks without set-ups"): mean Z on BTR seeds 1-3 5.474 / 5.488 /
// 5.499 / 5.521 at 0.075 / 0.08 / 0.085 / 0.09 against the pours' 5.498 +- 0.020 (with set-ups 0.075 gave 5.518,
// coupling/README.md, "Re-measured under the one-rate drag"); 0.085 lands on the mean. At 42.3 largest diameters (30 000 grains),
// compacted at once, the settled coordination did not follow the damping: the collapse, which runs from the floor
// up, set it, hence the slabs below; settle.json records the bed's depth and says when it lies away from 14.1.
inline constexpr double kDampingAnchorDepth = 14.1;  // largest diameters: bed3d, 10 000 grains in 3 cm x 3 cm
inline constexpr double kCompactionDamping = 0.085;
// Beds deeper than this (largest diameters), compacted at once, overshoot their target: the frictionless collapse
// runs from the floor up, and the upper bed, not yet jammed at the switch, keeps collapsing after it. bed3d at
// 42.3: phi 0.633 against the target 0.6268 and the pours' 0.6268, Z 5.67 against 5.520; at 141 (10^5 grains):
// +0.014 in the compaction's window and the unbalanced force still 0.08 (threshold 0.001) 0.3 s after the switch;
// at 39 (docs/settle/deep) 0.65 at the floor, 0.60 at the top. So both engines compact them in slabs
// (settle_compaction_slabs); settle serves them, and says what was measured (settle_depth_warning).
inline constexpr double kDeepBedDepth = 1.5 * kDampingAnchorDepth;
// "" for a bed at most kDeepBedDepth largest diameters deep; else the warning settle prints and records
// (settle.json chosen.compaction_damping.warning); `yade`: the engine is YADE, where the slabs were not measured.
std::string settle_depth_warning(double depth_in_largest_diameters, int compaction_slabs = 1, bool yade = false);
// The slabs settle compacts a bed in (RelaxSettings::compaction_slabs, either engine): 1 up to kDeepBedDepth largest
// diameters, deeper ceil(depth / kDampingAnchorDepth), so each slab is at most as deep as the bed the compaction
// damping was measured on. Compacted at once, a deeper bed collapses from the floor up and leaves a density
// gradient (39 largest diameters: 0.65 at the floor, 0.60 at the top; its pour 0.62-0.63 throughout).
int settle_compaction_slabs(double depth_in_largest_diameters);
// YADE's compaction damping in 3D: the value that lands bed3d's grains on YADE's own pours' coordination, by
// LIGGGHTS' protocol, measured at three depths in one 13.4 mm periodic cell (BTR seeds relaxed to their pours' mean
// phi; the least-squares line of Z against the damping crossed with the pours' mean Z). Measured again after YADE's
// periodic collider fix (0cca044), which took about 0.1 contacts a grain from the relaxed beds at a given damping
// (docs/guide/settle.md, "YADE's compaction damping after the collider fix"; before it: 0.6 / 0.4 / 0.65):
// - 2 cm, 9.4 largest diameters, 1333 grains: six pours, Z 5.446 +- 0.050; BTR seeds 1-6, mean Z 5.299 / 5.356 /
//   5.404 / 5.446 / 5.482 at 0.4 / 0.5 / 0.6 / 0.7 / 0.8: crossing 0.71 +- 0.06;
// - 3 cm, 14.1, 2000 grains: three pours, Z 5.478 +- 0.032; BTR seeds 1-3, mean Z 5.263 / 5.311 / 5.368 / 5.411 /
//   5.432 / 5.495 / 5.527 at 0.3 ... 0.9: crossing 0.78 +- 0.06;
// - 4.2 cm, 19.7, 2800 grains: three pours, Z 5.504 +- 0.022; BTR seeds 1-3, mean Z 5.418 / 5.455 / 5.508 / 5.527 /
//   5.540 at 0.5 ... 0.9: crossing 0.75 +- 0.05.
// Settle's single compaction serves beds up to kDeepBedDepth (21.15), so 19.7 is its deepest.
inline constexpr double kYadeShallowDepth = 9.4, kYadeShallowCompactionDamping = 0.71;
inline constexpr double kYadeCompactionDamping = 0.78;  // at kDampingAnchorDepth
inline constexpr double kYadeDeepDepth = 19.7, kYadeDeepCompactionDamping = 0.75;
// A 2D bed in YADE: 0.4 at any depth, the value that landed the held-out 2D bed (19.6 largest diameters) on its
// pours' coordination, before and after the collider fix (docs/settle/README.md); the 3D rule is not used in 2D.
inline constexpr double kYade2dCompactionDamping = 0.4;
// A YADE bed compacted in slabs (3D): each slab compacts under its own weight on a settled bed. Measured after the
// collider fix on bed3d's grains 26.9 largest diameters deep in 2 slabs of 13.45 (docs/guide/settle.md, "YADE's
// slabs after the collider fix"): three pours, Z 5.504 +- 0.032; settles' beds (seeds 1-3) relaxed to the first two
// pours' phi, mean Z 5.423 / 5.485 / 5.566 at 0.35 / 0.5 / 0.7: crossing 0.55 +- 0.05; at 0.5, 0.019 under the pours
// (within their reach, 0.075). Before the fix it had crossed at about 0.50; a held-out deep bed (2 slabs of 11.5) at
// 0.51 landed on its pours' mean after it (Z -0.007). The 3D rule's values (0.71-0.78) would land slabs 0.08 over.
inline constexpr double kYadeSlabCompactionDamping = 0.5;
// YADE's compaction damping for a 3D bed compacted at once, `depth` largest diameters deep: linear between the depths
// it was measured at (kYadeShallowDepth, kDampingAnchorDepth, kYadeDeepDepth), the nearer end's value outside them
// (settle.json says so).
double yade_compaction_damping(double depth_in_largest_diameters);
// The compaction's step as a fraction of the Rayleigh / contact time: twice the settle's 0.2, the setting
// measured to give the same structure for 0.65x the processor time (coupling/README.md, "The compaction's time
// step").
inline constexpr double kSettleCompactionTimestepFraction = 0.4;
// LIGGGHTS compacts a 3D bed in one go at 0.6: bed3d's BTR seeds 1-3 relaxed to its pours' 0.6254 at compaction
// damping 0.085 gave Z 5.512 / 5.498 / 5.478 (mean 5.496) against 5.538 / 5.486 / 5.474 (5.499) at 0.4, the pours'
// 5.498 +- 0.020, and the same packing fraction to 0.0003; on docs/settle's eight bed rows (three settle seeds
// each) every row's mean Z within one of its floors of where it was and the packing fractions within 0.0004, for
// 0.82-0.88x the relaxation's processor time (0.85x at 10^5 grains; docs/guide/settle.md, "The compaction's step at
// 0.6"). The frictionless compaction's only limit is the normal contact's stability, which the rule's damping
// factor already carries (the glass bed's margin is 8x the rule's 0.2). YADE, 2D beds and beds compacted in slabs
// keep 0.4: not measured there.
inline constexpr double kLiggghtsCompactionTimestepFraction3d = 0.6;
// The quasi-static settle after the compaction, 3D beds: 0.4 (the scene's own when coarser or
// explicit; 2D and heaps keep the scene's). Against 0.2 on docs/settle's beds (3000 grains; friction 0.1-0.5,
// rolling friction, size ratio 1-4, a cylinder), bed3d and a YADE bed (docs/guide/settle.md, "The settle's time
// step"): the same bulk packing fraction to 1e-4 and coordination to 0.02, for 0.66-0.94x the relaxation's time.
// Those beds were 9-14 largest diameters deep; a bed compacted in slabs (deeper than kDeepBedDepth) keeps the
// scene's step: a held-out bed 23 deep (restitution 0.3) kept moving to the max time at 0.4 in LIGGGHTS and in
// YADE, and came to rest at 0.2 in both (docs/guide/settle.md, "A held-out deep bed").
inline constexpr double kSettleTimestepFraction3d = 0.4;
// ... for grains of restitution at least this: the beds above had 0.4-0.8. The matrix's bed_mu0.5 grains at
// restitution 0.1 never came to rest at 0.4 (friction 0.5: unbalanced force 0.23 at the max time, 1 s) or crashed
// LIGGGHTS (friction 1: "Lost atoms" 0.04 s after the compaction), and at 0.2 came to rest 0.03 s after it
// (docs/guide/settle.md, "Low restitution"). Below it the settle keeps the scene's step.
inline constexpr double kCoarseSettleMinRestitution = 0.4;
// The quasi-static settle's local damping after a bed's compaction. LIGGGHTS: 0.7, measured on bed3d at 10 000
// grains (BTR seeds 1-3, compaction damping 0.065 and 0.075): the same packing fraction to 1e-4, Z 0.009-0.039
// lower (the pours' floor is 0.020), for 0.77x the relaxation's processor time; 0.8 is no faster (coupling/README.md,
// "Re-measured under the one-rate drag"). YADE keeps 0.5, where it was measured; heaps keep 0.5, which holds
// their shape.
inline constexpr double kLiggghtsSettleDamping = 0.7;
inline constexpr double kSettleDamping = 0.5;

// The bed's depth in largest diameters: its grains' solid volume over the container's floor area (2D: width),
// at the packing fraction the calibration measured.
double bed_depth_in_largest_diameters(const Grains& grains, const Scene& scene, double packing_fraction);

// What settle hands the relaxation: the target, the friction-reduction compaction with the damping of the rule
// above for the bed's depth (LIGGGHTS; YADE: 0.5) and a step of 0.4 of the characteristic time, then the
// quasi-static settle (damping kLiggghtsSettleDamping; YADE kSettleDamping) on the unbalanced-force rule, in 3D at
// the same step. `record` (settle.json "chosen") says where each
// value came from.
// The window the compaction watches: btr measure's own bulk window (this many largest diameters from the floor,
// walls and surface), where the settled bed is measured and judged, when the BTR bed keeps one through the
// compaction; else the calibration's (kCalibrationMargin). The settled bed is not uniform in height (its collapse
// runs from the floor up), so the band between 2 and 3 diameters from the floor and the surface can read denser or
// looser than the bulk: watched in the calibration's window, the judged one missed the target by -0.0036 to +0.0035
// on docs/settle's beds; watched in its own, it lands 0.0000-0.0017 above it (docs/guide/settle.md, "The window
// the compaction watches").
inline constexpr double kSettleTargetMargin = 3.0;
struct TargetMargin {
  double value = kCalibrationMargin;
  nlohmann::json record = {{"value", kCalibrationMargin},  // settle.json "chosen.target_margin"
                           {"from", "the calibration's bulk window: largest diameters from the floor, walls and "
                                    "surface"}};
};
TargetMargin settle_target_margin(const Grains& btr_grains, const Scene& scene, double target);

struct SettleChoices {
  Scene scene;  // the scene the relaxation runs: the scene's own, its relax.timestep_fraction as chosen
  RelaxSettings settings;
  std::string stop_rule = "unbalanced-force";
  nlohmann::json record;
};
SettleChoices settle_choices(const Scene& scene, double target_phi, const nlohmann::json& target_from,
                             double depth_in_largest_diameters, const TargetMargin& margin = {});

// ---- heaps
// A heap is judged by its flank angle, and the angle a pour leaves depends on the heap's size (a 500-grain pour of
// docs/open_floor_heap's scene stood at 12-17 deg where its 2000-grain pours stand at 16-23), so a small
// calibration pour cannot give it. The calibration is the scene itself, poured with every grain softened: a Hertz
// heap's angle does not depend on the stiffness while the contacts' overlaps stay small, and a softer contact
// allows a longer time step (the Rayleigh time grows as Young's modulus^-1/2). Measured in LIGGGHTS (seed 1 and 2
// of docs/open_floor_heap's scene, 16.4 and 23.4 deg stiff: 20.3 and 22.7 at 25x softer, a mean column overlap of
// 1.5 % of the radius; 18.7 and 19.0 at 100x, 3.9 %, for 0.23x the processor time; a Hele-Shaw cell 5 d wide,
// 25.3 deg stiff, 25.0 at 78x softer). Linear (Hooke) contacts do not keep their angle (the same cell: 20.6 deg
// stiff, 19.0 at 0.3x): check_settle_scene refuses their heaps. So the scene is softened until the Hertz law's
// static overlap of a floor grain under the mean column of the BTR heap (taller than the poured one, so the bound
// holds with room) reaches this share of its radius; never stiffened.
inline constexpr double kHeapCalibrationColumnOverlap = 0.04;
// The BTR heap is built with its grains rained over the heap's surface at this packing fraction (BTR's own
// bulk packing fraction of beds, 3D and 2D).
inline constexpr double kHeapSurfacePackingFraction3d = 0.58;
inline constexpr double kHeapSurfacePackingFraction2d = 0.80;
// Independent draws of the drop positions built in each of two rounds: over the target angle, then over the target
// less the first round's mean bias; the heap whose fitted flank is nearest the target is kept.
inline constexpr int kHeapDraws = 8;

struct HeapCalibrationPlan {
  Scene scene;             // the scene with every Young's modulus x `softening` (and no explicit time step)
  double softening = 1.0;
  double column_overlap_scene = 0.0;  // the mean column overlap / radius at the scene's stiffness
  double column_overlap = 0.0;        // ... and at the calibration's
  nlohmann::json record;   // settle.json "chosen": what was softened and why
};

// The softened scene of a heap's calibration pour. `btr_heap`: the scene's BTR packing (its mean column sets the
// bound). Throws RelaxRefused if the packing has no grains.
HeapCalibrationPlan heap_calibration_plan(const Scene& scene, const Grains& btr_heap);

// The relaxation of a BTR heap built at the calibrated angle: no compaction (a heap has no bulk window to
// target), the quasi-static settle (damping 0.5) on the unbalanced-force rule, which holds the heap's shape (on
// docs/open_floor_heap's scene a 21.5 deg BTR heap settled at 21.5 deg in 2.1 s of processor time).
SettleChoices heap_settle_choices(const Scene& scene, double angle_deg, const nlohmann::json& angle_from);

}  // namespace btr
