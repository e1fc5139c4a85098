#include "coupling/dem/check_schedule.h"

#include <algorithm>
#include <cmath>

namespace btr {

namespace {

constexpr long kChecksOverMaxTime = 500;  // at most this many stop checks over max_time
// Each check ends a `run` chunk; a check window is at least this many steps. Short chunks and frequent
// samples (every sample is an MPI_Allreduce, a synchronisation of all ranks) made 2 MPI ranks slower
// than 1 (coupling/README.md, "MPI").
constexpr long kMinStepsPerCheck = 1000;

}  // namespace

CheckSchedule check_schedule(const Grains& grains, const Scene& scene, const RelaxPlan& plan) {
  CheckSchedule s;
  const long total = std::max(1L, static_cast<long>(std::ceil(plan.max_time / plan.timestep)));
  long window = std::max(kMinStepsPerCheck, (total + kChecksOverMaxTime - 1) / kChecksOverMaxTime);
  if (plan.pour.enabled) window = std::max(kMinStepsPerCheck, plan.pour.steps_per_check);  // the pour's interval
  window = (window + kAveragedSamples - 1) / kAveragedSamples * kAveragedSamples;
  s.steps_per_check = window;
  s.average_every = window / kAveragedSamples;
  s.max_checks = std::max(1L, (total + window - 1) / window);
  s.arming_time = plan.arming_time > 0.0 ? plan.arming_time : stop_arming_time(grains);
  s.blowup_bound = kinetic_energy_bound(grains, scene) + (plan.tap.enabled ? plan.tap.energy_input : 0.0);
  return s;
}

}  // namespace btr
