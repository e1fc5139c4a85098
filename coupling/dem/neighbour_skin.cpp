#include "coupling/dem/neighbour_skin.h"

#include <algorithm>
#include <cmath>

#include "coupling/dem/materials.h"

namespace btr {

double pour_impact_speed(const PourRelease& pour) {
  return std::sqrt(2.0 * kGravity * (pour.drop_gap + 2.0 * pour.r_max));
}

double neighbour_skin(const RelaxPlan& plan, double r_min) {
  const double base = kBaseSkinRadii * r_min;
  if (!plan.pour.enabled) return base;
  const double crossing = 2.0 * kPourStepsPerRebuild * pour_impact_speed(plan.pour) * plan.timestep;
  return std::clamp(crossing, base, kMaxPourSkinRadii * r_min);
}

}  // namespace btr
