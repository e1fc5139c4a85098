#include "series_files.h"

#include <cstdio>
#include <iostream>
#include <sstream>

#include "btr/verify/check.h"
#include "command_support.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/packing_io.h"

namespace btr_app {

SeriesWriter::SeriesWriter(std::string dir, std::string name, std::string step_name)
    : dir_(std::move(dir)), name_(std::move(name)), step_name_(std::move(step_name)) {}

void SeriesWriter::write(long long step, double time, const btr::Grains& grains, const nlohmann::json& meta) {
  char base[64];
  std::snprintf(base, sizeof base, "_%c%06lld", step_name_.empty() ? 's' : step_name_[0], step);
  const std::string file = name_ + base;
  btr::Packing packing;
  packing.grains = grains;
  packing.meta = meta;
  btr::write_packing(dir_, file, packing);
  entries_.emplace_back(time, file + ".vtp");
  std::ostringstream x;
  x.precision(12);  // times are cycle numbers or angles in degrees
  x << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const auto& [t, f] : entries_)
    x << "    <DataSet timestep=\"" << t << "\" group=\"\" part=\"0\" file=\"" << f << "\"/>\n";
  x << "  </Collection>\n</VTKFile>\n";
  btr::write_text_file(dir_ + "/" + name_ + ".pvd", x.str());
}

nlohmann::json snapshot_meta(const char* command, const btr::Scene& scene, const nlohmann::json& scene_json,
                             std::uint64_t seed, std::size_t count) {
  return {{"program", "btr"}, {"version", BTR_VERSION},   {"command", command},
          {"scene_name", scene.name}, {"scene_file", scene.file}, {"scene", scene_json},
          {"seed", seed},      {"dimension", scene.dimension}, {"container", scene_json["container"]},
          {"count", count}};
}

bool check_snapshot(const char* command, const char* counter, long long step, const btr::Grains& grains,
                    const btr::Scene& scene, nlohmann::json& meta) {
  const btr::CheckReport rep = btr::check_packing(grains, scene.dimension, scene.container);
  meta["check"] = check_to_json(rep);
  if (rep.ok()) return true;
  std::cerr << "btr " << command << ": check failed at " << counter << " " << step << ": " << check_message(rep)
            << "\n";
  return false;
}

}  // namespace btr_app
