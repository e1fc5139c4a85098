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

}  // namespace btr
