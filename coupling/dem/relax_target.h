#pragma once
// Relaxation that lands on a target bulk packing fraction: the friction-reduction recipe YADE users know
// (REFD-style compaction: friction lowered while the packing fraction is watched, restored once it reaches
// the target), run inside the one engine run of the relaxation. The engine watches the packing fraction of
// the bulk window every few steps; the writers (liggghts_script.cpp, yade_script.cpp)
// emit the compaction phase from the CompactionPlan made here (engine_adapter.h says what it does).
//
// Why in the run and not as separate runs to rest at each friction: the compaction of a BTR bed is a
// collapse under gravity that overshoots any target if it runs to rest without friction (bed3d, 10 000
// grains: 0.645 against the pour's 0.626), and each run to rest costs a relaxation. Watched in the run,
// the collapse is stopped at the target, and how fast it was allowed to go (compaction_damping) decides how
// many contacts the settled bed keeps (docs/guide/relax.md, "Target packing fraction").
#include <string>
#include <vector>

#include "btr/measures/metrics.h"
#include "coupling/dem/engine_adapter.h"

namespace btr {

// The scene with every material's friction (and rolling friction) multiplied by scale.
Scene with_friction_scaled(const Scene& scene, double scale);

// Bulk packing fraction by `btr measure`'s definition (its window, `margin` largest diameters from floor, walls
// and surface); NaN if the bulk window is empty.
double bulk_packing_fraction(const Grains& grains, const Scene& scene, double margin = MetricsOptions{}.margin_diameters);

// The window the compaction watches: btr measure's bulk window of the starting packing at `margin` largest
// diameters, its top lowered by the compaction `target` needs (a bed compacting uniformly from the floor:
// (top + m) phi0 / target - m, m the margin in metres), so that it stays inside the bed. `measured`: the starting
// packing has a bulk window (its packing fraction is initial_phi); `valid`: the lowered window still has a height
// (`why` says what is missing).
struct CompactionWindow {
  bool measured = false, valid = false, slab = false;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  double initial_phi = 0.0;
  std::int64_t grains = 0;  // centred in the bulk window (before it is lowered for the compaction)
  std::string why;
};
CompactionWindow compaction_window(const Grains& grains, const Scene& scene, double margin, double target);

// settings.compaction_slabs > 1 (CompactionPlan::slabs): `count` slabs of equal grain counts in the packing's
// order (a BTR deposit's drops); slab k's window runs from the top of slab k-1's (the first: the plan's floor
// margin) to the top of the window the BTR bed of slab 1..k's drops would have, lowered for its compaction
// (compaction_window); the last slab's top is the plan's. Empty for count < 2. Throws RelaxRefused for more slabs
// than grains, several friction scales, or a slab without a window.
std::vector<CompactionPlan::Slab> compaction_slabs(const Grains& grains, const Scene& scene, double margin,
                                                   const CompactionPlan& plan, int count);

// The compaction phase of a relaxation of `packing`, from settings (which override the scene's relax.target_phi,
// friction_scales and compaction_damping). Not enabled without a target, or when the packing's bulk packing
// fraction already reaches it (then only `target` and `initial_phi` are set). The compaction's step is
// `timestep` (the run's) times its time-step fraction over the scene's timestep_fraction. The window is
// compaction_window's at settings.target_margin.
// Throws RelaxRefused for a target outside (0, 1), scales that are empty or not decreasing in [0, 1), a
// compaction damping outside [0, 1), an empty bulk window, or rigid clusters.
CompactionPlan plan_compaction(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                               double timestep, double kinetic_threshold);

// relaxed.json's "target_phi" record: the target, the starting and settled bulk packing fractions (btr measure's
// definition), whether and how the compaction reached the target, and the recipe.
nlohmann::json target_phi_record(const CompactionPlan& plan, const RelaxResult& result, const Scene& scene,
                                 double margin);

}  // namespace btr
