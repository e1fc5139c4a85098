#pragma once
// The packing a relax/export command works on: PACKING.csv, and the scene stored in PACKING.json.
#include <string>

#include "btr/scene/scene.h"
#include "coupling/io/packing_io.h"

namespace btr_app {

struct PackingWithScene {
  btr::Packing packing;
  btr::Scene scene;
};

// Throws std::runtime_error naming the file when the CSV is bad, the JSON is missing or has no "scene".
PackingWithScene load_packing_with_scene(const std::string& csv_path);

}  // namespace btr_app
