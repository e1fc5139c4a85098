#include "series_files.h"

#include <cstdio>
#include <sstream>

#include "coupling/packing_io.h"
#include "coupling/text_file.h"

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

}  // namespace btr_app
