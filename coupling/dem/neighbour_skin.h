#pragma once
// The engines' neighbour skin: how far beyond contact a pair is kept in the pair list (LIGGGHTS'
// `neighbor` distance, YADE's collider verlet distance). Both engines rebuild the list once some grain
// has moved half the skin, so any skin gives the same forces; the skin only sets how often that happens
// against how many pairs each step examines.
#include "coupling/dem/engine_adapter.h"

namespace btr {

// The skin of a relaxation or compaction, whose grains move a little per step.
inline constexpr double kBaseSkinRadii = 0.5;  // x r_min
// A pour's skin at most: measured on a softened heap pour (LIGGGHTS, 2000 grains, step 7x the stiff
// one), processor time 33.9 / 24.5 / 22.8 / 24.8 s for 0.5 / 1 / 1.5 / 2 r_min.
inline constexpr double kMaxPourSkinRadii = 1.5;  // x r_min
// Steps a released grain at its impact speed takes to cross half the skin (the stiff pours rebuild
// every 30-70 steps at 0.5 r_min).
inline constexpr double kPourStepsPerRebuild = 20.0;

// The speed of a pour's grain on reaching the pile: a fall from drop_gap + 2 r_max (pour_plan.h).
double pour_impact_speed(const PourRelease& pour);

// 0.5 r_min, and for a pour whose step is coarse (a softened calibration) the skin whose half a grain at the
// impact speed crosses in kPourStepsPerRebuild steps, 2 n v dt, capped at kMaxPourSkinRadii r_min.
double neighbour_skin(const RelaxPlan& plan, double r_min);

}  // namespace btr
