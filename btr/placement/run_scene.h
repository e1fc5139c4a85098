#pragma once
// One BTR run: the scene's drops, in order, placed by the deposition engine.
#include <cstdint>
#include <functional>
#include <vector>

#include "btr/model/grain.h"
#include "btr/placement/deposition.h"
#include "btr/scene/scene.h"

namespace btr {

struct RunResult {
  Grains grains;
  double wall_seconds = 0.0;  // drawing the drops and placing them
};

// Places `count` grains of `scene` (scene.grains.count is replaced by `count`) with the given seed.
// `progress` (may be empty) is called now and then with the number placed so far, and once at the end.
// Throws PlacementError (from the engine) or SceneError (from the drop sequence).
RunResult run_scene(const Scene& scene, std::uint64_t seed, std::int64_t count,
                    const std::function<void(std::int64_t done, std::int64_t total)>& progress);

// Places the given drops, in order, in the scene's container (its source and grains are not used).
RunResult run_drops(const Scene& scene, const std::vector<Drop>& drops,
                    const std::function<void(std::int64_t done, std::int64_t total)>& progress);

}  // namespace btr
