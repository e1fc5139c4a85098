#include "load_packing.h"

#include <filesystem>
#include <stdexcept>

#include "coupling/io/scene_json.h"

namespace btr_app {

PackingWithScene load_packing_with_scene(const std::string& csv_path) {
  PackingWithScene p;
  p.packing = btr::read_packing(csv_path);
  const std::string json_path = std::filesystem::path(csv_path).replace_extension(".json").string();
  if (!std::filesystem::exists(json_path))
    throw std::runtime_error(json_path + ": missing; relax, export and measure need the scene stored beside the packing (btr deposit writes it)");
  if (!p.packing.meta.contains("scene"))
    throw std::runtime_error(json_path + ": expected a key \"scene\" (the scene the packing was made from)");
  p.scene = btr::scene_from_json(p.packing.meta["scene"], json_path);
  return p;
}

}  // namespace btr_app
