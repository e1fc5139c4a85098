#include "coupling/dem/overlap.h"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "btr/placement/pair_search.h"

namespace btr {

namespace {

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

std::string OverlapReport::describe() const {
  if (count == 0) return "no overlap";
  std::string who = id_b == 0 ? "grain " + std::to_string(id_a) + " and the " + wall + " wall"
                              : "grains " + std::to_string(id_a) + " and " + std::to_string(id_b);
  return fmt(largest) + " of the smaller radius (" + fmt(depth) + " m" +
         (beyond_intended ? " beyond its intended overlap" : "") + ") between " + who;
}

void for_each_overlap(const Grains& grains, int dimension, const Container& container,
                      const std::function<void(std::int64_t, std::int64_t, double, const DemWall*)>& f) {
  const std::vector<DemWall> walls = dem_walls(container, dimension);
  const double r_max = max_radius(grains);
  const PairSearch pairs(grains, dimension, container, std::max(2.0 * r_max, 1e-300));
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Grain& g = grains[i];
    const auto id = static_cast<std::int64_t>(i) + 1;
    for (const DemWall& w : walls) {
      const double depth = g.r - w.distance(g.x);
      if (depth > 0.0) f(id, 0, depth, &w);
    }
    pairs.for_neighbours(i, [&](std::size_t j, const Vec3& d) {
      if (j < i) return;
      const double depth = g.r + grains[j].r - d.norm();
      if (depth > 0.0) f(id, static_cast<std::int64_t>(j) + 1, depth, nullptr);
    });
  }
}

OverlapReport largest_overlap(const Grains& grains, int dimension, const Container& container) {
  return largest_overlap(grains, dimension, container, IntendedOverlaps{});
}

OverlapReport largest_overlap(const Grains& grains, int dimension, const Container& container,
                              const IntendedOverlaps& intended) {
  OverlapReport rep;
  rep.beyond_intended = !intended.empty();
  const std::vector<DemWall> walls = dem_walls(container, dimension);
  for_each_overlap(grains, dimension, container, [&](std::int64_t a, std::int64_t b, double overlap, const DemWall* w) {
    ++rep.count;
    double depth = overlap;
    if (!intended.empty()) {
      std::int64_t code = b;
      if (w)
        for (std::size_t k = 0; k < walls.size(); ++k)
          if (walls[k].name == w->name) code = -static_cast<std::int64_t>(k);
      auto it = intended.find({a, code});
      if (it != intended.end()) depth -= it->second;
    }
    const double r = b == 0 ? grains[a - 1].r : std::min(grains[a - 1].r, grains[b - 1].r);
    const double rel = depth / r;
    if (rel > rep.largest) {
      rep.largest = rel;
      rep.depth = depth;
      rep.id_a = a;
      rep.id_b = b;
      rep.wall = w ? w->name : "";
    }
  });
  return rep;
}

}  // namespace btr
