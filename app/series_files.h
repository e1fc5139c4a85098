#pragma once
// A time series of packings for ParaView: DIR/NAME_<letter>NNNNNN.{csv,json,vtp} per snapshot and
// DIR/NAME.pvd, the collection file that lists them with their time step. The .pvd is rewritten
// (temporary name, then renamed) after every snapshot, so an interrupted run leaves a valid series.
// VTK 9 itself has no writer for .pvd collections (vtkXMLPVDWriter belongs to ParaView's own
// libraries), and the format is a short XML index, so it is written as text.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "btr/model/grain.h"
#include "btr/scene/scene.h"

namespace btr_app {

class SeriesWriter {
 public:
  // `step_name` names the snapshot counter in the file names and metadata ("cycle" -> NAME_c000010).
  SeriesWriter(std::string dir, std::string name, std::string step_name);

  // Writes one snapshot (step: the counter in the file name; time: the .pvd time step).
  void write(long long step, double time, const btr::Grains& grains, const nlohmann::json& meta);

  int count() const { return static_cast<int>(entries_.size()); }

 private:
  std::string dir_, name_, step_name_;
  std::vector<std::pair<double, std::string>> entries_;  // time, .vtp file name
};

// The JSON of one snapshot of `btr COMMAND`: program, version, command, scene, seed, dimension, container,
// count; the caller adds its counter (cycle, step, angle).
nlohmann::json snapshot_meta(const char* command, const btr::Scene& scene, const nlohmann::json& scene_json,
                             std::uint64_t seed, std::size_t count);

// Self-checks a snapshot and stores the result in meta["check"]; on failure prints one line naming the
// counter ("btr drum: check failed at step 12: ...") and returns false.
bool check_snapshot(const char* command, const char* counter, long long step, const btr::Grains& grains,
                    const btr::Scene& scene, nlohmann::json& meta);

}  // namespace btr_app
