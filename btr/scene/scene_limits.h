#pragma once
// The physical and numerical limits of a scene's values, checked on the Scene itself so that every reader
// (the TOML scene file, the scene stored in a packing's JSON) refuses the same values with the same reason.
// The TOML reader already checks each value's sign and type as it reads it; these rules add what only the
// whole scene shows (lengths against the grains) and, for the JSON reader, the signs as well.
#include <optional>
#include <string>

#include "btr/scene/scene.h"

namespace btr {

// Grain radii of one scene within this factor of each other.
constexpr double kMaxRadiusRatio = 1e4;
// Every length of a scene (container, source, intruder, shaking, drum) at most this many smallest radii:
// coordinates of magnitude L are rounded to L x 1.1e-16, which stays below 1e-10 of the smallest radius
// (the self-check's overlap tolerance is 1e-9 of it) up to this ratio.
constexpr double kMaxLengthRatio = 1e6;
// A drum's radius at most this many smallest radii: a grain rolling on the drum's wall meets a small neighbour at
// the crossing of two circles whose radii differ by that ratio, and the crossing loses precision as its square.
// drum2d's grains (radii 0.1-1 mm, 60 of them, 2 steps, --check): exact to the check's 1e-9 on every seed tried
// (1-6) up to a ratio of 2000, overlaps of 2e-9 on most seeds from 3000 (scripts/fuzz_inputs.py found them).
constexpr double kMaxDrumRadiusRatio = 1000.0;

// How a problem names fields: as the scene file (TOML) does, e.g. "container.size", "grains.component[1].radius",
// or as the scene stored in a packing's JSON does, e.g. "container.size_x", "grains.components[1].radius".
enum class FieldNames { Toml, Json };

struct SceneProblem {
  std::string field;    // the value at fault
  std::string message;  // "<field> = <value>: expected ..." (without the file name)
};

// The first value of the scene outside its limits, or nothing.
std::optional<SceneProblem> scene_value_problem(const Scene& scene, FieldNames names);

}  // namespace btr
