#pragma once
// The LIGGGHTS script's compaction phase (btr relax --target-phi; CompactionPlan in engine_adapter.h says what
// it does): the bulk window's packing fraction (v_btr_phi: each grain's exact part between the window's planes in
// z, times its fraction between the side planes in walled containers), and the loop that runs before the stop
// rule's loop, one block per friction scale, or with slabs (CompactionPlan::slabs) one block per slab, the window's
// z bounds and measure then variables set per slab.
#include <string>

#include "coupling/dem/engine_adapter.h"

namespace btr {

// The fix ID of the damping during the compaction (replaced by btr_damping, the plan's, when it ends).
inline constexpr const char* kCompactionDampingFix = "btr_compaction_damping";

// The compaction's drag rate c [1/s]: every grain feels F = -c m v, one c for all, the count-weighted mean over
// the species of gamma / m (liggghts_damping_gamma's coefficient of the damping `damping` over the mass of the
// species' mean grain). A drag coefficient per species instead lets a grain fall through the pores at
// m g / gamma, so in a wide size distribution the large grains sank past the small ones (coupling/README.md,
// "The compaction's drag").
double liggghts_compaction_drag_rate(const Grains& grains, const Scene& scene, double damping);

// "fix kCompactionDampingFix all addforce ..." with its three atom-style variables (and comment): the drag of
// liggghts_compaction_drag_rate. The first run after it must set up (a `run 0`); the checks after that run
// "pre no" (its variables are found once, at that set-up).
std::string liggghts_compaction_drag_fix(const Grains& grains, const Scene& scene, double damping);

// The per-grain volume (area in 2D) in the window, compute btr_bulk_volume and variable btr_phi. Needs
// compute btr_radius; v_btr_phi must be in the thermo output (computes are evaluated on thermo steps).
std::string liggghts_compaction_setup(const CompactionPlan& c, int dimension);

// The loop: needs the variables btr_ekin, btr_kmean, btr_phi, btr_time and btr_bound, and the friction fixes
// btr_friction (btr_rolling) of liggghts_friction_fixes. Prints "BTR-COMPACTION-END reached|not-reached
// friction x S t = T s phi = P" (read back by liggghts_readback.cpp), then restores the friction, stops every
// grain, swaps the compaction's drag for the settle's YADE-style local damping and the compaction's
// step for the settle's (`settle_damping`, 0 = none: liggghts_local_damping_fix;
// `settle_timestep`, the run's step, which the compaction's c.timestep replaces until then) and re-arms the stop
// rule: btr_tarm = now + arming_time, btr_armed = 0.
std::string liggghts_compaction_loop(const CompactionPlan& c, const Scene& scene,
                                     double settle_damping, double settle_timestep, double arming_time);

}  // namespace btr
