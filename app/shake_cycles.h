#pragma once
// NAME_cycles.csv of `btr shake`, one row per cycle, the same columns whether BTR (dynamic BTR) or a DEM engine
// (tapping) shook the bed: one place for each measure of a shaken bed.
#include <cstdint>
#include <string>

#include "btr/model/grain.h"
#include "btr/scene/scene.h"

namespace btr_app {

// The header line (with its newline).
extern const char* const kCycleHeader;

struct CycleRow {
  std::int64_t cycle = 0;
  double seconds = 0.0;
  double packing_fraction = 0.0;  // bulk window (metrics.h); NaN when the bed is too shallow
  double bed_top = 0.0;           // mean free-surface height [m]
  double intruder_z = 0.0;        // intruder centre height [m]; NaN without an intruder
};

// The length unit of the table: the bed's grain diameter with an intruder (the last grain's), else the mean
// diameter.
double bed_grain_diameter(const btr::Grains& grains, const btr::Scene& scene);

// The measures of one cycle; the intruder, when the scene has one, is grain 1 (id 1).
CycleRow measure_cycle(std::int64_t cycle, double seconds, const btr::Grains& grains, const btr::Scene& scene,
                       double d_small);

// One line of the table (with its newline): cycle, seconds, packing_fraction, bed_top_d, intruder_z_d,
// intruder_z_over_bed_top, intruder_below_top_d (lengths in d_small).
std::string cycle_row_text(const CycleRow& row, double d_small);

}  // namespace btr_app
