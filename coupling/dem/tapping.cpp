// DEM tapping, engine-independent part (tapping.h).
#include "coupling/dem/tapping.h"

#include <algorithm>
#include <cmath>
#include <iostream>

#include "btr/model/number_text.h"
#include "coupling/dem/check_schedule.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/relax_plan.h"

namespace btr {

Scene engine_scene(const Scene& scene) {
  Scene out = scene;
  if (!scene.intruder || scene.grains.components.empty()) return out;
  for (const Component& c : scene.grains.components)
    if (c.species == scene.intruder->species) return out;
  Component intruder = scene.grains.components.front();
  intruder.species = scene.intruder->species;
  intruder.fraction = 0.0;
  out.grains.components.push_back(intruder);
  return out;
}

double tap_amplitude(double gamma, double frequency) {
  const double omega = 2.0 * M_PI * frequency;
  return gamma * kGravity / (omega * omega);
}

RelaxPlan make_tap_plan(const Packing& start, const Scene& scene, const TapSettings& settings,
                        const std::string& engine) {
  if (!scene.shaking) refuse_scene_field(scene, "[shaking]", "missing; DEM tapping takes its gamma and frequency there");
  if (scene.container.kind != ContainerKind::Periodic && scene.container.kind != ContainerKind::Box)
    refuse_scene_field(scene, "container.kind",
                       std::string("\"") + to_string(scene.container.kind) +
                           "\" is not tapped: DEM tapping moves a flat floor under a periodic or box container");
  if (scene.clusters) refuse_scene_field(scene, "[clusters]", "DEM tapping moves single grains, not rigid clusters");
  for (const Grain& g : start.grains)
    if (g.cluster != 0) throw RelaxRefused("tapping: grains in rigid clusters are not tapped");
  if (settings.taps < 1) throw RelaxRefused("--taps: expected at least 1 tap, got " + std::to_string(settings.taps));
  if (!(settings.max_rest_time > 0.0) || !std::isfinite(settings.max_rest_time))
    throw RelaxRefused("--rest-time: expected a positive time [s], got " + g6(settings.max_rest_time));

  Scene calm = scene;  // the relaxation's rules without what would change the tapping's dynamics
  calm.relax.target_phi.reset();
  calm.relax.damping = 0.0;
  RelaxSettings rs;
  rs.np = settings.np;
  rs.wall_time_limit = settings.wall_time_limit;
  RelaxPlan plan = make_plan(start, calm, rs, engine);
  plan.compaction = CompactionPlan{};
  plan.damping = 0.0;

  TapSchedule& tap = plan.tap;
  tap.enabled = true;
  tap.taps = settings.taps;
  tap.gamma = scene.shaking->gamma.value_or(kDefaultTapGamma);
  tap.frequency = scene.shaking->frequency.value_or(kDefaultTapFrequency);
  tap.period = 1.0 / tap.frequency;
  tap.amplitude = tap_amplitude(tap.gamma, tap.frequency);
  // A whole number of steps per period: the floor ends each tap where it started.
  tap.steps_per_tap = static_cast<long>(std::ceil(tap.period / plan.stable_timestep * (1.0 - 1e-12)));
  tap.steps_per_tap = std::max(tap.steps_per_tap, 20L);
  plan.timestep = tap.period / static_cast<double>(tap.steps_per_tap);
  plan.timestep_rule = plan.timestep_rule + ", lowered to the tap period / " + std::to_string(tap.steps_per_tap);
  // What the floor may give the grains per tap: a grain bouncing off the floor at its peak speed A omega leaves at
  // up to 2 A omega, and the bed is lifted by up to A; twice that, as the blow-up bound doubles the energy held.
  double mass = 0.0;
  for (const Grain& g : start.grains)
    mass += grain_mass(g.r, scene.grains.components[component_index(scene, g.species)].density);
  const double v_peak = tap.amplitude * 2.0 * M_PI * tap.frequency;
  tap.energy_input = 2.0 * mass * (0.5 * (2.0 * v_peak) * (2.0 * v_peak) + kGravity * tap.amplitude);
  // The rest: windows of the relaxation's check window, at most max_rest_time in all.
  const CheckSchedule sched = check_schedule(start.grains, calm, plan);
  tap.steps_per_check = sched.steps_per_check;
  const double window = static_cast<double>(tap.steps_per_check) * plan.timestep;
  tap.max_rest_checks = std::max(1L, static_cast<long>(std::ceil(settings.max_rest_time / window - 1e-9)) - 1);
  return plan;
}

TapResult run_tapping(const Packing& start, const Scene& scene, const EngineAdapter& adapter, const std::string& engine,
                      const TapSettings& settings, const RelaxPlan& plan, const std::string& dir) {
  RelaxSettings rs;
  rs.np = settings.np;
  rs.wall_time_limit = settings.wall_time_limit;
  const TapSchedule& tap = plan.tap;
  std::cout << "tapping: " << tap.taps << " taps of Gamma " << g6(tap.gamma) << " at " << g6(tap.frequency)
            << " Hz (amplitude " << g6(tap.amplitude) << " m, " << tap.steps_per_tap << " steps of "
            << g6(plan.timestep) << " s), each followed by a rest of at most "
            << g6((tap.max_rest_checks + 1) * tap.steps_per_check * plan.timestep) << " s\n";
  write_engine_inputs(start, scene, adapter, rs, plan, dir);
  TapResult out;
  out.plan = plan;
  out.run = run_and_read_back(start, scene, adapter, engine, rs, plan, dir, "tapping");
  out.taps = adapter.read_taps(dir, start, plan);
  write_run_tables(out.run, dir);

  const std::vector<DemWall> walls = dem_walls(scene.container, scene.dimension);
  for (TapSnapshot& t : out.taps)
    for (std::size_t i = 0; i < t.grains.size(); ++i) {
      Grain& g = t.grains[i];
      g.x = wrap_into_cell(scene.container, scene.dimension, g.x);
      for (const DemWall& w : walls)
        if (w.distance(g.x) < 0.0)
          throw EngineFailure(FailureKind::OutsideContainer,
                              engine + " tapping failed in " + dir + ": after tap " + std::to_string(t.tap) +
                                  " grain " + std::to_string(i + 1) + " is beyond the " + w.name + " wall by " +
                                  g6(-w.distance(g.x)) + " m",
                              {{"tap", t.tap}, {"grain", i + 1}, {"wall", w.name}, {"beyond", -w.distance(g.x)}});
    }
  // The engine's processor and wall time up to each tap, shared out by time steps (one run of evenly costly
  // steps; the process's own total is the only processor time measured).
  const double total_steps = out.taps.empty() ? 1.0 : std::max(1.0, static_cast<double>(out.taps.back().step));
  nlohmann::json rows = nlohmann::json::array();
  long previous_step = 0;
  double previous_time = 0.0;
  for (const TapSnapshot& t : out.taps) {
    const double share = static_cast<double>(t.step) / total_steps;
    const double share_tap = static_cast<double>(t.step - previous_step) / total_steps;
    out.cpu_seconds.push_back(out.run.cpu_seconds * share);
    nlohmann::json row = {{"tap", t.tap},
                    {"moved_time", t.moved_time},
                    {"moved_kinetic_energy", t.moved_kinetic},
                    {"rested_time", t.rested_time},
                    {"rest_time", t.rested_time - t.moved_time},
                    {"rested_kinetic_energy", t.rested_kinetic},
                    {"settled", t.settled},
                    {"steps", t.step - previous_step},
                    {"simulated_time", t.rested_time - previous_time},
                    {"engine_cpu_seconds", out.run.cpu_seconds * share_tap},
                    {"engine_wall_seconds", out.run.wall_seconds * share_tap}};
    if (std::isfinite(t.floor_highest))  // measured by the engine's script on the floor body (YADE)
      row["floor_measured"] = {{"highest", t.floor_highest},
                               {"lowest", t.floor_lowest},
                               {"peak_speed", t.floor_peak_speed},
                               {"end", t.floor_end}};
    rows.push_back(row);
    previous_step = t.step;
    previous_time = t.rested_time;
  }
  const double n = std::max<double>(1.0, static_cast<double>(out.taps.size()));
  out.record = {
      {"engine", engine},
      {"np", settings.np},
      {"grains", start.grains.size()},
      {"taps", tap.taps},
      {"gamma", tap.gamma},
      {"frequency", tap.frequency},
      {"amplitude", tap.amplitude},
      {"period", tap.period},
      {"peak_velocity", tap.amplitude * 2.0 * M_PI * tap.frequency},
      {"motion", "per tap one period of z(t) = amplitude sin(2 pi frequency t) of the floor, then a rest"},
      {"timestep", plan.timestep},
      {"timestep_rule", plan.timestep_rule},
      {"stable_timestep", plan.stable_timestep},
      {"steps_per_tap", tap.steps_per_tap},
      {"rest",
       {{"rule", "kinetic energy below kinetic_threshold at the ends of two check windows in a row, or max_time"},
        {"kinetic_threshold", plan.kinetic_threshold},
        {"window_steps", tap.steps_per_check},
        {"window_time", tap.steps_per_check * plan.timestep},
        {"max_time", (tap.max_rest_checks + 1) * tap.steps_per_check * plan.timestep}}},
      {"blowup_bound_extra", tap.energy_input},
      {"per_tap", rows},
      {"simulated_time", out.run.simulated_time},
      {"engine_cpu_seconds", out.run.cpu_seconds},
      {"wall_seconds", out.run.wall_seconds},
      {"engine_cpu_seconds_per_tap", out.run.cpu_seconds / n},
      {"engine_wall_seconds_per_tap", out.run.wall_seconds / n},
      {"cpu_rule", "the engine process's processor time (user + system), shared out over the taps by time steps"},
  };
  return out;
}

}  // namespace btr
