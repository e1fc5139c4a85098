#pragma once
// The DEM tapping of `btr shake --engine` (tapping.h), as the engines' writers need it: a plain schedule, part of
// RelaxPlan (engine_adapter.h), and what an engine gives back after each tap.
#include <limits>
#include <vector>

#include "btr/model/grain.h"

namespace btr {

// Per tap the floor (a plane at z = 0 at rest) moves by z(t) = amplitude sin(2 pi t / period) for exactly one
// period (steps_per_tap steps, the time step a whole fraction of the period, so the floor ends where it started),
// then rests: check windows of steps_per_check steps until the relaxation's kinetic rule holds (the kinetic
// energy and its mean over the window below the plan's kinetic_threshold), at most max_rest_checks windows.
// After each rest the grains are written (the engine's per-tap output).
struct TapSchedule {
  bool enabled = false;
  long taps = 0;
  double gamma = 0.0;          // peak acceleration / g
  double frequency = 0.0;      // Hz, 1 / period
  double amplitude = 0.0;      // m
  double period = 0.0;         // s
  long steps_per_tap = 0;
  long steps_per_check = 0;
  long max_rest_checks = 0;
  double energy_input = 0.0;   // J added to the blow-up bound: what the moving floor may give the grains
};

// What an engine reports after tap `tap` (1-based) has rested.
struct TapSnapshot {
  long tap = 0;
  Grains grains;               // same order and ids as the run's input
  double moved_time = 0.0;     // s, simulated time at the end of the floor's motion
  double moved_kinetic = 0.0;  // J, kinetic energy then (the grains in flight)
  double rested_time = 0.0;    // s, at the end of the rest
  double rested_kinetic = 0.0; // J
  bool settled = false;        // the kinetic rule held (else the rest hit max_rest_checks)
  long step = 0;               // the run's time step count at the end of the rest
  // The floor's motion during the tap as the engine's script measured it on the floor body at every step (YADE;
  // NaN where an engine does not measure it): highest and lowest displacement from its rest height [m], largest
  // speed [m/s], and the displacement left when the period ended (round-off, then removed) [m].
  static constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();
  double floor_highest = kNotMeasured, floor_lowest = kNotMeasured, floor_peak_speed = kNotMeasured,
         floor_end = kNotMeasured;
};

}  // namespace btr
