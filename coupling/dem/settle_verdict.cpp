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

}  // namespace btr
