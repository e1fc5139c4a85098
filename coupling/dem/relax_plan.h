#pragma once
// The engine-independent steps of a relaxation, in the order relax() runs them; exposed so that a
// test or a tool can run them one at a time (e.g. export, edit the inputs, then run them).
#include <memory>
#include <string>
#include <vector>

#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/relax.h"

namespace btr {

// A packing or setting that is refused before any engine starts (overlap, time step, ...).
class RelaxRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws RelaxRefused "FILE: FIELD: WHY" (a scene without a file is named "scene 'NAME'").
[[noreturn]] void refuse_scene_field(const Scene& scene, const std::string& field, const std::string& why);

// Time step (stable step, or the requested one if it is not above it), stop threshold and the
// largest initial overlap. Throws RelaxRefused for a requested step above the stable one or an
// overlap above settings.max_overlap, each with the number that would be accepted.
// `engine` ("liggghts" | "yade") decides which contact mode's damping limits the step (timestep.h).
// With `intended` (a pre-loaded packing, preload.h) the overlap checked is the one beyond each
// contact's intended overlap, and the stop rule arms after preload_arming_time.
RelaxPlan make_plan(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                    const std::string& engine, const IntendedOverlaps* intended = nullptr);

// Arming time of a pre-loaded start: sqrt(2 delta_max / g), the time a grain whose weight were not
// carried takes to fall through the largest intended overlap (its kinetic energy m g delta_max is then
// far above the threshold, ~1e-6 m g d), and at least 50 time steps.
double preload_arming_time(double largest_intended_depth, double timestep);

// The packing a relaxation starts from: the input, or its pre-loaded version when settings.preload or
// the scene's relax.preload asks for it (then `intended` is filled and the preloaded packing with its
// force network is written to out_dir/preloaded.{csv,json,vtp} and preloaded.forces.{csv,vtp}).
Packing starting_packing(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                         IntendedOverlaps& intended, const std::string& out_dir);

// The stop rule's threshold: ratio * sum_i m_i g d_i (d_i the diameter, m_i a sphere's mass).
double kinetic_threshold(const Grains& grains, const Scene& scene);

// Simulated time after which a relaxation may stop even if its kinetic energy never rose above the
// threshold: sqrt(2 r_min / g), the time a grain falling freely from rest takes to move its own
// radius. (Otherwise a packing at rest at t = 0 would "converge" before it started to move.)
double stop_arming_time(const Grains& grains);

// An upper bound of the kinetic energy a relaxation can reach without creating energy:
// 2 (sum_i m_i g z_i + elastic energy of the initial overlaps). Above it the run has blown up.
double kinetic_energy_bound(const Grains& grains, const Scene& scene);

// Makes dir and writes the engine's inputs into it; prints the time-step rule on stdout.
std::vector<std::string> write_engine_inputs(const Packing& packing, const Scene& scene, const EngineAdapter& adapter,
                                             const RelaxSettings& settings, const RelaxPlan& plan,
                                             const std::string& dir);

// Runs the inputs already in dir and reads the result back, checked: ids, radii and species kept, finite values,
// grains inside the container, bounded kinetic energy, a stop reason. Removed grains (open floors) are left out
// of relaxed.grains, velocities and contacts, and the others renumbered 1..N-k (RelaxResult::removed lists them).
// Throws EngineFailure ("<engine> <what> failed in DIR: ...", with the tail of the engine's log) or Interrupted.
RelaxResult run_and_read_back(const Packing& packing, const Scene& scene, const EngineAdapter& adapter,
                              const std::string& engine, const RelaxSettings& settings, const RelaxPlan& plan,
                              const std::string& dir, const std::string& what);

// dir/kinetic.csv (time,kinetic_energy), dir/contacts.csv (id1,id2,normal_force; id2 = 0 a wall) and
// dir/velocities.csv (id,vx,vy,vz; removed when the engine gave none) of a run.
void write_run_tables(const RelaxResult& res, const std::string& dir);

// Runs the inputs already in dir, reads the result back, checks it (ids, finite values, grains
// inside the container, bounded kinetic energy) and writes dir/relaxed.{csv,json,vtp},
// dir/kinetic.csv and dir/contacts.csv. Throws EngineFailure with the tail of the engine's log, after
// writing dir/relax_failure.json (kRelaxFailureFile: kind, engine, message, the check's values, the log's
// name) atomically; removes that file when it starts, so it is there only after a failed run.
RelaxResult run_engine_inputs(const Packing& packing, const Scene& scene, const EngineAdapter& adapter,
                              const std::string& engine, const RelaxSettings& settings, const RelaxPlan& plan,
                              const std::string& dir);

// Removes dir/relax_failure.json, if any: a run into dir starts, so the record of an earlier one goes.
void clear_failure_record(const std::string& dir);

// Refuses (RelaxRefused) what rigid clusters cannot do in `engine`: they must stay rigid.
void check_clusters_supported(const Packing& packing, const Scene& scene, const std::string& engine,
                              const RelaxSettings& settings);

}  // namespace btr
