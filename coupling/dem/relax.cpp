// DEM relaxation, engine-independent part: plan (time step, overlap, stop threshold), inputs, run,
// checks of the result, output files. The engines live behind EngineAdapter.
#include "coupling/dem/relax.h"

#include <stdexcept>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>

#include "btr/model/container.h"
#include "btr/model/number_text.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/open_floor_region.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/preload.h"
#include "coupling/dem/process.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/relax_target.h"
#include "coupling/dem/timestep.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/force_io.h"

namespace btr {

namespace fs = std::filesystem;

void refuse_scene_field(const Scene& scene, const std::string& field, const std::string& why) {
  throw RelaxRefused((scene.file.empty() ? "scene '" + scene.name + "'" : scene.file) + ": " + field + ": " + why);
}

namespace {

constexpr int kLogTailLines = 25;
constexpr const char* kConsoleFile = "console.log";  // the engine's stdout and stderr

void check_inputs(const Packing& packing, const Scene& scene) {
  if (packing.grains.empty()) throw RelaxRefused("the packing has no grains");
  if (scene.dimension != 2 && scene.dimension != 3)
    throw RelaxRefused("scene dimension must be 2 or 3, got " + std::to_string(scene.dimension));
  const RelaxSpec& r = scene.relax;
  if (!(r.max_time > 0.0)) throw RelaxRefused("relax.max_time must be positive, got " + g6(r.max_time));
  if (!(r.stop_kinetic_ratio > 0.0))
    throw RelaxRefused("relax.stop_kinetic_ratio must be positive, got " + g6(r.stop_kinetic_ratio));
  if (!(r.timestep_fraction > 0.0 && r.timestep_fraction <= 1.0))
    throw RelaxRefused("relax.timestep_fraction must be in (0, 1], got " + g6(r.timestep_fraction));
  if (r.stop_rule != "kinetic-energy" && r.stop_rule != "unbalanced-force" && r.stop_rule != "displacement")
    throw RelaxRefused("relax.stop_rule: expected \"kinetic-energy\", \"unbalanced-force\" or \"displacement\", got \"" +
                       r.stop_rule + "\"");
  if (!(r.stop_unbalanced_force > 0.0 && r.stop_unbalanced_force < 1.0))
    throw RelaxRefused("relax.stop_unbalanced_force must be in (0, 1), got " + g6(r.stop_unbalanced_force));
  if (!(r.stop_displacement > 0.0 && r.stop_displacement < 1.0))
    throw RelaxRefused("relax.stop_displacement must be in (0, 1) (of the smallest diameter), got " +
                       g6(r.stop_displacement));
  if (!(r.open_margin > 0.0)) throw RelaxRefused("relax.open_margin must be positive, got " + g6(r.open_margin));
  try {
    dem_walls(scene.container, scene.dimension);
    for (const Grain& g : packing.grains) component_index(scene, g.species);
  } catch (const std::runtime_error& e) {
    throw RelaxRefused(e.what());
  }
  if (scene.dimension == 2)
    for (std::size_t i = 0; i < packing.grains.size(); ++i)
      if (packing.grains[i].x.y() != 0.0)
        throw RelaxRefused("2D packing: grain " + std::to_string(i + 1) + " has y = " + g6(packing.grains[i].x.y()) +
                           " (2D grains lie in the plane y = 0)");
}

constexpr std::pair<FailureKind, const char*> kFailureKindNames[] = {
    {FailureKind::EngineError, "engine_error"},       {FailureKind::TimeLimit, "time_limit"},
    {FailureKind::BlowUp, "blow_up"},                 {FailureKind::NonFinite, "non_finite"},
    {FailureKind::LostGrains, "lost_grains"},         {FailureKind::OutsideContainer, "outside_container"},
    {FailureKind::MissedContact, "missed_contact"},   {FailureKind::BadOutput, "bad_output"},
};

// A number for relax_failure.json: JSON has no NaN or infinity, so those are written as null.
nlohmann::json json_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

const char* failure_kind_name(FailureKind kind) {
  for (const auto& [k, name] : kFailureKindNames)
    if (k == kind) return name;
  return "engine_error";
}

std::optional<FailureKind> failure_kind_from_name(const std::string& name) {
  for (const auto& [k, n] : kFailureKindNames)
    if (name == n) return k;
  return std::nullopt;
}

void clear_failure_record(const std::string& dir) {
  std::error_code ec;
  fs::remove(fs::path(dir) / kRelaxFailureFile, ec);
}

double kinetic_threshold(const Grains& grains, const Scene& scene) {
  const std::vector<double> m = grain_masses(grains, scene);
  double sum = 0.0;
  for (std::size_t i = 0; i < grains.size(); ++i) sum += m[i] * kGravity * 2.0 * grains[i].r;
  return scene.relax.stop_kinetic_ratio * sum;
}

double stop_arming_time(const Grains& grains) {
  double r_min = std::numeric_limits<double>::infinity();
  for (const Grain& g : grains) r_min = std::min(r_min, g.r);
  return std::sqrt(2.0 * r_min / kGravity);
}

double kinetic_energy_bound(const Grains& grains, const Scene& scene) {
  const std::vector<double> m = grain_masses(grains, scene);
  double energy = 0.0;
  for (std::size_t i = 0; i < grains.size(); ++i) energy += m[i] * kGravity * std::max(grains[i].x.z(), 0.0);
  const bool hooke = scene.relax.model == "hooke";
  const double v = hooke_characteristic_velocity(grains);
  const Material& wall = wall_material(scene);
  auto material = [&](std::int64_t id) -> const Material& {
    return scene.grains.components[component_index(scene, grains[id - 1].species)].material;
  };
  for_each_overlap(grains, scene.dimension, scene.container,
                   [&](std::int64_t a, std::int64_t b, double depth, const DemWall*) {
                     const double ra = grains[a - 1].r, ma = m[a - 1];
                     const double r_eff = b == 0 ? ra : ra * grains[b - 1].r / (ra + grains[b - 1].r);
                     const double m_eff = b == 0 ? ma : ma * m[b - 1] / (ma + m[b - 1]);
                     const double y_eff = effective_young(material(a), b == 0 ? wall : material(b));
                     if (scene.relax.model == "hooke-stiffness")
                       energy += 0.5 * pair_material(material(a), b == 0 ? material(a) : material(b)).kn * depth * depth;
                     else if (hooke)
                       energy += 0.5 * hooke_stiffness(r_eff, m_eff, y_eff, v) * depth * depth;
                     else
                       energy += 8.0 / 15.0 * y_eff * std::sqrt(r_eff) * std::pow(depth, 2.5);
                   });
  return 2.0 * energy;
}

double preload_arming_time(double largest_intended_depth, double timestep) {
  return std::max(std::sqrt(2.0 * largest_intended_depth / kGravity), 50.0 * timestep);
}

Packing starting_packing(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                         IntendedOverlaps& intended, const std::string& out_dir) {
  intended.clear();
  if (!settings.preload && !scene.relax.preload) return packing;
  check_inputs(packing, scene);
  Preloaded p;
  try {
    p = preload_packing(packing.grains, scene);
  } catch (const std::runtime_error& e) {
    throw RelaxRefused(e.what());
  }
  Packing out;
  out.grains = std::move(p.grains);
  out.meta = packing.meta.is_object() ? packing.meta : nlohmann::json::object();
  out.meta["preload"] = {{"model", scene.relax.model},
                         {"contacts", p.forces.contacts.size()},
                         {"largest_intended_overlap", p.largest_relative},
                         {"largest_intended_depth", p.largest_depth},
                         {"largest_move", p.largest_move},
                         {"largest_misfit", p.largest_misfit},
                         {"rms_misfit", p.rms_misfit},
                         {"column_fallbacks", p.column_fallbacks},
                         {"lifted_grains", p.forces.lifted_grains},
                         {"lateral_grains", p.forces.lateral_grains},
                         {"largest_lateral_load", p.forces.largest_lateral}};
  intended = std::move(p.intended);
  std::cout << "pre-load (" << scene.relax.model << "): " << p.forces.contacts.size()
            << " contacts, largest intended overlap " << g6(p.largest_relative) << " of the smaller radius ("
            << g6(p.largest_depth) << " m), grains moved by up to " << g6(p.largest_move)
            << " m, overlap misfit against the law rms " << g6(p.rms_misfit) << " m (largest " << g6(p.largest_misfit)
            << " of a radius), " << p.column_fallbacks << " grains sunk with their column; "
            << p.forces.lateral_grains << " grains with a lateral load left to friction (largest "
            << g6(p.forces.largest_lateral) << " of a grain's weight)\n";
  write_packing(out_dir, "preloaded", out);
  write_forces(out_dir, "preloaded", packing.grains, p.forces);
  return out;
}

RelaxPlan make_plan(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                    const std::string& engine, const IntendedOverlaps* intended) {
  check_inputs(packing, scene);
  RelaxPlan plan;
  const StableStep stable = stable_timestep(packing.grains, scene,
                                            engine == "yade" ? DampedMode::TangentialSameDashpot : DampedMode::Normal);
  plan.stable_timestep = stable.step;
  const std::optional<double> requested = settings.timestep ? settings.timestep : scene.relax.timestep;
  if (settings.forced_timestep) {
    const double forced = *settings.forced_timestep;
    if (!(forced > 0.0)) throw RelaxRefused("forced time step must be positive, got " + g6(forced));
    plan.timestep = forced;
    plan.timestep_forced = true;
    plan.timestep_rule = "FORCED " + g6(forced) + " s = " + g6(forced / stable.step) +
                         " x the stable step, not checked (stability study only; stable: " + stable.rule + ")";
  } else if (requested) {
    if (!(*requested > 0.0)) throw RelaxRefused("requested time step must be positive, got " + g6(*requested));
    if (*requested > stable.step)
      throw RelaxRefused("requested time step " + g6(*requested) + " s is above the stable step " + g6(stable.step) +
                         " s; use at most " + g6(stable.step) + " s (" + stable.rule + ")");
    plan.timestep = *requested;
    plan.timestep_rule = "requested " + g6(*requested) + " s (stable: " + stable.rule + ")";
  } else {
    plan.timestep = stable.step;
    plan.timestep_rule = stable.rule;
  }
  if (!(settings.max_overlap >= 0.0)) throw RelaxRefused("max_overlap must be >= 0, got " + g6(settings.max_overlap));
  const OverlapReport overlap = intended ? largest_overlap(packing.grains, scene.dimension, scene.container, *intended)
                                         : largest_overlap(packing.grains, scene.dimension, scene.container);
  if (overlap.largest > settings.max_overlap)
    throw RelaxRefused("packing refused: its largest overlap, " + overlap.describe() + ", exceeds the limit " +
                       g6(settings.max_overlap) + " (" + std::to_string(overlap.count) +
                       " overlapping contacts in all); " +
                       (intended ? "a pre-loaded packing may overlap only as its contact forces require"
                                 : "BTR contacts touch exactly, so this packing was changed or is not a BTR packing"));
  plan.largest_overlap = overlap.largest;
  if (intended) {
    double deepest = 0.0;
    for (const auto& [key, depth] : *intended) deepest = std::max(deepest, depth);
    plan.arming_time = preload_arming_time(deepest, plan.timestep);
  }
  plan.max_time = scene.relax.max_time;
  plan.kinetic_threshold = kinetic_threshold(packing.grains, scene);
  plan.stop_rule = scene.relax.stop_rule;
  plan.unbalanced_threshold = scene.relax.stop_unbalanced_force;
  double r_min = std::numeric_limits<double>::infinity(), r_max = 0.0;
  for (const Grain& g : packing.grains) r_min = std::min(r_min, g.r), r_max = std::max(r_max, g.r);
  plan.displacement_threshold = scene.relax.stop_displacement * 2.0 * r_min;
  const double damping = settings.damping ? *settings.damping : scene.relax.damping;
  if (!(damping >= 0.0 && damping < 1.0)) throw RelaxRefused("damping must be in [0, 1), got " + g6(damping));
  plan.damping = damping;
  plan.compaction = plan_compaction(packing, scene, settings, plan.timestep, plan.kinetic_threshold);
  if (plan.compaction.enabled && engine == "yade" && uses_rolling_friction(scene))
    throw RelaxRefused("target packing fraction: YADE's Hertz-Mindlin moment law takes its rolling friction once, for "
                       "every contact, and the compaction cannot scale it with the sliding friction; relax with "
                       "LIGGGHTS, or without rolling friction");
  if (scene.container.kind == ContainerKind::Open) {
    plan.has_region = true;
    const FloorRegion region = open_floor_region(packing.grains, scene.dimension, scene.relax.open_margin * 2.0 * r_max,
                                                 scene.relax.open_heap_angle);
    for (int a = 0; a < 2; ++a) plan.region_lo[a] = region.lo[a], plan.region_hi[a] = region.hi[a];
  }
  return plan;
}

std::vector<std::string> write_engine_inputs(const Packing& packing, const Scene& scene, const EngineAdapter& adapter,
                                             const RelaxSettings& settings, const RelaxPlan& plan,
                                             const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the output folder: " + ec.message());
  std::cout << "time step " << g6(plan.timestep) << " s: " << plan.timestep_rule << "\n"
            << "stable time step " << g6(plan.stable_timestep) << " s" << (plan.timestep_forced ? " (step FORCED)" : "")
            << "\n"
            << "largest initial overlap: " << g6(plan.largest_overlap) << " of the smaller radius\n"
            << "stop rule: " << plan.stop_rule << " (threshold "
            << g6(stop_threshold(plan))
            << (plan.stop_rule == "kinetic-energy" ? " J" : plan.stop_rule == "displacement" ? " m per check window" : "")
            << "), or max_time " << g6(plan.max_time) << " s"
            << (plan.damping > 0 ? "; damping " + g6(plan.damping) : std::string()) << "\n";
  if (plan.compaction.enabled) {
    std::cout << "compaction to bulk phi " << g6(plan.compaction.target) << " (from " << g6(plan.compaction.initial_phi)
              << "): friction x";
    for (double f : plan.compaction.friction_scales) std::cout << " " << g6(f);
    std::cout << ", damping " << g6(plan.compaction.damping) << ", time step " << g6(plan.compaction.timestep)
              << " s, window z in ["
              << g6(plan.compaction.window_lo.z()) << ", " << g6(plan.compaction.window_hi.z()) << "] m, every "
              << plan.compaction.steps_per_check << " steps"
              << (plan.compaction.slabs.empty() ? std::string()
                                                : ", in " + std::to_string(plan.compaction.slabs.size()) +
                                                      " slabs from the floor up (their windows tile it)")
              << "\n";
  }
  if (plan.has_region)
    std::cout << "open floor: grains leaving x in [" << g6(plan.region_lo[0]) << ", " << g6(plan.region_hi[0]) << "]"
              << (scene.dimension == 3 ? ", y in [" + g6(plan.region_lo[1]) + ", " + g6(plan.region_hi[1]) + "]" : "")
              << " m are removed\n";
  return adapter.write_inputs(packing, scene, settings, plan, dir);
}

RelaxResult run_and_read_back(const Packing& packing, const Scene& scene, const EngineAdapter& adapter,
                              const std::string& engine, const RelaxSettings& settings, const RelaxPlan& plan,
                              const std::string& dir, const std::string& what) {
  const std::string log = adapter.log_file(dir);
  const std::string console = (fs::path(dir) / kConsoleFile).string();
  std::error_code ec;
  fs::remove(log, ec);  // a stale log must not pass for this run's
  fs::remove(console, ec);
  clear_failure_record(dir);  // nor an earlier run's failure record

  // Every failure of the run comes through here: its record is written (relax_failure.json: kind, engine,
  // why, the check's numbers) and the message gets the last lines of the engine's log and console.
  auto failure = [&](FailureKind kind, const std::string& why,
                     const nlohmann::json& values = nlohmann::json::object()) -> EngineFailure {
    std::string msg = engine + " " + what + " failed in " + dir + ": " + why;
    const nlohmann::json record = {{"kind", failure_kind_name(kind)},
                                   {"engine", engine},
                                   {"message", why},
                                   {"values", values.is_object() ? values : nlohmann::json::object()},
                                   {"log", fs::path(log).filename().string()}};
    try {
      write_text_file((fs::path(dir) / kRelaxFailureFile).string(), record.dump(1) + "\n");
    } catch (const std::exception& e) {
      msg += "\n(the failure record could not be written: " + std::string(e.what()) + ")";
    }
    const std::string log_tail = tail_lines(log, kLogTailLines);
    msg += "\n--- last lines of " + log + " ---\n" + (log_tail.empty() ? "(no log)\n" : log_tail);
    const std::string console_tail = tail_lines(console, 10);
    if (!console_tail.empty()) msg += "--- last lines of " + console + " ---\n" + console_tail;
    return EngineFailure(kind, msg, values);
  };

  const EngineCommand cmd = adapter.command(dir, settings);
  const ProcessOutcome outcome = run_process(cmd, dir, settings.wall_time_limit, console);
  if (outcome.stopped_by != 0)
    throw Interrupted(outcome.stopped_by, "interrupted by " + signal_name(outcome.stopped_by) + ": the " + engine +
                                              " run in " + dir + " and every process it started were stopped");
  if (!outcome.ok()) {
    nlohmann::json values = {{"wall_seconds", outcome.wall_seconds}};
    if (outcome.timed_out) {
      values["time_limit"] = settings.wall_time_limit;
      throw failure(FailureKind::TimeLimit, outcome.describe(), values);
    }
    if (outcome.signal != 0) values["signal"] = outcome.signal;
    else if (outcome.started) values["exit_status"] = outcome.exit_code;
    // The engine's own outputs may say what ended it (LIGGGHTS' ERROR line, YADE's status file).
    std::optional<EngineFailure> reported;
    if (outcome.started) {
      try {
        reported = adapter.failure_after_exit(dir, packing, scene, plan);
      } catch (const std::exception&) {
        reported.reset();  // outputs too broken to say more: the exit status is the failure
      }
    }
    if (!reported) throw failure(FailureKind::EngineError, outcome.describe(), values);
    values.update(reported->values());
    throw failure(reported->kind(), outcome.describe() + ": " + reported->what(), values);
  }

  RelaxResult res;
  try {
    res = adapter.read_back(dir, packing, scene, plan);
  } catch (const EngineFailure& e) {
    throw failure(e.kind(), e.what(), e.values());
  }
  res.wall_seconds = outcome.wall_seconds;
  res.cpu_seconds = outcome.cpu_seconds;

  // Checks every engine's result gets.
  const Grains& in = packing.grains;
  Grains& out = res.relaxed.grains;
  if (out.size() != in.size())
    throw failure(FailureKind::LostGrains,
                  "lost grains: " + std::to_string(out.size()) + " of " + std::to_string(in.size()) + " came back",
                  {{"grains", in.size()}, {"returned", out.size()}});
  std::vector<char> kept(in.size(), 1);
  if (!res.removed.empty() && !plan.has_region)
    throw failure(FailureKind::LostGrains,
                  "lost grains: " + std::to_string(res.removed.size()) + " of " + std::to_string(in.size()) +
                      " did not come back (only an open container removes grains)",
                  {{"grains", in.size()}, {"lost", res.removed.size()}});
  for (std::int64_t id : res.removed) {
    if (id < 1 || id > static_cast<std::int64_t>(in.size()) || !kept[id - 1])
      throw failure(FailureKind::BadOutput, "removed grain id " + std::to_string(id) + " is unknown or repeated",
                    {{"grain", id}});
    kept[id - 1] = 0;
  }
  if (res.removed.size() == in.size())
    throw failure(FailureKind::LostGrains, "every grain left the region: nothing to relax",
                  {{"grains", in.size()}, {"removed", res.removed.size()}});
  const Container& c = scene.container;
  const std::vector<DemWall> walls = dem_walls(c, scene.dimension);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!kept[i]) continue;
    Grain& g = out[i];
    const std::string who = "grain " + std::to_string(i + 1);
    if (!g.x.allFinite())
      throw failure(FailureKind::NonFinite, who + " has a non-finite position", {{"grain", i + 1}});
    if (g.r != in[i].r || g.species != in[i].species)
      throw failure(FailureKind::BadOutput, who + " came back with another radius or species", {{"grain", i + 1}});
    if (scene.dimension == 2 && std::abs(g.x.y()) > 1e-9 * g.r)
      throw failure(FailureKind::OutsideContainer, who + " left the plane y = 0 (y = " + g6(g.x.y()) + " m)",
                    {{"grain", i + 1}, {"y", g.x.y()}});
    g.x = wrap_into_cell(c, scene.dimension, g.x);
    for (const DemWall& w : walls)
      if (w.distance(g.x) < 0.0)
        throw failure(FailureKind::OutsideContainer,
                      who + " is outside the container: its centre is beyond the " + w.name + " wall by " +
                          g6(-w.distance(g.x)) + " m",
                      {{"grain", i + 1}, {"wall", w.name}, {"beyond", -w.distance(g.x)}});
  }
  if (!res.velocities.empty()) {
    if (res.velocities.size() != in.size())
      throw failure(FailureKind::BadOutput,
                    "velocities of " + std::to_string(res.velocities.size()) + " grains came back, expected " +
                        std::to_string(in.size()));
    for (std::size_t i = 0; i < res.velocities.size(); ++i)
      if (kept[i] && !res.velocities[i].allFinite())
        throw failure(FailureKind::NonFinite, "grain " + std::to_string(i + 1) + " has a non-finite velocity",
                      {{"grain", i + 1}});
  }
  const double bound = kinetic_energy_bound(in, scene) + (plan.tap.enabled ? plan.tap.energy_input : 0.0);
  for (const auto& [t, e] : res.kinetic_history) {
    if (!std::isfinite(e))
      throw failure(FailureKind::NonFinite, "kinetic energy " + g6(e) + " J at t = " + g6(t) + " s",
                    {{"kinetic_energy", json_number(e)}, {"time", json_number(t)}, {"bound", bound}});
    if (e > bound)
      throw failure(FailureKind::BlowUp,
                    "kinetic energy grew to " + g6(e) + " J at t = " + g6(t) + " s, above the bound " + g6(bound) +
                        " J (twice the energy the packing holds): the run blew up",
                    {{"kinetic_energy", e}, {"time", json_number(t)}, {"bound", bound}});
  }
  if (res.stop_reason.empty()) throw failure(FailureKind::BadOutput, "the engine did not say why it stopped");

  // Removed grains leave the outputs: the others keep their order, renumbered 1..N-k.
  std::vector<std::int64_t> new_id(in.size() + 1, 0);
  {
    std::int64_t next = 0;
    for (std::size_t i = 0; i < in.size(); ++i)
      if (kept[i]) new_id[i + 1] = ++next;
  }
  std::vector<RelaxResult::Contact> kept_contacts;
  for (const auto& k : res.contacts) {
    if (!new_id[k.i] || (k.j != 0 && !new_id[k.j]))
      throw failure(FailureKind::BadOutput,
                    "a contact names grain " + std::to_string(!new_id[k.i] ? k.i : k.j) + ", which was removed");
    kept_contacts.push_back({new_id[k.i], k.j == 0 ? 0 : new_id[k.j], k.fn});
  }
  res.contacts = std::move(kept_contacts);
  std::sort(res.contacts.begin(), res.contacts.end(), [](const RelaxResult::Contact& a, const RelaxResult::Contact& b) {
    return a.i != b.i ? a.i < b.i : a.j < b.j;
  });
  Grains kept_grains;
  std::vector<Vec3> kept_velocities;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!kept[i]) continue;
    kept_grains.push_back(out[i]);
    if (!res.velocities.empty()) kept_velocities.push_back(res.velocities[i]);
  }
  out = std::move(kept_grains);
  res.velocities = std::move(kept_velocities);
  return res;
}

void write_run_tables(const RelaxResult& res, const std::string& dir) {
  std::string kin = "time,kinetic_energy\n";
  char row[128];
  for (const auto& [t, e] : res.kinetic_history) {
    std::snprintf(row, sizeof row, "%.17g,%.17g\n", t, e);
    kin += row;
  }
  write_text_file((fs::path(dir) / "kinetic.csv").string(), kin);
  std::string con = "id1,id2,normal_force\n";  // id2 = 0: a wall
  for (const auto& k : res.contacts) {
    std::snprintf(row, sizeof row, "%lld,%lld,%.17g\n", static_cast<long long>(k.i), static_cast<long long>(k.j),
                  k.fn);
    con += row;
  }
  write_text_file((fs::path(dir) / "contacts.csv").string(), con);
  const fs::path velocities = fs::path(dir) / "velocities.csv";
  std::error_code ec;
  if (res.velocities.empty()) {
    fs::remove(velocities, ec);  // an earlier run's file must not pass for this one's
  } else {
    std::string vel = "id,vx,vy,vz\n";
    for (std::size_t i = 0; i < res.velocities.size(); ++i) {
      const Vec3& v = res.velocities[i];
      std::snprintf(row, sizeof row, "%zu,%.17g,%.17g,%.17g\n", i + 1, v.x(), v.y(), v.z());
      vel += row;
    }
    write_text_file(velocities.string(), vel);
  }
}

RelaxResult run_engine_inputs(const Packing& packing, const Scene& scene, const EngineAdapter& adapter,
                              const std::string& engine, const RelaxSettings& settings, const RelaxPlan& plan,
                              const std::string& dir) {
  RelaxResult res = run_and_read_back(packing, scene, adapter, engine, settings, plan, dir, "relaxation");
  const Grains& in = packing.grains;
  Grains& out = res.relaxed.grains;
  const Container& c = scene.container;
  std::vector<char> kept(in.size(), 1);
  for (std::int64_t id : res.removed) kept[id - 1] = 0;

  // Outputs.
  PointData displacement{"displacement", {}};
  for (std::size_t i = 0, k = 0; i < in.size(); ++i) {
    if (!kept[i]) continue;
    Vec3 d = out[k++].x - in[i].x;
    for (int axis : {0, 1})
      if (const double period = period_along(c, scene.dimension, axis); period > 0.0)
        d[axis] = minimum_image(d[axis], period);
    displacement.values.push_back(d.norm());
  }
  const OverlapReport final_overlap = largest_overlap(out, scene.dimension, c);
  // The largest grain-floor overlap / that grain's radius (the floor's share of final_overlap, which
  // takes every wall and pair): the static overlap a grain's column load gives on the floor.
  double final_floor_overlap = 0.0;
  for_each_overlap(out, scene.dimension, c, [&](std::int64_t a, std::int64_t, double depth, const DemWall* w) {
    if (w && w->name == "floor") final_floor_overlap = std::max(final_floor_overlap, depth / out[a - 1].r);
  });
  // The adapter's metadata (the input's, plus anything engine-specific under "relax") is kept; the
  // common fields are set here, the same for every engine.
  nlohmann::json meta = res.relaxed.meta.is_object() ? res.relaxed.meta
                        : packing.meta.is_object()    ? packing.meta
                                                      : nlohmann::json::object();
  nlohmann::json info = nlohmann::json::object();
  const bool inherited = packing.meta.is_object() && packing.meta.contains("relax") && meta.contains("relax") &&
                         packing.meta["relax"] == meta["relax"];  // from relaxing this packing before
  if (meta.contains("relax") && meta["relax"].is_object() && !inherited) info = meta["relax"];
  info.update({
      {"engine", engine},
      {"model", scene.relax.model},
      {"np", settings.np},
      {"timestep", plan.timestep},
      {"timestep_rule", plan.timestep_rule},
      {"stable_timestep", plan.stable_timestep},
      {"timestep_forced", plan.timestep_forced},
      {"max_time", plan.max_time},
      {"kinetic_threshold", plan.kinetic_threshold},
      {"stop_reason", res.stop_reason},
      {"simulated_time", res.simulated_time},
      {"wall_seconds", res.wall_seconds},
      {"final_kinetic_energy", res.kinetic_history.empty() ? 0.0 : res.kinetic_history.back().second},
      {"initial_largest_overlap", plan.largest_overlap},
      {"final_largest_overlap", final_overlap.largest},
      {"final_largest_floor_overlap", final_floor_overlap},
      {"contacts", res.contacts.size()},
      {"stop_rule", plan.stop_rule},
      {"stop_threshold", stop_threshold(plan)},
      {"final_unbalanced_force", std::isfinite(res.final_unbalanced_force) ? nlohmann::json(res.final_unbalanced_force)
                                                                           : nlohmann::json(nullptr)},
      {"stop_value", std::isfinite(res.stop_value) ? nlohmann::json(res.stop_value) : nlohmann::json(nullptr)},
      {"damping", plan.damping},
  });
  if (plan.has_region) {
    info["removed"] = {{"count", res.removed.size()},
                       {"ids", res.removed},
                       {"region", {{"x", {plan.region_lo[0], plan.region_hi[0]}}, {"y", {plan.region_lo[1], plan.region_hi[1]}}}},
                       {"rule", "open floor: grains whose centre left the region (the packing's footprint grown by "
                                "relax.open_margin largest diameters, and at least the heap of its grains at "
                                "relax.open_heap_angle) were removed; ids are the input packing's"}};
  }
  meta["relax"] = info;
  if (plan.compaction.target > 0.0) {
    meta["target_phi"] = target_phi_record(plan.compaction, res, scene, settings.target_margin);
    const nlohmann::json& t = meta["target_phi"];
    std::cout << "target phi " << g6(plan.compaction.target) << ": "
              << (!plan.compaction.enabled ? "the packing already had it (bulk phi " + g6(plan.compaction.initial_phi) + ")"
                  : res.compaction.reached
                      ? "reached at t = " + g6(res.compaction.time) + " s with friction x " +
                            g6(res.compaction.friction_scale) + " (in-run phi " + g6(res.compaction.packing_fraction) + ")"
                      : "NOT reached: the bed came to rest at in-run phi " + g6(res.compaction.packing_fraction) +
                            " with friction x " + g6(res.compaction.friction_scale))
              << "; settled bulk phi "
              << (t["settled_bulk_packing_fraction"].is_number() ? g6(t["settled_bulk_packing_fraction"].get<double>())
                                                                 : std::string("(no bulk window)"))
              << "\n";
  } else {
    meta.erase("target_phi");  // the input's record (a packing relaxed before) describes another run
  }
  // The input's structural measures describe the input, not this packing; `btr relax` measures the
  // relaxed grains itself and stores them under the same key.
  meta.erase("measures");
  meta.erase("metrics");  // the key packings written before the measures had one home carried
  res.relaxed.meta = meta;
  write_packing(dir, "relaxed", res.relaxed, {displacement});

  write_run_tables(res, dir);
  return res;
}

// Rigid clusters (the cluster column) must stay rigid: YADE gets them as clumps, LIGGGHTS as rigid bodies
// (fix rigid molecule). The pre-loaded start has no rule for them, an open floor would remove single members
// of a clump, and LIGGGHTS' unbalanced force is summed per atom, not per rigid body.
void check_clusters_supported(const Packing& packing, const Scene& scene, const std::string& engine,
                              const RelaxSettings& settings) {
  const auto clustered = std::find_if(packing.grains.begin(), packing.grains.end(), [](const Grain& g) { return g.cluster != 0; });
  if (clustered == packing.grains.end()) return;
  const std::string which = "the packing has rigid clusters (grain " +
                            std::to_string(clustered - packing.grains.begin() + 1) + " is in cluster " +
                            std::to_string(clustered->cluster) + ")";
  if (engine == "liggghts" && scene.relax.stop_rule == "unbalanced-force")
    throw RelaxRefused(which + ": LIGGGHTS' unbalanced force is a mean over atoms, and a member of a rigid body at "
                       "rest still carries a resultant (the body's is zero); use the kinetic-energy or displacement "
                       "rule, or --engine yade");
  if (settings.preload || scene.relax.preload)
    throw RelaxRefused(which + ": the pre-loaded start has no force network for clusters (it splits each grain's "
                       "load on that grain's own supports); relax without --preload");
  if (scene.container.kind == ContainerKind::Open)
    throw RelaxRefused(which + ": an open floor removes grains one by one as they leave, which would break clumps; "
                       "relax them in a container with walls");
}

}  // namespace btr
