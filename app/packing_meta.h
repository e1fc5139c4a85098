#pragma once
// The head of every packing JSON a scene-driven command writes (deposit, pour, settle): program, version,
// command, the scene (so the packing can be measured, relaxed or exported on its own), seed, counts and radii.
#include <nlohmann/json.hpp>
#include <string>

#include "btr/model/grain.h"
#include "btr/scene/scene.h"

namespace btr_app {

nlohmann::json scene_packing_meta(const btr::Scene& scene, const btr::Grains& grains, std::uint64_t seed,
                                  const std::string& command);

// Processor time (user + system) of this process so far, in seconds.
double own_cpu_seconds();

}  // namespace btr_app
