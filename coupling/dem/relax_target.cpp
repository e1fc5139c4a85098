#include "coupling/dem/relax_target.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "btr/model/grain.h"
#include "btr/model/number_text.h"
#include "coupling/dem/relax_plan.h"

namespace btr {

namespace {
// The packing fraction is checked this often during the compaction: a free collapse gains ~0.002 per 100
// steps near the target (bed3d), so a check every 50 steps overshoots by at most about the pours' own
// seed-to-seed spread.
constexpr long kCompactionCheckSteps = 50;
// A friction scale has brought the bed to rest when its kinetic energy and its mean are below this many times
// the stop threshold: the compaction only needs the rearrangement to end, not the settle's rest.
constexpr double kRestLoosening = 100.0;

}  // namespace

Scene with_friction_scaled(const Scene& scene, double scale) {
  Scene s = scene;
  for (Component& c : s.grains.components) {
    c.material.friction *= scale;
    c.material.rolling_friction *= scale;
  }
  return s;
}

double bulk_packing_fraction(const Grains& grains, const Scene& scene, double margin) {
  MetricsOptions o;
  o.margin_diameters = margin;
  const BulkMeasures b = bulk_measures(grains, scene.dimension, scene.container, o);
  return b.valid ? b.packing_fraction : std::numeric_limits<double>::quiet_NaN();
}

CompactionWindow compaction_window(const Grains& grains, const Scene& scene, double margin, double target) {
  CompactionWindow w;
  MetricsOptions o;
  o.margin_diameters = margin;
  const BulkMeasures b = bulk_measures(grains, scene.dimension, scene.container, o);
  if (!b.valid) {
    w.why = b.note;
    return w;
  }
  w.measured = true;
  w.initial_phi = b.packing_fraction;
  w.grains = b.grains_in_window;
  const double m = margin * 2.0 * max_radius(grains);
  w.slab = b.slab;
  w.lo = b.window.lo;
  w.hi = b.window.hi;
  if (w.initial_phi < target) w.hi.z() = (b.window.hi.z() + m) * w.initial_phi / target - m;
  w.valid = w.hi.z() > w.lo.z();
  if (!w.valid)
    w.why = "the bed is too shallow to keep a bulk window through a compaction from " + g6(w.initial_phi) + " to " +
            g6(target);
  return w;
}

std::vector<CompactionPlan::Slab> compaction_slabs(const Grains& grains, const Scene& scene, double margin,
                                                   const CompactionPlan& c, int count) {
  if (count < 2) return {};
  if (static_cast<std::size_t>(count) > grains.size())
    throw RelaxRefused("compaction in " + std::to_string(count) + " slabs: the packing has only " +
                       std::to_string(grains.size()) + " grains");
  if (c.friction_scales.size() != 1)
    throw RelaxRefused("compaction in slabs: it runs one friction scale, got " +
                       std::to_string(c.friction_scales.size()));
  const double cross_section = c.window_measure / (c.window_hi.z() - c.window_lo.z());
  std::vector<CompactionPlan::Slab> slabs;
  double lo = c.window_lo.z();
  for (int k = 1; k <= count; ++k) {
    CompactionPlan::Slab s;
    s.last = grains.size() * static_cast<std::size_t>(k) / static_cast<std::size_t>(count) - 1;
    double hi = c.window_hi.z();
    if (k < count) {  // the first s.last + 1 drops are a BTR bed of their own: its window, lowered as the bed's
      const Grains below(grains.begin(), grains.begin() + static_cast<std::ptrdiff_t>(s.last + 1));
      const CompactionWindow w = compaction_window(below, scene, margin, c.target);
      if (!w.valid)
        throw RelaxRefused("compaction in slabs: slab " + std::to_string(k) + " has no window (" + w.why +
                           "): use fewer slabs");
      hi = w.hi.z();
    }
    if (!(hi > lo))
      throw RelaxRefused("compaction in slabs: slab " + std::to_string(k) + "'s window is empty (its top " + g6(hi) +
                         " m is not above the slab below's " + g6(lo) + " m): use fewer slabs");
    s.window_lo_z = lo;
    s.window_hi_z = hi;
    s.window_measure = cross_section * (hi - lo);
    slabs.push_back(s);
    lo = hi;
  }
  return slabs;
}

CompactionPlan plan_compaction(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                               double timestep, double kinetic_threshold) {
  CompactionPlan c;
  const std::optional<double> target = settings.target_phi ? settings.target_phi : scene.relax.target_phi;
  if (!target) return c;
  c.target = *target;
  if (!(c.target > 0.0 && c.target < 1.0))
    throw RelaxRefused("target packing fraction must be in (0, 1), got " + g6(c.target));
  c.friction_scales = settings.friction_scales ? *settings.friction_scales : scene.relax.friction_scales;
  if (c.friction_scales.empty()) throw RelaxRefused("target packing fraction: no friction scale to try");
  for (std::size_t k = 0; k < c.friction_scales.size(); ++k)
    if (!(c.friction_scales[k] >= 0.0 && c.friction_scales[k] < 1.0 &&
          (k == 0 || c.friction_scales[k] < c.friction_scales[k - 1])))
      throw RelaxRefused("target packing fraction: friction scales must decrease within [0, 1)");
  c.damping = settings.compaction_damping ? *settings.compaction_damping : scene.relax.compaction_damping;
  if (!(c.damping >= 0.0 && c.damping < 1.0))
    throw RelaxRefused("target packing fraction: compaction damping must be in [0, 1), got " + g6(c.damping));
  c.timestep_fraction = settings.compaction_timestep_fraction ? *settings.compaction_timestep_fraction
                        : scene.relax.compaction_timestep_fraction ? *scene.relax.compaction_timestep_fraction
                                                                    : scene.relax.timestep_fraction;
  if (!(c.timestep_fraction > 0.0 && c.timestep_fraction <= 1.0))
    throw RelaxRefused("target packing fraction: the compaction's time-step fraction must be in (0, 1], got " +
                       g6(c.timestep_fraction));
  c.timestep = timestep * c.timestep_fraction / scene.relax.timestep_fraction;
  for (const Grain& g : packing.grains)
    if (g.cluster != 0)
      throw RelaxRefused("target packing fraction: the packing has rigid clusters (grain " +
                         std::to_string(&g - packing.grains.data() + 1) +
                         "); the compaction's friction switch and stop of every grain are not written for rigid "
                         "bodies: relax without --target-phi");

  const CompactionWindow w = compaction_window(packing.grains, scene, settings.target_margin, c.target);
  if (!w.measured)
    throw RelaxRefused("target packing fraction: the packing has no bulk window to measure (" + w.why +
                       "); use a smaller --target-margin or a deeper packing");
  c.initial_phi = w.initial_phi;
  if (c.initial_phi >= c.target) return c;  // already there: no compaction
  if (!w.valid)
    throw RelaxRefused("target packing fraction: " + w.why + "; use a smaller --target-margin");
  c.slab = w.slab;
  c.window_lo = w.lo;
  c.window_hi = w.hi;
  const double height = c.window_hi.z() - c.window_lo.z();
  const double dx = c.window_hi.x() - c.window_lo.x(), dy = c.window_hi.y() - c.window_lo.y();
  c.window_measure = scene.dimension == 3 ? dx * dy * height : dx * height;
  c.steps_per_check = kCompactionCheckSteps;
  c.max_checks_per_scale =
      std::max(1L, static_cast<long>(std::ceil(scene.relax.max_time / c.timestep / kCompactionCheckSteps)));
  c.rest_kinetic = kRestLoosening * kinetic_threshold;
  c.slabs = compaction_slabs(packing.grains, scene, settings.target_margin, c, settings.compaction_slabs);
  c.enabled = true;
  return c;
}

namespace {
nlohmann::json slabs_record(const CompactionPlan& plan, const RelaxResult& result) {
  nlohmann::json rec = nlohmann::json::array();
  for (std::size_t k = 0; k < plan.slabs.size(); ++k) {
    const CompactionPlan::Slab& s = plan.slabs[k];
    nlohmann::json r = {{"grains", s.last + 1 - (k == 0 ? 0 : plan.slabs[k - 1].last + 1)},
                        {"window_z", {s.window_lo_z, s.window_hi_z}}};
    if (k < result.compaction.slabs.size())
      r.update({{"reached", result.compaction.slabs[k].reached},
                {"time", result.compaction.slabs[k].time},
                {"in_run_packing_fraction", result.compaction.slabs[k].packing_fraction}});
    rec.push_back(r);
  }
  return rec;
}
}  // namespace

nlohmann::json target_phi_record(const CompactionPlan& plan, const RelaxResult& result, const Scene& scene,
                                 double margin) {
  const double settled = bulk_packing_fraction(result.relaxed.grains, scene, margin);
  nlohmann::json rec = {
      {"target", plan.target},
      {"window_margin_diameters", margin},
      {"initial_bulk_packing_fraction", plan.initial_phi},
      {"settled_bulk_packing_fraction", std::isfinite(settled) ? nlohmann::json(settled) : nlohmann::json(nullptr)},
      {"compaction_ran", plan.enabled},
      {"reached", plan.enabled ? result.compaction.reached : true},
  };
  if (plan.enabled)
    rec.update({{"friction_scales", plan.friction_scales},
                {"compaction_damping", plan.damping},
                {"compaction_timestep", plan.timestep},
                {"compaction_timestep_fraction", plan.timestep_fraction},
                {"friction_scale_at_end", result.compaction.friction_scale},
                {"friction_restored_at", result.compaction.time},
                {"in_run_packing_fraction_at_end", result.compaction.packing_fraction},
                {"recipe", "in one engine run: friction scaled (friction_scales, the next when the bed came to rest "
                           "below the target) with compaction_damping until the packing fraction "
                           "of the bulk window reached the target; then the scene's friction restored, every "
                           "grain stopped, and the scene's stop rule run with relax.damping"}});
  else
    rec["recipe"] = "the packing already had the target: relaxed without compaction";
  if (plan.enabled && !plan.slabs.empty()) {
    rec["slabs"] = slabs_record(plan, result);
    rec["recipe"] = "in one engine run, slab by slab from the floor up (slabs: grains in drop order), as a pour "
                    "builds the bed: the slab released (the grains above held, not integrated) and frictionless "
                    "(friction_scales) with compaction_damping until the packing fraction of its window reached the "
                    "target, then its friction restored and the next slab released; after the last, every grain "
                    "stopped and the scene's stop rule run with relax.damping";
  }
  return rec;
}

}  // namespace btr
