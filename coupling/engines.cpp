#include "coupling/engines.h"

#include "coupling/dem/relax_plan.h"

namespace btr {

std::unique_ptr<EngineAdapter> make_adapter(const std::string& engine) {
  if (engine == "liggghts") return make_liggghts_adapter();
  if (engine == "yade") return make_yade_adapter();
  throw RelaxRefused("engine: expected \"liggghts\" or \"yade\", got \"" + engine + "\"");
}

std::vector<std::string> export_inputs(const Packing& packing, const Scene& scene, const std::string& engine,
                                       const RelaxSettings& settings, const std::string& dir) {
  check_clusters_supported(packing, scene, engine, settings);
  const auto adapter = make_adapter(engine);
  IntendedOverlaps intended;
  const Packing start = starting_packing(packing, scene, settings, intended, dir);
  const RelaxPlan plan = make_plan(start, scene, settings, engine, intended.empty() ? nullptr : &intended);
  return write_engine_inputs(start, scene, *adapter, settings, plan, dir);
}

RelaxResult relax(const Packing& packing, const Scene& scene, const std::string& engine,
                  const RelaxSettings& settings, const std::string& out_dir) {
  clear_failure_record(out_dir);  // also when this run is refused before the engine starts
  check_clusters_supported(packing, scene, engine, settings);
  const auto adapter = make_adapter(engine);
  IntendedOverlaps intended;
  const Packing start = starting_packing(packing, scene, settings, intended, out_dir);
  const RelaxPlan plan = make_plan(start, scene, settings, engine, intended.empty() ? nullptr : &intended);
  write_engine_inputs(start, scene, *adapter, settings, plan, out_dir);
  return run_engine_inputs(start, scene, *adapter, engine, settings, plan, out_dir);
}

PourResult pour(const Grains& grains, const Scene& scene, const std::string& engine, const PourSettings& settings,
                const std::string& out_dir, const nlohmann::json& meta, const Grains* footprint) {
  check_pour_grains(grains, scene);
  const auto adapter = make_adapter(engine);
  const Scene run_scene = pour_scene(scene, settings);
  const PourLattice lattice = pour_lattice(grains, run_scene, settings.seed, settings.max_batches,
                                           pour_drop_gap(grains, settings));
  const RelaxPlan plan = make_pour_plan(lattice, run_scene, settings, engine, footprint);
  write_pour_inputs(lattice, run_scene, *adapter, settings, plan, out_dir);
  return run_pour_inputs(lattice, run_scene, *adapter, engine, settings, plan, out_dir, meta);
}

}  // namespace btr
