#include "coupling/dem/overlap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <unordered_map>
#include <vector>

namespace btr {

namespace {

// Hashed uniform grid with cells at least one largest diameter wide; periodic axes are divided
// into whole cells and wrap.
class Grid {
 public:
  Grid(const Grains& grains, int dimension, const Container& c) : grains_(grains) {
    double r_max = 0.0;
    for (const Grain& g : grains) r_max = std::max(r_max, g.r);
    const double h = std::max(2.0 * r_max, 1e-300);
    const bool periodic = c.kind == ContainerKind::Periodic;
    period_[0] = periodic ? c.size_x : 0.0;
    period_[1] = periodic && dimension == 3 ? c.size_y : 0.0;
    for (int a = 0; a < 3; ++a) {
      if (period_[a] > 0.0) {
        n_[a] = std::max(1L, static_cast<long>(std::floor(period_[a] / h)));
        h_[a] = period_[a] / static_cast<double>(n_[a]);
      } else {
        h_[a] = h;
      }
    }
    for (std::size_t i = 0; i < grains.size(); ++i) cells_[key(cell_of(grains[i].x))].push_back(static_cast<int>(i));
  }

  // f(j, dx) for every grain j != i in the cells around grain i, dx = x_j - x_i (nearest image).
  template <class F>
  void neighbours(std::size_t i, F&& f) const {
    const Vec3& xi = grains_[i].x;
    const auto c = cell_of(xi);
    std::vector<std::uint64_t> seen;
    for (long dz = -1; dz <= 1; ++dz)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dx = -1; dx <= 1; ++dx) {
          std::array<long, 3> n{c[0] + dx, c[1] + dy, c[2] + dz};
          for (int a = 0; a < 3; ++a)
            if (period_[a] > 0.0) n[a] = ((n[a] % n_[a]) + n_[a]) % n_[a];
          const std::uint64_t k = key(n);
          if (std::find(seen.begin(), seen.end(), k) != seen.end()) continue;
          seen.push_back(k);
          auto it = cells_.find(k);
          if (it == cells_.end()) continue;
          for (int j : it->second) {
            if (static_cast<std::size_t>(j) == i) continue;
            Vec3 d = grains_[j].x - xi;
            for (int a = 0; a < 3; ++a)
              if (period_[a] > 0.0) d[a] -= period_[a] * std::round(d[a] / period_[a]);
            f(static_cast<std::size_t>(j), d);
          }
        }
  }

 private:
  std::array<long, 3> cell_of(const Vec3& x) const {
    std::array<long, 3> c{};
    for (int a = 0; a < 3; ++a) {
      if (period_[a] > 0.0) {
        const double u = (x[a] + 0.5 * period_[a]) / period_[a];
        long k = static_cast<long>(std::floor((u - std::floor(u)) * static_cast<double>(n_[a])));
        c[a] = std::clamp(k, 0L, n_[a] - 1);
      } else {
        c[a] = static_cast<long>(std::floor(x[a] / h_[a]));
      }
    }
    return c;
  }
  static std::uint64_t key(const std::array<long, 3>& c) {
    auto part = [](long v) { return static_cast<std::uint64_t>(v + (1L << 20)) & ((1ULL << 21) - 1); };
    return part(c[0]) | (part(c[1]) << 21) | (part(c[2]) << 42);
  }

  const Grains& grains_;
  double period_[3] = {0, 0, 0};
  double h_[3] = {1, 1, 1};
  long n_[3] = {1, 1, 1};
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

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
  const Grid grid(grains, dimension, container);
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Grain& g = grains[i];
    const auto id = static_cast<std::int64_t>(i) + 1;
    for (const DemWall& w : walls) {
      const double depth = g.r - w.distance(g.x);
      if (depth > 0.0) f(id, 0, depth, &w);
    }
    grid.neighbours(i, [&](std::size_t j, const Vec3& d) {
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
