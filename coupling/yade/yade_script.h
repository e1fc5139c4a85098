#pragma once
// The YADE half of the coupling (coupling/yade/yade_adapter.cpp): the batch script that relaxes a packing and the
// files it reads and writes, all inside one run folder.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "coupling/dem/engine_adapter.h"

namespace btr {

namespace yade_files {
constexpr const char* kScript = "relax_yade.py";      // generated batch script
constexpr const char* kPacking = "yade_packing.csv";  // input: id,x,y,z,radius,species
constexpr const char* kMesh = "btr_mesh.stl";          // input (mesh container): its triangles, as placed
constexpr const char* kStatus = "yade_status.json";   // written last: status, stop reason, time, steps
constexpr const char* kFinal = "yade_final.csv";      // id,x,y,z,vx,vy,vz
constexpr const char* kKinetic = "yade_kinetic.csv";  // time,kinetic_energy
constexpr const char* kContacts = "yade_contacts.csv";  // i,j,fn,overlap (j = 0 for a wall)
constexpr const char* kLog = "yade.log";
constexpr const char* kTaps = "yade_taps.json";     // tapping: one record per tap (yade_library.py tap())
}  // namespace yade_files

// A rotating drum's snapshot k (1-based, DrumRotation): "yade_rot_K.csv" (id,x,y,z).
std::string yade_snapshot_file(std::size_t k);

// Reads snapshot k of a rotating drum's run in dir (EngineAdapter::read_snapshot).
Grains yade_read_snapshot(const std::string& dir, std::size_t k, const Packing& original);

// Tapping (RelaxPlan::tap): tap k's grains (1-based) after its rest, "yade_tap_K.csv" (id,x,y,z).
std::string yade_tap_file(long k);

// The taps of a tapping run in dir (EngineAdapter::read_taps): yade_taps.json's records (times, kinetic energies,
// settled, step, the floor's measured motion) and each tap's grains. Throws EngineFailure for a missing or bad record
// or file, lost or repeated ids.
std::vector<TapSnapshot> yade_read_taps(const std::string& dir, const Packing& original, const RelaxPlan& plan);

// Where Debian installs the `yade` Python module (package yade, double precision build).
constexpr const char* kYadePythonPath = "/usr/lib/x86_64-linux-gnu/yade-double/py";

// The Python functions every script shares (coupling/yade/yade_library.py, embedded by the build).
const char* yade_script_library();

// The whole script for this packing and scene. Throws std::invalid_argument naming the scene file and
// the field for what YADE cannot run (unknown model, 2D container without a 2D form, rolling friction with
// the linear law, ...).
std::string yade_script(const Packing& packing, const Scene& scene, const RelaxPlan& plan);

// Reads the outputs of a run in dir (see EngineAdapter::read_back).
RelaxResult yade_read_back(const std::string& dir, const Packing& original, const Scene& scene,
                           const RelaxPlan& plan);

// The failure a status file that is not "ok" reports: its kind is the script's "failure_kind" (the name
// of a FailureKind; engine_error if absent or unknown), its message the script's; a blow-up or a non-finite
// energy gets the last row of the kinetic history and the bound as values.
EngineFailure yade_status_failure(const std::string& dir, const nlohmann::json& status, const Packing& original,
                                  const Scene& scene);

// After a non-zero exit: the failure dir's status file reports, or std::nullopt if it reports none.
std::optional<EngineFailure> yade_failure_after_exit(const std::string& dir, const Packing& original,
                                                     const Scene& scene);

}  // namespace btr
