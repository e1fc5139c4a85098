#pragma once
// NAME_steps.csv of `btr drum`, written by both the dynamic BTR run and the DEM run (one format, one place).
#include <cstdint>
#include <string>

#include "btr/measures/metrics.h"

namespace btr_app {

// "step,angle_deg,seconds,cpu_seconds,segregation_index,axis_small_R,...,surface_angle_deg\n"
std::string drum_table_header();

// One row: distances in drum radii R; surface_angle_deg NaN when the surface fit is not valid.
std::string drum_table_row(std::int64_t step, double angle_deg, double seconds, double cpu, const btr::DrumMeasures& m,
                           double R);

}  // namespace btr_app
