// NAME_cycles.csv of `btr shake` (shake_cycles.h).
#include "shake_cycles.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "btr/measures/metrics.h"

namespace btr_app {

const char* const kCycleHeader =
    "cycle,seconds,packing_fraction,bed_top_d,intruder_z_d,intruder_z_over_bed_top,intruder_below_top_d\n";

double bed_grain_diameter(const btr::Grains& grains, const btr::Scene& scene) {
  if (scene.intruder) return 2.0 * grains.back().r;
  double d = 0.0;
  for (const btr::Grain& g : grains) d += 2.0 * g.r;
  return d / static_cast<double>(grains.size());
}

CycleRow measure_cycle(std::int64_t cycle, double seconds, const btr::Grains& grains, const btr::Scene& scene,
                       double d_small) {
  CycleRow row;
  row.cycle = cycle;
  row.seconds = seconds;
  row.packing_fraction = NAN;
  row.intruder_z = NAN;
  // The bulk window keeps 3 bed-grain diameters (not 3 intruder diameters) from floor, walls and surface.
  double r_max = 0.0;
  for (const btr::Grain& g : grains) r_max = std::max(r_max, g.r);
  btr::MetricsOptions mo;
  mo.margin_diameters = 3.0 * d_small / (2.0 * r_max);
  const btr::BulkMeasures bulk = btr::bulk_measures(grains, scene.dimension, scene.container, mo);
  if (bulk.valid) row.packing_fraction = bulk.packing_fraction;
  if (scene.intruder) {
    btr::Grains bed(grains.begin() + 1, grains.end());  // the intruder is grain 1
    row.bed_top = btr::mean_surface_height(bed, scene.dimension, scene.container, 2.0 * d_small);
    row.intruder_z = grains[0].x.z();
  } else {
    row.bed_top = btr::mean_surface_height(grains, scene.dimension, scene.container, 2.0 * d_small);
  }
  return row;
}

std::string cycle_row_text(const CycleRow& r, double d_small) {
  char buf[320];
  const double in_d = r.intruder_z / d_small, below_top = (r.bed_top - r.intruder_z) / d_small;
  std::snprintf(buf, sizeof buf, "%lld,%.6f,%.10g,%.10g,%.10g,%.10g,%.10g\n", static_cast<long long>(r.cycle),
                r.seconds, r.packing_fraction, r.bed_top / d_small, in_d, r.intruder_z / r.bed_top, below_top);
  return buf;
}

}  // namespace btr_app
