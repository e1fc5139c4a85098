#pragma once
// The packing interchange format (docs/design.md section 2): NAME.csv + NAME.json + NAME.vtp.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "btr/model/grain.h"

namespace btr {

struct Packing {
  Grains grains;        // grain i has id i + 1
  nlohmann::json meta;  // the content of NAME.json (scene, seed, dimension, container, counts, timings...)
};

// A per-grain value written as VTK point data (e.g. displacement), one value per grain.
struct PointData {
  std::string name;
  std::vector<double> values;
};

// Reads PATH (NAME.csv) and, if present, NAME.json beside it. Ids must be 1..N in order. When the JSON
// records the CSV's size and CRC-32 ("files", written by write_packing), the CSV must match it; the
// record is not kept in Packing::meta.
// Throws std::runtime_error naming the file, the line and what was expected.
Packing read_packing(const std::string& csv_path);

// Writes DIR/NAME.csv, DIR/NAME.json and DIR/NAME.vtp (creating DIR if missing): all three go to
// temporary names in DIR first and are renamed only when all were written, so a failure leaves any
// previous packing of that name as it was. NAME.json gets "files": the CSV's and VTP's bytes and CRC-32;
// it is renamed last, so a packing is whole (its JSON matches its CSV) or has no JSON.
// `extra` becomes VTK point data (one value per grain).
void write_packing(const std::string& dir, const std::string& name, const Packing& packing,
                   const std::vector<PointData>& extra = {});

// Rewrites only DIR/NAME.json (temporary name, then renamed), e.g. to add the time spent writing; the
// "files" record of the JSON it replaces is kept (meta's own is ignored).
void write_packing_meta(const std::string& dir, const std::string& name, const nlohmann::json& meta);

}  // namespace btr
