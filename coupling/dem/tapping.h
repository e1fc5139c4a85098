#pragma once
// DEM tapping of a packing at rest (btr shake --engine; docs/guide/shake_dem.md), engine-independent part: the
// plan (amplitude and period from the scene's [shaking] gamma and frequency, the time step a whole fraction of
// the period, the rest's windows), the run through the engine's writer and read-back (relax_plan.h), the grains
// after each tap and the record. The engines' writers turn RelaxPlan::tap (tap_schedule.h) into their inputs.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/tap_schedule.h"

namespace btr {

// The longest rest after a tap, simulated seconds, unless asked otherwise: 15 periods of the default 30 Hz tap.
// The kinetic rule ends most rests sooner on stiff beds; a soft bed (E = 5 MPa) of 1500 grains still creeps at
// 1e-4 of sum m g d after 0.2 s (docs/guide/shake_dem.md).
inline constexpr double kDefaultTapRestTime = 0.5;

struct TapSettings {
  long taps = 1;
  double max_rest_time = kDefaultTapRestTime;  // s
  int np = 1;                       // LIGGGHTS: MPI ranks; YADE: threads
  double wall_time_limit = 3600.0;  // s; the engine run is killed past this
};

// The scene as the engines run a shaken bed: an intruder (its species, the bed's + 1, is no component of the
// scene) becomes a component of the first component's material and density (fraction 0: it draws no grains), so
// that the engines' writers give it a type. Other scenes are returned unchanged.
Scene engine_scene(const Scene& scene);

// Amplitude A [m] of a tap of peak acceleration gamma g at `frequency` [Hz]: A = gamma g / (2 pi f)^2.
double tap_amplitude(double gamma, double frequency);

// The plan of tapping `start` (a packing at rest): the relaxation's plan (time step rule, kinetic threshold; no
// damping, no compaction), the time step lowered to period / ceil(period / step), and plan.tap (rest windows of
// the relaxation's check window, up to settings.max_rest_time). Throws RelaxRefused (naming the scene field) for a
// scene without [shaking], a container other than periodic or box, rigid clusters, taps < 1 or a rest time <= 0.
RelaxPlan make_tap_plan(const Packing& start, const Scene& scene, const TapSettings& settings,
                        const std::string& engine);

struct TapResult {
  RelaxPlan plan;
  RelaxResult run;                 // the whole engine run (final state, kinetic history, cpu and wall seconds)
  std::vector<TapSnapshot> taps;   // after each tap's rest, grains wrapped into the cell
  std::vector<double> cpu_seconds; // the engine's processor time up to each tap's end (the run's, shared by steps)
  nlohmann::json record;           // shake_dem.json's "tapping" part
};

// Writes the inputs into dir, runs the engine, reads every tap back and checks it (ids kept, no centre below the
// floor or beyond a wall). Throws EngineFailure, Interrupted or RelaxRefused.
TapResult run_tapping(const Packing& start, const Scene& scene, const EngineAdapter& adapter, const std::string& engine,
                      const TapSettings& settings, const RelaxPlan& plan, const std::string& dir);

}  // namespace btr
