#pragma once
// DEM relaxation of a packing in LIGGGHTS or YADE (docs/design.md section 4): write the inputs, run the
// engine, detect failure, read the relaxed packing back.
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "btr/scene/scene.h"
#include "coupling/io/packing_io.h"

namespace btr {

struct RelaxSettings {
  int np = 1;                       // LIGGGHTS: MPI ranks; YADE: threads
  double wall_time_limit = 3600.0;  // s; the engine is killed past this
  std::optional<double> timestep;   // overrides the computed stable step (refused if above it)
  // Study only (`btr relax --force-timestep`, hidden): this step is used even above the stable one,
  // never refused; the run records that it was forced. Never set on the default path.
  std::optional<double> forced_timestep;
  double max_overlap = 0.05;        // refuse packings whose largest overlap / smaller radius exceeds this
                                    // (with a pre-load: the overlap beyond the intended one)
  bool preload = false;             // pre-loaded start (preload.h); also on when the scene sets relax.preload
  std::optional<double> damping;    // overrides the scene's relax.damping
  std::optional<double> target_phi; // overrides the scene's relax.target_phi (relax_target.h)
  std::optional<std::vector<double>> friction_scales;  // overrides relax.friction_scales
  std::optional<double> compaction_damping;            // overrides relax.compaction_damping
  std::optional<double> compaction_timestep_fraction;  // overrides relax.compaction_timestep_fraction
  double target_margin = 3.0;       // bulk window of the target: largest diameters from floor, walls, surface
  // Compact the bed in this many slabs of equal grain counts, from the floor up (CompactionPlan::slabs); the
  // packing must be a BTR deposit in drop order. 1: the whole bed at once.
  int compaction_slabs = 1;
};

// What an engine run produced.
struct RelaxResult {
  Packing relaxed;                  // same ids; meta records engine, stop reason, timings
  std::string stop_reason;          // the rule that fired: "kinetic-energy", "unbalanced-force", "displacement"
                                    // or "max-time"
  double simulated_time = 0.0;      // s
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;         // processor time (user + system) of the engine and what it started
  std::vector<std::pair<double, double>> kinetic_history;  // (time, kinetic energy)
  std::vector<Vec3> velocities;     // final translational velocity of each grain, same order as relaxed.grains
  struct Contact { std::int64_t i, j; double fn; };       // j == 0 for a wall
  std::vector<Contact> contacts;
  // Open containers: grains removed because they left the region (ids of the input packing, 1-based, in
  // order). relaxed.grains then holds the others, in input order, renumbered 1..N-k; contacts use those ids.
  std::vector<std::int64_t> removed;
  // Reported by the engine at the end of the run (NaN if it did not): the unbalanced-force ratio.
  double final_unbalanced_force = std::numeric_limits<double>::quiet_NaN();
  // The stop rule's measure at the check that fired it (J, ratio or m; NaN for max-time).
  double stop_value = std::numeric_limits<double>::quiet_NaN();
  // The compaction to a target packing fraction, when the plan had one (engine_adapter.h, CompactionPlan).
  struct Compaction {
    bool ran = false;
    bool reached = false;          // the in-run packing fraction reached the target
    double friction_scale = 0.0;   // the scale in force when it ended
    double time = 0.0;             // s, when the friction was restored
    double packing_fraction = 0.0; // the engine's in-run bulk packing fraction then (exact cut volumes)
    struct Slab {                  // a slab-by-slab compaction (CompactionPlan::slabs): each slab's end
      bool reached = false;
      double time = 0.0, packing_fraction = 0.0;
    };
    std::vector<Slab> slabs;
  } compaction;
};

// What went wrong in a failed engine run, decided where the failure is detected (the process runner, the
// engine's read-back, relax.cpp's checks). Each has a stable name (failure_kind_name), the "kind" of
// OUTDIR/relax_failure.json (docs/faults.md, "Engine failures").
enum class FailureKind {
  EngineError,       // "engine_error": could not start, exited non-zero or by a signal, or logged an error
  TimeLimit,         // "time_limit": killed at the wall-time limit (--time-limit)
  BlowUp,            // "blow_up": kinetic energy above twice the energy the packing holds
  NonFinite,         // "non_finite": NaN or infinity in positions, velocities, energies or thermo output
  LostGrains,        // "lost_grains": grains missing from the result (lost atoms or bodies)
  OutsideContainer,  // "outside_container": a centre beyond a wall or below the floor, a 2D grain off y = 0
  MissedContact,     // "missed_contact": two grains sunk into each other (a contact the engine missed)
  BadOutput,         // "bad_output": an output missing, truncated, malformed or contradicting the run
};

// "engine_error", "time_limit", "blow_up", "non_finite", "lost_grains", "outside_container",
// "missed_contact", "bad_output".
const char* failure_kind_name(FailureKind kind);
// The kind of one of those names; std::nullopt for any other string.
std::optional<FailureKind> failure_kind_from_name(const std::string& name);

// An engine that failed (non-zero exit, lost atoms, NaN, blow-up, grains outside the container): the
// kind, the message (why, and from relax.cpp the last lines of the engine's log) and the numbers the
// check had (e.g. {"kinetic_energy", "bound", "time"} of a blow-up), as relax_failure.json records them.
class EngineFailure : public std::runtime_error {
 public:
  EngineFailure(FailureKind kind, const std::string& what, nlohmann::json values = nlohmann::json::object())
      : std::runtime_error(what), kind_(kind), values_(std::move(values)) {}
  FailureKind kind() const { return kind_; }
  const nlohmann::json& values() const { return values_; }

 private:
  FailureKind kind_;
  nlohmann::json values_;
};

// The failure record of the last `btr relax` into a folder: written (atomically) when the run fails with
// an EngineFailure, removed when a run starts, so it never describes an earlier run (relax.cpp).
constexpr const char* kRelaxFailureFile = "relax_failure.json";

}  // namespace btr
