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
// The packing fraction the cell's grain count is sized with (a random loose packing): only the depth follows.
inline constexpr double kCalibrationSizingPhi3d = 0.60;
inline constexpr double kCalibrationSizingPhi2d = 0.80;
// Bulk window of the calibration's measure: this many largest diameters from the floor and the free surface
// (the settle's own bulk window keeps btr measure's 3; the cell is shallow, and a floor's layering dies out
// within two largest diameters).
inline constexpr double kCalibrationMargin = 2.0;
// Fewest grains a calibration may have: below this the window holds too few grains to measure.
inline constexpr std::int64_t kMinCalibrationGrains = 50;

// Throws RelaxRefused, naming the scene file and field, for a scene `btr settle` does not serve: only beds
// (a periodic, box or cylinder container filled by rain) of single grains; heaps (open floor, a point or
// region source), Hele-Shaw cells, drums, shaking, intruders and clusters are refused with the reason.
void check_settle_scene(const Scene& scene);

struct CalibrationPlan {
  Scene scene;              // the cell: the scene's grains and material in a periodic container, rain, `grains`
  std::int64_t grains = 0;  // count
  double width = 0.0;       // m, the period along x (and y in 3D)
  double largest_diameter = 0.0;
  double mean_grain_volume = 0.0;  // m^3 (2D: m^2), exact from the scene's radius distributions
};

// The calibration cell of a scene served by settle: periodic, kCalibrationWidth largest diameters wide, with the
// count that fills it kCalibrationDepth largest diameters deep at the sizing packing fraction (or `grains`
// when given: at least kMinCalibrationGrains). Same seed, relax section (engine, model, time-step fraction,
// stop ratio, max time) and material as the scene.
CalibrationPlan calibration_plan(const Scene& scene, std::int64_t grains = 0);

// What settle hands the relaxation: the target, the friction-reduction compaction at the scene's compaction
// damping, the quasi-static settle (damping 0.5) on the unbalanced-force rule. `record` (settle.json "chosen")
// says where each value came from.
struct SettleChoices {
  RelaxSettings settings;
  std::string stop_rule = "unbalanced-force";
  double damping = 0.5;
  nlohmann::json record;
};
SettleChoices settle_choices(const Scene& scene, double target_phi, const nlohmann::json& target_from);

}  // namespace btr
