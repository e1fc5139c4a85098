#include "btr/placement/run_scene.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "btr/placement/deposition.h"
#include "btr/placement/drops.h"
#include "btr/scene/scene_toml.h"

namespace btr {

namespace {

// The deposition loop: `next()` gives the drops in order; the next three are drawn ahead, so the grid memory
// each one's fall reads is asked for while the grains before it are placed (Deposition::prefetch).
template <class Next>
RunResult place_all(const Scene& s, std::int64_t total, double r_max, Next next,
                    const std::function<void(std::int64_t done, std::int64_t total)>& progress,
                    std::chrono::steady_clock::time_point start) {
  Deposition deposition(s.dimension, s.container, r_max);
  // Rain spreads the grains evenly over the footprint, so each column can be given room for its share at once.
  deposition.reserve(total, s.source.kind == SourceSpec::Kind::Rain);
  constexpr std::int64_t kProgressEvery = 256;
  Drop ahead[3];
  for (std::int64_t k = 0; k < std::min<std::int64_t>(3, total); ++k) ahead[k] = next();
  for (std::int64_t i = 0; i < total; ++i) {
    const Drop now = ahead[i % 3];
    if (i + 3 < total) ahead[i % 3] = next();
    if (i + 2 < total) deposition.prefetch(ahead[(i + 2) % 3], 2);
    if (i + 1 < total) deposition.prefetch(ahead[(i + 1) % 3], 1);
    deposition.prefetch(now, 0);
    try {
      deposition.place(now);
    } catch (const ContainerFull& e) {
      throw SceneError(s.file + ": grains.count = " + std::to_string(total) + ": expected at most " +
                       std::to_string(e.grain_id() - 1) + " grains, as many as the drum held when it was full (" +
                       e.what() + ")");
    }
    if (progress && (i + 1) % kProgressEvery == 0) progress(i + 1, total);
  }
  if (progress) progress(total, total);
  RunResult result;
  result.grains = deposition.release();
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

RunResult run_scene(const Scene& scene, std::uint64_t seed, std::int64_t count,
                    const std::function<void(std::int64_t done, std::int64_t total)>& progress) {
  if (count < 1) throw std::invalid_argument("run_scene: count must be >= 1, got " + std::to_string(count));
  const auto start = std::chrono::steady_clock::now();
  Scene s = scene;
  s.grains.count = count;
  DropSequence drops(s, seed);
  return place_all(s, drops.count(), drops.r_max(), [&] { return drops.next(); }, progress, start);
}

RunResult run_drops(const Scene& scene, const std::vector<Drop>& drops,
                    const std::function<void(std::int64_t done, std::int64_t total)>& progress) {
  if (drops.empty()) throw std::invalid_argument("run_drops: no drops");
  const auto start = std::chrono::steady_clock::now();
  double r_max = 0.0;
  for (const Drop& d : drops) r_max = std::max(r_max, d.r);
  std::size_t k = 0;
  return place_all(scene, static_cast<std::int64_t>(drops.size()), r_max, [&] { return drops[k++]; }, progress,
                   start);
}

}  // namespace btr
