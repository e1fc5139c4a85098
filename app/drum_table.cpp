#include "drum_table.h"

#include <cmath>
#include <cstdio>

namespace btr_app {

std::string drum_table_header() {
  return "step,angle_deg,seconds,cpu_seconds,segregation_index,axis_small_R,axis_large_R,core_small_R,core_large_R,"
         "com_x_R,com_z_R,surface_angle_deg\n";
}

std::string drum_table_row(std::int64_t step, double angle_deg, double seconds, double cpu, const btr::DrumMeasures& m,
                           double R) {
  char buf[400];
  std::snprintf(buf, sizeof buf, "%lld,%.10g,%.6f,%.6f,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n",
                static_cast<long long>(step), angle_deg, seconds, cpu, m.segregation_index, m.axis_small / R,
                m.axis_large / R, m.core_small / R, m.core_large / R, m.com_x / R, m.com_z / R,
                m.surface_valid ? m.surface_angle_deg : NAN);
  return buf;
}

}  // namespace btr_app
