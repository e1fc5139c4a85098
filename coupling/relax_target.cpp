#include "coupling/relax_target.h"

#include <cmath>
#include <iostream>
#include <limits>

#include "btr/metrics.h"
#include "coupling/relax_plan.h"

namespace btr {

namespace {
// Reduced-friction stages end once the rearrangement has stopped; the kinetic threshold there is this
// many times the scene's (the settle at full friction uses the scene's own).
constexpr double kStageKineticLoosening = 100.0;
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

std::vector<double> target_phi_schedule() { return {0.5, 0.25, 0.125, 0.0625, 0.03125, 0.0}; }

TargetPhiResult relax_to_target_phi(const Packing& packing, const Scene& scene, const std::string& engine,
                                    const RelaxSettings& settings, double target_phi, const std::string& out_dir,
                                    const std::vector<double>& schedule, double margin) {
  if (!(target_phi > 0.0 && target_phi < 1.0))
    throw RelaxRefused("target packing fraction must be in (0, 1), got " + std::to_string(target_phi));
  for (std::size_t k = 0; k < schedule.size(); ++k)
    if (!(schedule[k] >= 0.0 && schedule[k] < 1.0 && (k == 0 || schedule[k] < schedule[k - 1])))
      throw RelaxRefused("target packing fraction: friction scales must decrease within [0, 1)");
  if (schedule.empty()) throw RelaxRefused("target packing fraction: no friction scale to try");
  TargetPhiResult out;
  Packing current = packing;
  const auto record = [&](double scale, const RelaxResult& r) {
    TargetPhiStage st;
    st.friction_scale = scale;
    st.packing_fraction = bulk_packing_fraction(r.relaxed.grains, scene, margin);
    st.wall_seconds = r.wall_seconds;
    st.simulated_time = r.simulated_time;
    st.stop_reason = r.stop_reason;
    out.wall_seconds += r.wall_seconds;
    out.stages.push_back(st);
    std::cout << "target phi " << target_phi << ": friction x " << scale << " -> bulk phi " << st.packing_fraction
              << " (" << r.stop_reason << ", " << r.wall_seconds << " s)\n";
  };
  const double phi0 = bulk_packing_fraction(packing.grains, scene, margin);
  // A pre-loaded start (preload.h) needs BTR's supports: only the first run starts from the BTR packing.
  RelaxSettings later = settings;
  Scene settle_scene = scene;
  if (std::isnan(phi0)) throw RelaxRefused("target packing fraction: the packing has no bulk window to measure");
  if (!(phi0 >= target_phi)) {
    for (std::size_t k = 0; k < schedule.size() && !out.reached; ++k) {
      Scene stage = with_friction_scaled(settle_scene, schedule[k]);
      stage.relax.stop_kinetic_ratio *= kStageKineticLoosening;
      RelaxResult r = relax(current, stage, engine, later, out_dir + "/friction_" + std::to_string(k + 1));
      later.preload = false, settle_scene.relax.preload = false;
      record(schedule[k], r);
      current.grains = r.relaxed.grains;
      if (!r.removed.empty())
        throw EngineFailure("target packing fraction: grains left an open container in a reduced-friction stage; "
                            "use a walled or periodic container");
      out.reached = out.stages.back().packing_fraction >= target_phi;
    }
  } else {
    out.reached = true;  // already at or above the target: only the settle
  }
  out.settled = relax(current, settle_scene, engine, later, out_dir);
  record(1.0, out.settled);
  nlohmann::json stages = nlohmann::json::array();
  for (const TargetPhiStage& s : out.stages)
    stages.push_back({{"friction_scale", s.friction_scale}, {"bulk_packing_fraction", s.packing_fraction},
                      {"wall_seconds", s.wall_seconds}, {"simulated_time", s.simulated_time},
                      {"stop_reason", s.stop_reason}});
  out.settled.relaxed.meta["target_phi"] = {
      {"target", target_phi}, {"window_margin_diameters", margin}, {"initial_bulk_packing_fraction", phi0}, {"reached", out.reached},
      {"stages", stages}, {"wall_seconds_all_runs", out.wall_seconds},
      {"recipe", "friction scaled stage by stage (stages[].friction_scale), stopping at the first whose bulk phi >= target ("
                 "kinetic threshold x" + std::to_string(static_cast<int>(kStageKineticLoosening)) +
                     "), then full friction settled by the scene's stop rule"}};
  write_packing_meta(out_dir, "relaxed", out.settled.relaxed.meta);
  return out;
}

}  // namespace btr
