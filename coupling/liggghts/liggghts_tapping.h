#pragma once
// The LIGGGHTS script's tapping (btr shake --engine liggghts; TapSchedule in tap_schedule.h says what it does):
// the floor as a two-triangle mesh (fix mesh/surface) that `fix move/mesh ... wiggle` moves for one period per
// tap, and the loop of taps and rests that replaces the stop rule's loop. Checked by running the Debian
// LIGGGHTS 3.8: a move/mesh run needs the run's set-up ("run N pre no" aborts in
// MultiNodeMesh::decide_rebuild), and so does the first run after "unfix" (a segmentation fault otherwise).
#include <string>
#include <vector>

#include "coupling/dem/engine_adapter.h"

namespace btr {

inline constexpr const char* kLiggghtsTapFloor = "btr_tap_floor.stl";  // the moving floor's two triangles

// dir/btr_tap_<k>.dump: the grains after tap k's rest (k = 1, 2, ...).
std::string liggghts_tap_dump(long tap);

// Writes dir/btr_tap_floor.stl (the rectangle [x_lo, x_hi] x [y_lo, y_hi] at z = 0, the simulation box's
// footprint) and returns the fix lines of the floor: mesh btr_tap_floor_mesh of material `wall_type` and the wall
// `wall_fix` (fix wall/gran `models` mesh ..., store_force yes, so its force columns are a plane floor's).
std::string liggghts_tap_floor(double x_lo, double x_hi, double y_lo, double y_hi, int wall_type,
                               const std::string& models, const std::string& wall_fix, const std::string& dir);

// The loop of plan.tap: needs the variables btr_ekin, btr_time, btr_bound and btr_kinetic (liggghts_script.cpp).
// Prints "BTR-TAP-MOVED k t = T kinetic = E" after the floor's period, "BTR-TAP-RESTED k settled|max-rest t = T
// kinetic = E step = S" after the rest, writes btr_tap_<k>.dump (`dump_columns`, printed with `dump_format`),
// and ends with "BTR-STOP taps t = T s".
std::string liggghts_tap_loop(const TapSchedule& tap, const std::string& dump_columns, const std::string& dump_format);

}  // namespace btr
