#pragma once
// What relax.cpp needs from each engine: write its inputs, say how to run them, read the result back.
// One implementation per engine: liggghts_adapter.cpp, yade_adapter.cpp.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "coupling/dem/relax.h"
#include "coupling/dem/tap_schedule.h"

namespace btr {

// In-run compaction to a target bulk packing fraction (btr relax --target-phi; relax_target.h), run before
// the stop rule: friction scaled by friction_scales[k] (k = 0 first; the next one once the bed is at rest,
// kinetic energy and its mean below rest_kinetic, still below the target), damping `damping`, the packing
// fraction of the window checked every steps_per_check steps (each grain's exact part between the window's
// planes, for the grains whose centre lies in its lateral bounds); at the target (or when
// the last scale is at rest) the scene's friction is restored, every grain is stopped (velocities and spins
// zeroed), the plan's damping replaces `damping`, and the stop rule runs as without compaction, armed anew.
struct CompactionPlan {
  bool enabled = false;
  double target = 0.0;                  // bulk packing fraction (area fraction in 2D)
  std::vector<double> friction_scales;  // decreasing, in [0, 1)
  double damping = 0.0;                 // during the compaction, as RelaxPlan::damping
  double timestep = 0.0;                // s, during the compaction (the settle uses RelaxPlan::timestep)
  double timestep_fraction = 0.0;       // of the Rayleigh / contact time, as relax.timestep_fraction
  bool slab = false;                    // the window spans the periodic footprint (lo/hi x, y unused)
  Vec3 window_lo = Vec3::Zero(), window_hi = Vec3::Zero();  // 2D: x and z used
  double window_measure = 0.0;          // m^3 (3D) or m^2 (2D)
  double initial_phi = 0.0;             // of the starting packing, by btr measure's exact definition
  long steps_per_check = 0;
  long max_checks_per_scale = 0;        // each scale runs at most max_time
  double rest_kinetic = 0.0;            // J
  // Deep beds (settle): the bed compacted slab by slab from the floor up, as a pour builds it, instead of all at
  // once. Slab k is the grains slabs[k-1].last+1 .. slabs[k].last (0-based, packing order: a BTR deposit's drop
  // order, so the first slabs[k].last+1 grains are the BTR bed of that many drops). The grains above the slab
  // being compacted are held (not integrated: fixed obstacles, as a pour's held lattice); the slab is released
  // and frictionless (friction_scales[0]; the grains below it have their friction) until the packing fraction
  // of its window, [window_lo_z, window_hi_z] within the plan's lateral window bounds, reaches the target (or it
  // is at rest); then its friction is restored and the next slab released. After the last, as without slabs.
  // Empty: the whole bed at once in the plan's window.
  struct Slab {
    std::size_t last = 0;                // 0-based index of the slab's last grain
    double window_lo_z = 0.0, window_hi_z = 0.0;
    double window_measure = 0.0;         // m^3 (3D) or m^2 (2D)
  };
  std::vector<Slab> slabs;
};

// The release of a reference pour (pour.h), run before the stop rule: every grain starts held on a lattice
// (not integrated: a fixed obstacle), and batch k (grains first..last, consecutive ids) is moved down until
// its lowest centre is drop_gap + 2 r_max above the highest released centre (the first batch: drop_gap + r_max
// above the floor), joins the integrated grains and falls for steps[k] steps before the next. A batch that
// would have to move up (the pile reached the held lattice) ends the run as a failure. The stop rule runs
// once every batch is out: RelaxPlan::max_time counts from the end of the release, and RelaxPlan::arming_time
// (a time of the run, as in a relaxation) lies past it.
struct PourRelease {
  bool enabled = false;
  struct Batch {
    std::size_t first = 0, last = 0;  // 0-based indices into the grains, inclusive
    long steps = 0;                   // steps run after its release
  };
  std::vector<Batch> batches;
  double drop_gap = 0.0;       // m, between the lowest batch grain's surface and the pile's top surface
  double r_max = 0.0;          // m
  double release_time = 0.0;   // s, sum of the batches' steps times the time step
  long steps_per_check = 0;    // the settle's check window (check_schedule)
};

// The rotation of a drum (drum_rotation.h), run instead of the stop rule: the drum's mesh (drum_mesh.h) turns
// about the drum's axis (along y through x = 0, z = axis_z) at omega rad/s in the drum's sense (its lowest line
// towards +x, as DrumStepper: a rotation about -y), from the run's start; the grains' positions are written
// after each of snapshot_steps (cumulative step counts, increasing; the last one ends the run), snapshot k
// (1-based) to the engine's file k, read back by EngineAdapter::read_snapshot.
struct DrumRotation {
  bool enabled = false;
  double omega = 0.0;   // rad/s, > 0
  double axis_z = 0.0;  // m
  std::vector<long> snapshot_steps;
};

// The numbers every engine input is built from, computed once by relax.cpp.
struct RelaxPlan {
  double timestep = 0.0;        // s, already checked against the stable step
  std::string timestep_rule;    // one line, e.g. "Rayleigh time 1.2e-5 s x 0.2 (Hertz, smallest grain)"
  double stable_timestep = 0.0; // s, the rule's step (equal to timestep unless requested or forced)
  bool timestep_forced = false; // RelaxSettings::forced_timestep was used: the step was not checked
  double max_time = 0.0;        // simulated seconds
  double kinetic_threshold = 0.0;  // J: stop when the total kinetic energy falls below this
  double largest_overlap = 0.0;    // of the input packing, relative to the smaller radius
                                   // (pre-loaded: beyond the intended overlap)
  double arming_time = 0.0;        // s; 0: stop_arming_time(grains) (a pre-loaded start arms sooner)
  std::string stop_rule = "kinetic-energy";  // scene relax.stop_rule
  double unbalanced_threshold = 1e-3;        // unbalanced-force: stop below this ratio
  double displacement_threshold = 0.0;       // displacement: stop below this largest displacement per window [m]
  double damping = 0.0;                      // YADE's NewtonIntegrator damping; 0 = off
  // Open containers: grains whose centre leaves [lo, hi] laterally are removed and counted (lo/hi[1] unused
  // in 2D). Other containers: has_region is false.
  bool has_region = false;
  double region_lo[2] = {0.0, 0.0}, region_hi[2] = {0.0, 0.0};
  CompactionPlan compaction;  // enabled only with a target packing fraction
  PourRelease pour;           // enabled only for a reference pour (pour.h)
  TapSchedule tap;            // enabled only for DEM tapping (tapping.h); replaces the stop rule
  DrumRotation rotation;      // enabled only for a rotating drum (drum_rotation.h); replaces the stop rule
};

// The threshold of the plan's stop rule: J (kinetic-energy), a ratio (unbalanced-force) or m (displacement).
inline double stop_threshold(const RelaxPlan& plan) {
  if (plan.stop_rule == "kinetic-energy") return plan.kinetic_threshold;
  if (plan.stop_rule == "unbalanced-force") return plan.unbalanced_threshold;
  return plan.displacement_threshold;
}

struct EngineCommand {
  std::vector<std::string> argv;            // argv[0] is looked up on PATH
  std::map<std::string, std::string> env;   // added to the environment
};

class EngineAdapter {
 public:
  virtual ~EngineAdapter() = default;
  // Writes every input file into dir (which exists); returns their paths.
  virtual std::vector<std::string> write_inputs(const Packing& packing, const Scene& scene,
                                                const RelaxSettings& settings, const RelaxPlan& plan,
                                                const std::string& dir) const = 0;
  virtual EngineCommand command(const std::string& dir, const RelaxSettings& settings) const = 0;
  // The engine's own log file inside dir (kept; its tail goes into failure messages).
  virtual std::string log_file(const std::string& dir) const = 0;
  // Reads the outputs in dir; throws EngineFailure if they show a failed run.
  virtual RelaxResult read_back(const std::string& dir, const Packing& original, const Scene& scene,
                                const RelaxPlan& plan) const = 0;
  // A rotating drum's snapshot k (1-based, DrumRotation::snapshot_steps): original's grains at the positions the
  // engine wrote (same order and ids). Throws EngineFailure for a missing, truncated or non-finite file or
  // missing or repeated ids.
  // (An adapter that never runs a drum need not: this one refuses.)
  virtual Grains read_snapshot(const std::string& dir, std::size_t k, const Packing& original) const {
    (void)original;
    throw EngineFailure(FailureKind::BadOutput,
                        dir + ": this engine adapter reads no rotating-drum snapshots (snapshot " + std::to_string(k) + ")");
  }
  // After the engine exited non-zero or was ended by a signal: the failure its own outputs in dir report
  // (its log's error line, its status file), with the kind and numbers they give; std::nullopt if they
  // say nothing (relax.cpp then reports an engine_error with the exit status).
  virtual std::optional<EngineFailure> failure_after_exit(const std::string& dir, const Packing& original,
                                                          const Scene& scene, const RelaxPlan& plan) const {
    (void)dir, (void)original, (void)scene, (void)plan;
    return std::nullopt;
  }
  // Tapping (plan.tap): the grains and numbers after each tap of the run in dir, in tap order. Throws
  // EngineFailure for a missing or bad per-tap output, std::runtime_error if the engine does not tap.
  virtual std::vector<TapSnapshot> read_taps(const std::string& dir, const Packing& original,
                                             const RelaxPlan& plan) const {
    (void)dir, (void)original, (void)plan;
    throw std::runtime_error("this engine has no DEM tapping");
  }
};

std::unique_ptr<EngineAdapter> make_liggghts_adapter();
std::unique_ptr<EngineAdapter> make_yade_adapter();

}  // namespace btr
