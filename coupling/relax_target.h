#pragma once
// Relaxation that lands on a target bulk packing fraction: the friction-reduction recipe YADE users know
// from REFD-style compaction. Relax with every friction coefficient scaled down (halved stage by stage)
// until the bulk packing fraction reaches the target, then restore the friction and settle.
// Each stage is a full engine run from the previous stage's relaxed packing, so both engines are
// served by the same writers; the friction of a stage is simply the scene's materials scaled.
#include <string>
#include <vector>

#include "btr/metrics.h"
#include "coupling/relax.h"

namespace btr {

struct TargetPhiStage {
  double friction_scale = 1.0;  // friction of this stage / the scene's
  double packing_fraction = 0.0;  // bulk packing fraction after the stage (btr measure's window)
  double wall_seconds = 0.0, simulated_time = 0.0;
  std::string stop_reason;
};

struct TargetPhiResult {
  RelaxResult settled;                // the last run: full friction, the scene's stop rule
  std::vector<TargetPhiStage> stages;  // reduced-friction stages, then the settle (scale 1)
  bool reached = false;               // a reduced-friction stage reached the target
  double wall_seconds = 0.0;          // all engine runs
};

// The scene with every material's friction (and rolling friction) multiplied by scale.
Scene with_friction_scaled(const Scene& scene, double scale);

// Bulk packing fraction by `btr measure`'s definition (its window, `margin` largest diameters from floor, walls
// and surface, default btr measure's); NaN if the bulk window is empty.
double bulk_packing_fraction(const Grains& grains, const Scene& scene, double margin = MetricsOptions{}.margin_diameters);

// Friction scales tried in order: 1/2, 1/4, ... down to 1/32, then 0 (frictionless).
std::vector<double> target_phi_schedule();

// Reduced-friction stages go into out_dir/friction_<k>/, the settle into out_dir itself (relaxed.csv ...).
// Reduced-friction stages stop on the scene's rule with the kinetic ratio loosened (they only need the
// rearrangement to end); the settle uses the scene's rule as given. relaxed.json records the stages.
// `schedule`: the friction scales to try, in order. Throws RelaxRefused for a target outside (0, 1), a
// packing without a bulk window, or a schedule that is empty or not decreasing within [0, 1).
TargetPhiResult relax_to_target_phi(const Packing& packing, const Scene& scene, const std::string& engine,
                                    const RelaxSettings& settings, double target_phi, const std::string& out_dir,
                                    const std::vector<double>& schedule = target_phi_schedule(),
                                    double margin = MetricsOptions{}.margin_diameters);

}  // namespace btr
