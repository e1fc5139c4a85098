#pragma once
// `btr drum --engine liggghts|yade`: the DEM rotating drum (docs/guide/drum_dem.md). The same BTR fill as the
// dynamic BTR run, relaxed in the still drum (btr::relax, OUTDIR/relax/), then rotated by the engine
// (btr::rotate_drum, OUTDIR/rotation/); the snapshots and the steps table are written as `btr drum` writes them.
#include <cstdint>
#include <string>

#include "btr/scene/scene.h"

namespace btr_app {

struct DrumDemOptions {
  std::string engine;          // "liggghts" | "yade"
  std::string out, name;
  std::uint64_t seed = 0;
  int np = 1;
  double time_limit = 3600.0;  // s, wall time of each engine run
  double revolutions = 0.0;    // > 0
  double settle_max_time = 0;  // s; 0 = the scene's relax.max_time
  bool quiet = false;
};

// Writes OUTDIR/NAME_sNNNNNN.{csv,json,vtp}, NAME.pvd, NAME_steps.csv and drum_dem.json; returns the exit code.
// Throws what btr::relax and btr::rotate_drum throw (run_engine_command maps it to the exit code).
int run_drum_dem(btr::Scene scene, const DrumDemOptions& o);

}  // namespace btr_app
