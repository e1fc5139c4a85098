// The reference DEM pour, engine-independent part (pour.h): the lattice's inputs, the run, the record.
#include "coupling/dem/pour.h"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "btr/model/number_text.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/relax_plan.h"

namespace btr {

namespace fs = std::filesystem;

void check_pour_grains(const Grains& grains, const Scene& scene) {
  if (grains.empty()) throw RelaxRefused("pour: no grains to pour");
  for (std::size_t i = 0; i < grains.size(); ++i) {
    if (grains[i].cluster != 0)
      throw RelaxRefused("pour: grain " + std::to_string(i + 1) + " is in rigid cluster " +
                         std::to_string(grains[i].cluster) + "; the pour releases single grains, not rigid clusters");
    if (!(grains[i].r > 0.0) || !std::isfinite(grains[i].r))
      throw RelaxRefused("pour: grain " + std::to_string(i + 1) + " has radius " + g6(grains[i].r) +
                         "; expected a positive number");
  }
  if (scene.clusters) refuse_scene_field(scene, "[clusters]", "the pour releases single grains, not rigid clusters");
}

std::vector<std::string> write_pour_inputs(const PourLattice& lattice, const Scene& pour, const EngineAdapter& adapter,
                                           const PourSettings& settings, const RelaxPlan& plan, const std::string& dir) {
  Packing start;
  start.grains = lattice.grains;
  std::cout << "pour: " << lattice.grains.size() << " grains on a lattice of " << lattice.sites_per_layer
            << " sites x " << lattice.layers << " layers (" << g6(lattice.spacing) << " m apart), "
            << plan.pour.batches.size() << " batches of " << lattice.layers_per_batch << " layer(s), pace "
            << g6(settings.pace) << ", drop gap " << g6(plan.pour.drop_gap) << " m; release "
            << g6(plan.pour.release_time) << " s, then settling <= " << g6(plan.max_time) << " s\n";
  RelaxSettings rs;
  rs.np = settings.np;
  rs.wall_time_limit = settings.wall_time_limit;
  return write_engine_inputs(start, pour, adapter, rs, plan, dir);
}

namespace {

nlohmann::json pour_record(const PourLattice& lattice, const Scene& pour, const std::string& engine,
                           const PourSettings& settings, const RelaxPlan& plan, const RelaxResult& run) {
  std::vector<long> steps;
  for (const PourRelease::Batch& b : plan.pour.batches) steps.push_back(b.steps);
  nlohmann::json r = {
      {"engine", engine},
      {"model", pour.relax.model},
      {"np", settings.np},
      {"grains", lattice.grains.size()},
      {"settings",
       {{"seed", settings.seed},
        {"pace", settings.pace},
        {"drop_gap", settings.drop_gap},
        {"max_batches", settings.max_batches},
        {"stop_ratio", pour.relax.stop_kinetic_ratio},
        {"settle_max_time", pour.relax.max_time},
        {"timestep_fraction", pour.relax.timestep_fraction},
        {"check_interval", settings.check_interval},
        {"wall_time_limit", settings.wall_time_limit}}},
      {"lattice",
       {{"sites_per_layer", lattice.sites_per_layer},
        {"layers", lattice.layers},
        {"layers_per_batch", lattice.layers_per_batch},
        {"spacing", lattice.spacing},
        {"hold_base", lattice.hold_base}}},
      {"batches", plan.pour.batches.size()},
      {"batch_steps", steps},
      {"drop_gap_m", plan.pour.drop_gap},
      {"release_time", plan.pour.release_time},
      {"timestep", plan.timestep},
      {"timestep_rule", plan.timestep_rule},
      {"stable_timestep", plan.stable_timestep},
      {"stop_rule", plan.stop_rule},
      {"kinetic_threshold", plan.kinetic_threshold},
      {"stop_reason", run.stop_reason},
      {"stop_value", std::isfinite(run.stop_value) ? nlohmann::json(run.stop_value) : nlohmann::json(nullptr)},
      {"simulated_time", run.simulated_time},
      {"final_kinetic_energy", run.kinetic_history.empty() ? 0.0 : run.kinetic_history.back().second},
      {"wall_seconds", run.wall_seconds},
      {"engine_cpu_seconds", run.cpu_seconds},
      {"contacts", run.contacts.size()},
      {"final_largest_overlap", largest_overlap(run.relaxed.grains, pour.dimension, pour.container).largest},
  };
  if (plan.has_region)
    r["removed"] = {{"count", run.removed.size()},
                    {"ids", run.removed},
                    {"region", {{"x", {plan.region_lo[0], plan.region_hi[0]}}, {"y", {plan.region_lo[1], plan.region_hi[1]}}}},
                    {"rule", "open floor: grains whose centre left the region (the lattice's footprint, and the "
                             "poured packing's, grown by relax.open_margin largest diameters, and at least the heap "
                             "of the grains at relax.open_heap_angle) were removed; ids are the input's, the others "
                             "are renumbered"}};
  return r;
}

}  // namespace

PourResult run_pour_inputs(const PourLattice& lattice, const Scene& pour, const EngineAdapter& adapter,
                           const std::string& engine, const PourSettings& settings, const RelaxPlan& plan,
                           const std::string& dir, const nlohmann::json& meta) {
  Packing start;
  start.grains = lattice.grains;
  RelaxSettings rs;
  rs.np = settings.np;
  rs.wall_time_limit = settings.wall_time_limit;
  PourResult out;
  out.run = run_and_read_back(start, pour, adapter, engine, rs, plan, dir, "pour");
  out.record = pour_record(lattice, pour, engine, settings, plan, out.run);
  out.poured.grains = out.run.relaxed.grains;
  out.poured.meta = meta.is_object() ? meta : nlohmann::json::object();
  out.poured.meta["count"] = out.poured.grains.size();
  out.poured.meta["pour"] = out.record;
  write_packing(dir, "poured", out.poured);
  write_run_tables(out.run, dir);
  return out;
}

}  // namespace btr
