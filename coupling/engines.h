#pragma once
// The engines the coupling drives, chosen by name: one adapter per engine (coupling/liggghts/,
// coupling/yade/), and the two entry points that pick one. The only coupling code that sees every engine.
#include <memory>
#include <string>
#include <vector>

#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/pour.h"
#include "coupling/dem/relax.h"

namespace btr {

// "liggghts" or "yade"; throws RelaxRefused for anything else.
std::unique_ptr<EngineAdapter> make_adapter(const std::string& engine);

// Write-only: the input files for `engine` ("liggghts" | "yade") into dir; returns their paths.
std::vector<std::string> export_inputs(const Packing& packing, const Scene& scene, const std::string& engine,
                                       const RelaxSettings& settings, const std::string& dir);

// Writes the inputs into out_dir, runs the engine there, and reads the result back. An EngineFailure
// leaves out_dir/relax_failure.json (relax_plan.h, run_engine_inputs); any other end of the run leaves none.
RelaxResult relax(const Packing& packing, const Scene& scene, const std::string& engine,
                  const RelaxSettings& settings, const std::string& out_dir);

// The reference pour of `grains` (their radii, species and order; positions unused) in `engine`: lattice, plan,
// inputs, run and checks into out_dir (pour.h). `meta` starts poured.json; `footprint`, when given, also bounds
// an open floor's region (the grains' earlier packing). Throws RelaxRefused, EngineFailure or Interrupted.
PourResult pour(const Grains& grains, const Scene& scene, const std::string& engine, const PourSettings& settings,
                const std::string& out_dir, const nlohmann::json& meta, const Grains* footprint = nullptr);

}  // namespace btr
