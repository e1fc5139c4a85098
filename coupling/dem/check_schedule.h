#pragma once
// How a relaxation samples and stops, the same in both engines: the check window (thermo interval = stop-rule
// check interval = averaging window), the kinetic-energy samples averaged in it, the arming time and the
// blow-up bound, all derived from the plan. A window is at least 1000 steps: every check ends a `run` chunk and
// synchronises MPI ranks. A pour (plan.pour) asks for its own window (its check interval), at least as long.
#include "coupling/dem/relax_plan.h"

namespace btr {

inline constexpr long kAveragedSamples = 20;  // kinetic-energy samples in each check window (its mean)

struct CheckSchedule {
  long steps_per_check = 0;   // thermo interval = stop-rule check interval = averaging window
  long average_every = 0;     // fix ave/time Nevery (Nrepeat = steps_per_check / average_every)
  long max_checks = 0;        // checks until max_time
  double arming_time = 0.0;   // s
  double blowup_bound = 0.0;  // J
};
CheckSchedule check_schedule(const Grains& grains, const Scene& scene, const RelaxPlan& plan);

}  // namespace btr
