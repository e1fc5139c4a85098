#pragma once
// A rotating drum in a DEM engine (`btr drum --engine`), engine-independent part: the drum's speed from the
// scene, the snapshot schedule (the angles `btr drum` writes at), the run (the relaxation's inputs plus a
// DrumRotation, engine_adapter.h) and the snapshots read back and checked. The engines' own parts are in their
// writers (liggghts_script.cpp, yade_library.py `rotate`).
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/relax.h"

namespace btr {

// The default speed when the scene gives neither [drum].rpm nor [drum].froude: the Froude number omega^2 R / g.
// The rolling regime spans about 1e-4 < Fr < 1e-2 (Mellmann 2001); a revolution's simulated time goes as
// Fr^-1/2, so the upper part of the regime is the cheapest to simulate, and 5e-3 keeps a factor 2 from the
// rolling-cascading transition near 1e-2 (docs/guide/drum_dem.md).
inline constexpr double kDefaultDrumFroude = 5e-3;

struct DrumSpeed {
  double omega = 0.0;   // rad/s
  double rpm = 0.0;     // revolutions per minute
  double froude = 0.0;  // omega^2 R / g
  std::string source;   // "drum.rpm", "drum.froude" or "default"
};

// The scene's speed. Throws RelaxRefused naming the scene file and the field for a speed at or above the
// centrifuging one (Froude >= 1) or a scene that is not a drum.
DrumSpeed drum_speed(const Scene& scene);

// The BTR steps `btr drum` writes snapshots at for `revolutions` (> 0): every snapshot_every steps and the last,
// S = round(revolutions * steps_per_revolution) (at least 1); step 0 excluded. Angle of step s: 360 s / spr deg.
std::vector<std::int64_t> drum_snapshot_steps(const DrumSpec& drum, double revolutions);

struct DrumSnapshot {
  std::int64_t step = 0;    // BTR step whose angle it has
  double angle_deg = 0.0;   // 360 step / steps_per_revolution
  long engine_steps = 0;    // engine time steps from the rotation's start
  double time = 0.0;        // s of rotation (engine_steps x time step)
  Grains grains;            // same order and ids as the starting packing
};

struct DrumRotationResult {
  DrumSpeed speed;
  RelaxPlan plan;
  RelaxResult run;                      // the engine run (final state, kinetic history, costs)
  std::vector<DrumSnapshot> snapshots;  // in order; the last one ends the run
};

// Rotates the drum holding `start` (a packing at rest in it, e.g. relaxed) for `revolutions` in `engine`: writes
// the inputs into dir, runs them, reads and checks every snapshot (ids kept, finite, inside the exact drum, 2D
// grains in y = 0). Throws RelaxRefused (scene, settings), EngineFailure or Interrupted.
DrumRotationResult rotate_drum(const Packing& start, const Scene& scene, const EngineAdapter& adapter,
                               const std::string& engine, const RelaxSettings& settings, double revolutions,
                               const std::string& dir);

// drum_dem.json's record of a rotation: engine, speed (rpm, froude, omega, source), time step and its rule,
// simulated time, engine processor and wall seconds in all and per revolution, np, snapshot schedule.
nlohmann::json drum_rotation_record(const DrumRotationResult& r, const Scene& scene, const std::string& engine,
                                    const RelaxSettings& settings, double revolutions);

}  // namespace btr
