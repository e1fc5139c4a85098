#include "coupling/dem/settle_verdict.h"

#include <cmath>

#include "btr/model/number_text.h"

namespace btr {

TargetVerdict settle_target_verdict(double btr_phi, double settled_phi, bool compaction_ran, bool compaction_reached,
                                    double target, double standard_error,
                                    const nlohmann::json& calibration_coordination) {
  TargetVerdict v;
  const double reach = kTargetPrecisionErrors * standard_error;
  if (!compaction_ran && btr_phi > target + reach) {
    v.off_target = true;
    v.looser_than_btr = {
        {"btr_bulk_packing_fraction", btr_phi},
        {"target", target},
        {"standard_error", standard_error},
        {"limit", target + reach},
        {"calibration_bulk_coordination", calibration_coordination},
        {"why", "the BTR bed (bulk phi " + g6(btr_phi) + ") is denser than the target " + g6(target) + " +- " +
                    g6(standard_error) + " by more than " + g6(kTargetPrecisionErrors) +
                    " of its standard errors: this material pours looser than BTR places grains. Settle "
                    "compacts and cannot loosen, so the settled bed keeps BTR's packing fraction and its contact "
                    "network (compare the settled bulk coordination with the calibration pour's). Pour the scene "
                    "(`btr pour`) for a DEM initial condition of this material"}};
  }
  if (compaction_ran && !compaction_reached) {
    const bool within = std::isfinite(settled_phi) && target - settled_phi <= reach;
    v.off_target = v.off_target || !within;
    v.short_of_target = {
        {"settled_bulk_packing_fraction", std::isfinite(settled_phi) ? nlohmann::json(settled_phi) : nlohmann::json()},
        {"target", target},
        {"standard_error", standard_error},
        {"limit", target - reach},
        {"within_precision", within},
        {"why", "the compaction came to rest below the target " + g6(target) + " +- " + g6(standard_error) +
                    "; the settled bed (" + (std::isfinite(settled_phi) ? g6(settled_phi) : std::string("no bulk window")) +
                    ") is " + (within ? "within " : "further than ") + g6(kTargetPrecisionErrors) +
                    " of its standard errors from it" + (within ? ", as close as the target is known" : "")}};
  }
  return v;
}

nlohmann::json relaxation_not_at_rest(const nlohmann::json& relax, const Grains& grains,
                                      const std::vector<Vec3>& velocities, bool heap) {
  if (relax.value("stop_reason", std::string()) != "max-time") return nullptr;
  const std::string rule = relax.value("stop_rule", std::string());
  const char* final_key = rule == "unbalanced-force" ? "final_unbalanced_force"
                          : rule == "kinetic-energy" ? "final_kinetic_energy"
                                                     : nullptr;  // no final displacement is recorded
  const nlohmann::json final_value = final_key ? relax.value(final_key, nlohmann::json()) : nlohmann::json();
  const double threshold = relax.value("stop_threshold", std::nan("")), time = relax.value("simulated_time", 0.0);
  nlohmann::json record = {
      {"stop_rule", rule}, {"threshold", threshold}, {"final_value", final_value}, {"simulated_seconds", time}};
  std::string fastest;
  if (!velocities.empty() && velocities.size() == grains.size()) {
    std::size_t k = 0;
    for (std::size_t i = 1; i < velocities.size(); ++i)
      if (velocities[i].squaredNorm() > velocities[k].squaredNorm()) k = i;
    const double speed = velocities[k].norm();
    record["fastest_grain"] = {{"id", k + 1}, {"speed", speed}, {"x", {grains[k].x.x(), grains[k].x.y(), grains[k].x.z()}}};
    fastest = "; its fastest grain (id " + std::to_string(k + 1) + ") moved at " + g6(speed) + " m/s";
  }
  record["why"] = "the relaxation ran to its max time (" + g6(time) + " s simulated) without its stop rule (" + rule +
                  " below " + g6(threshold) + (final_value.is_number() ? ", at the end " + g6(final_value.get<double>()) : "") +
                  "): the packing was still moving when it was written" + fastest +
                  (heap ? ". A heap whose toe rolls on the floor (no rolling resistance) has no rest state: its angle "
                          "follows the time it is given, as a pour's does (docs/settle/heaps/README.md)"
                        : "");
  return record;
}

}  // namespace btr
