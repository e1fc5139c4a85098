#pragma once
// `btr shake --engine liggghts|yade`: the DEM counterpart of dynamic BTR by shaking (docs/guide/shake_dem.md).
#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>

#include "btr/scene/scene.h"
#include "coupling/dem/tapping.h"
#include "scene_run_options.h"

namespace btr_app {

struct ShakeOptions : SceneRunOptions {
  std::string engine;
  std::int64_t cycles = 0, taps = 0;
  int np = 1;
  double time_limit = 3600.0;
  double rest_time = btr::kDefaultTapRestTime;  // s
};

// Builds the scene's BTR packing (seed `seed`), relaxes it at rest in OUT/relax/, taps it in OUT/tap/ and writes
// the snapshots, NAME.pvd, NAME_cycles.csv and shake_dem.json into OUT. Throws SceneError, RelaxRefused,
// EngineFailure or Interrupted (run_engine_command maps them to exit codes).
int run_shake_dem(const ShakeOptions& o, const CLI::App& cmd, const btr::Scene& scene, std::uint64_t seed);

}  // namespace btr_app
