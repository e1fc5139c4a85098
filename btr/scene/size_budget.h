#pragma once
// The memory a run will need, estimated from the user's values before anything is allocated, so a value
// that cannot fit in this machine's memory is refused up front (exit 2, naming the field and the
// estimate) instead of ending in std::bad_alloc after minutes of allocation.
#include <cstdint>
#include <optional>
#include <string>

#include "btr/scene/scene.h"

namespace btr {

// Physical memory of this machine [bytes].
double machine_memory_bytes();

// Peak memory per placed grain [bytes]: the grain, its neighbour-grid entry, the released packing and the
// output buffers. Measured: 157 MB peak RSS for `btr deposit` of 1e6 grains (bed3d); rounded up.
constexpr double kBytesPerGrain = 200.0;

// Bytes of the neighbour grid's columns over a lateral extent lx by ly (ly unused in 2D) with cells of
// width `cell`: one column record per cell of the footprint.
double grid_bytes(int dimension, double lx, double ly, double cell);

// What does not fit: the message (field, value, estimate, the machine's memory), or nothing.
// `field` names where the value came from (e.g. "--count" or "grains.count").
std::optional<std::string> count_does_not_fit(std::int64_t count, const std::string& field);
std::optional<std::string> grid_does_not_fit(int dimension, double lx, double ly, double cell,
                                             const std::string& field, double value);

// A closed drum holds at most its volume (area in 2D) times the densest packing fraction (pi / sqrt(18) of
// spheres, pi / sqrt(12) of disks) over the smallest grain's volume (area): more grains cannot fit, whatever
// their order. The message, or nothing (also for other containers, which are open at the top).
std::optional<std::string> drum_overfilled(const Scene& scene, std::int64_t count, const std::string& field);

// Throws SceneError (naming scene.file and the field) when `count` grains of the scene cannot fit in this
// machine's memory, or in its drum.
void check_count_fits(const Scene& scene, std::int64_t count, const std::string& field);

}  // namespace btr
