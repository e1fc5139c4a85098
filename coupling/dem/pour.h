#pragma once
// The reference DEM pour, engine-independent part: inputs of the lattice through the engine's writer, the run
// and its checks (the relaxation's), and the poured packing with its record. Plan: pour_plan.h; the entry point
// that picks the engine: coupling/engines.h.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/pour_plan.h"

namespace btr {

struct PourResult {
  Packing poured;          // the grains at rest, same ids (an open floor's removed grains left out, the others
                           // renumbered); meta: the caller's, plus "pour" (the record)
  nlohmann::json record;   // settings, lattice, batches, time step and rule, stop reason, times, removed grains
  RelaxResult run;         // what the engine gave back (kinetic history, contacts, velocities)
};

// Refuses (RelaxRefused) grains the pour cannot take: none, rigid clusters, a 2D grain off the plane y = 0.
void check_pour_grains(const Grains& grains, const Scene& scene);

// Makes dir and writes the engine's inputs of the lattice into it; prints the plan on stdout.
std::vector<std::string> write_pour_inputs(const PourLattice& lattice, const Scene& pour, const EngineAdapter& adapter,
                                           const PourSettings& settings, const RelaxPlan& plan, const std::string& dir);

// Runs the inputs in dir, checks the result as a relaxation's, and writes dir/poured.{csv,json,vtp} (meta + the
// record), kinetic.csv, contacts.csv and velocities.csv. Throws EngineFailure or Interrupted.
PourResult run_pour_inputs(const PourLattice& lattice, const Scene& pour, const EngineAdapter& adapter,
                           const std::string& engine, const PourSettings& settings, const RelaxPlan& plan,
                           const std::string& dir, const nlohmann::json& meta);

}  // namespace btr
