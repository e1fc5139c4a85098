#pragma once
// Overlaps in a packing: grain pairs (nearest periodic image in a periodic container) and grains
// against the container's walls (dem_walls.h). BTR contacts touch exactly, so any overlap beyond
// round-off comes from elsewhere (an edited packing, a relaxation) and is measured here.
#include <cstdint>
#include <functional>
#include <map>
#include <utility>
#include <string>

#include "btr/model/container.h"
#include "btr/model/grain.h"
#include "coupling/dem/dem_walls.h"

namespace btr {

struct OverlapReport {
  double largest = 0.0;        // largest overlap / smaller radius of the pair (grain radius for a wall)
  double depth = 0.0;          // that overlap [m]
  std::int64_t id_a = 0;       // grains of the largest overlap; id_b == 0 means a wall
  std::int64_t id_b = 0;
  std::string wall;            // the wall's name when id_b == 0
  std::int64_t count = 0;      // contacts with a positive overlap
  bool beyond_intended = false;  // largest/depth measure the overlap beyond the intended one
  std::string describe() const;  // "0.031 of the smaller radius (1.5e-05 m) between grains 4 and 17"
};

// Calls f(id_a, id_b, depth, wall) for every overlapping contact (depth > 0); wall is null for a grain
// pair, else the wall (then id_b == 0). Each pair is reported once, with id_a < id_b.
void for_each_overlap(const Grains& grains, int dimension, const Container& container,
                      const std::function<void(std::int64_t, std::int64_t, double, const DemWall*)>& f);

OverlapReport largest_overlap(const Grains& grains, int dimension, const Container& container);

// The overlaps a packing is meant to have (a pre-loaded start, preload.h), by contact: (id_a, id_b)
// with id_a < id_b for a grain pair, (id, code) for a wall with code 0 the floor and -1, -2, ... the
// other walls in dem_walls order. A contact not listed is meant to have none.
using IntendedOverlaps = std::map<std::pair<std::int64_t, std::int64_t>, double>;

// The largest overlap beyond its intended value: largest = (overlap - intended) / smaller radius.
OverlapReport largest_overlap(const Grains& grains, int dimension, const Container& container,
                              const IntendedOverlaps& intended);

}  // namespace btr
