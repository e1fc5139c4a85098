#pragma once
// A scene as JSON, stored in every packing's NAME.json so later stages need only the packing.
#include <nlohmann/json.hpp>

#include "btr/scene/scene.h"

namespace btr {

nlohmann::json scene_to_json(const Scene& scene);
// `origin` names where the JSON came from, for error messages.
Scene scene_from_json(const nlohmann::json& j, const std::string& origin);

}  // namespace btr
