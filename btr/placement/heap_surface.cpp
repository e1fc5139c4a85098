#include "btr/placement/heap_surface.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "btr/model/container.h"
#include "btr/model/grain.h"
#include "btr/placement/drops.h"
#include "btr/scene/scene_toml.h"

namespace btr {
namespace {

// At most this many cells along an axis of the sampling grid (cells are otherwise half the smallest radius).
constexpr long kMaxCellsPerAxis = 2048;
// Draws per drop before a drop that finds no room inside the container is an error.
constexpr int kTries = 100000;
// Mixed into the seed (times the draw + 1): the positions' generators differ from the drops' own and each other.
constexpr std::uint64_t kPositionStream = 0x9e3779b97f4a7c15ULL;

double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

std::string scene_name(const Scene& scene) { return scene.file.empty() ? "scene '" + scene.name + "'" : scene.file; }

// Whether a grain of radius r centred at (x, y) is inside the container's lateral walls (the floor is z = 0).
bool fits(const Container& c, int dim, double x, double y, double r) {
  switch (c.kind) {
    case ContainerKind::Open:
    case ContainerKind::Periodic: return true;
    case ContainerKind::Box: return std::abs(x) <= 0.5 * c.size_x - r && (dim == 2 || std::abs(y) <= 0.5 * c.size_y - r);
    case ContainerKind::HeleShaw: return std::abs(x) <= 0.5 * c.size_x - r && (dim == 2 || std::abs(y) <= 0.5 * c.gap - r);
    case ContainerKind::Cylinder: return dim == 2 ? std::abs(x) <= c.radius - r : std::hypot(x, y) <= c.radius - r;
    default: return false;  // drums and meshes are not heaps (refused before)
  }
}

// The rectangle [x0, x1] x [y0, y1] the container confines its grains to, or false when it is open.
bool bounds(const Container& c, double& x0, double& x1, double& y0, double& y1) {
  switch (c.kind) {
    case ContainerKind::Box:
    case ContainerKind::Periodic: x1 = 0.5 * c.size_x, y1 = 0.5 * c.size_y; break;
    case ContainerKind::HeleShaw: x1 = 0.5 * c.size_x, y1 = 0.5 * c.gap; break;
    case ContainerKind::Cylinder: x1 = y1 = c.radius; break;
    default: return false;
  }
  x0 = -x1, y0 = -y1;
  return true;
}

struct Grid {
  double x0 = 0, y0 = 0, h = 0;
  long nx = 1, ny = 1;
  double cell_measure = 0;       // area (3D) or length (2D) of a cell
  std::vector<double> distance;  // per cell (NaN outside the container), row-major in x
};

Grid make_grid(const Scene& scene, double x0, double x1, double y0, double y1, double r_min) {
  const int dim = scene.dimension;
  Grid g;
  const double span = std::max(x1 - x0, dim == 3 ? y1 - y0 : 0.0);
  g.h = std::max(0.5 * r_min, span / kMaxCellsPerAxis);
  g.nx = std::max(1L, static_cast<long>(std::ceil((x1 - x0) / g.h)));
  g.ny = dim == 3 ? std::max(1L, static_cast<long>(std::ceil((y1 - y0) / g.h))) : 1;
  g.x0 = x0, g.y0 = y0;
  g.cell_measure = dim == 3 ? g.h * g.h : g.h;
  g.distance.resize(static_cast<std::size_t>(g.nx * g.ny));
  for (long j = 0; j < g.ny; ++j)
    for (long i = 0; i < g.nx; ++i) {
      const double x = x0 + (i + 0.5) * g.h, y = dim == 3 ? y0 + (j + 0.5) * g.h : 0.0;
      g.distance[static_cast<std::size_t>(j * g.nx + i)] =
          fits(scene.container, dim, x, y, 0.0) ? distance_to_source(scene, x, y) : std::nan("");
    }
  return g;
}

double surface_volume(const Grid& g, double apex, double slope) {
  double v = 0.0;
  for (double d : g.distance)
    if (!std::isnan(d)) v += std::max(0.0, apex - slope * d);
  return v * g.cell_measure;
}

}  // namespace

double distance_to_source(const Scene& scene, double x, double y) {
  const SourceSpec& s = scene.source;
  const Container& c = scene.container;
  const bool three = scene.dimension == 3;
  auto gap = [](double v, double lo, double hi) { return v < lo ? lo - v : v > hi ? v - hi : 0.0; };
  auto image = [&](double v, int axis) {
    const double period = period_along(c, scene.dimension, axis);
    return period > 0.0 ? wrap_coordinate(v, period) : v;
  };
  switch (s.kind) {
    case SourceSpec::Kind::Point: {
      const double dx = image(x - s.x, 0), dy = three ? image(y - s.y, 1) : 0.0;
      return std::max(0.0, std::hypot(dx, dy) - s.scatter);
    }
    case SourceSpec::Kind::Region: {
      const double cx = 0.5 * (s.x_min + s.x_max), cy = 0.5 * (s.y_min + s.y_max);
      const double dx = gap(cx + image(x - cx, 0), s.x_min, s.x_max);
      const double dy = three ? gap(cy + image(y - cy, 1), s.y_min, s.y_max) : 0.0;
      return std::hypot(dx, dy);
    }
    default:
      throw SceneError(scene_name(scene) +
                       ": source.kind: a heap is built around a point or region source; a rain or list source has "
                       "no footprint to build it around");
  }
}

HeapSurfaceSampler::HeapSurfaceSampler(const Scene& scene, std::uint64_t seed, std::int64_t count, double angle,
                                       double packing_fraction)
    : scene_(scene), seed_(seed) {
  if (!(angle > 0.0 && angle < 0.5 * M_PI))
    throw std::invalid_argument("HeapSurfaceSampler: the flank angle must lie in (0, 90) degrees, got " +
                                std::to_string(angle * 180.0 / M_PI));
  if (!(packing_fraction > 0.0 && packing_fraction <= 1.0))
    throw std::invalid_argument("HeapSurfaceSampler: the packing fraction must lie in (0, 1], got " +
                                std::to_string(packing_fraction));
  distance_to_source(scene, 0.0, 0.0);  // refuses a source without a footprint
  const int dim = scene.dimension;
  scene_.grains.count = count;
  DropSequence sequence(scene_, seed);
  drops_.resize(static_cast<std::size_t>(sequence.count()));
  double solid = 0.0;
  for (Drop& d : drops_) {
    d = sequence.next();
    solid += grain_volume(d.r, dim);
  }
  HeapSurface& out = surface_;
  out.angle = angle;
  out.packing_fraction = packing_fraction;
  out.volume = solid / packing_fraction;
  const double slope = std::tan(angle);

  // The sampling grid covers the container, or on an open floor the footprint widened by the reach of the
  // tallest heap needed: even a point footprint's cone, pi/3 H^3 / tan^2 (2D: triangle H^2 / tan), holds the
  // volume at that height, and a wider footprint holds more.
  double x0, x1, y0, y1;
  if (!bounds(scene.container, x0, x1, y0, y1)) {
    const double h_max = dim == 3 ? std::cbrt(3.0 * out.volume * slope * slope / M_PI) : std::sqrt(out.volume * slope);
    const SourceSpec& src = scene.source;
    const bool point = src.kind == SourceSpec::Kind::Point;
    const double reach = h_max / slope + 2.0 * sequence.r_max() + (point ? src.scatter : 0.0);
    x0 = (point ? src.x : src.x_min) - reach, x1 = (point ? src.x : src.x_max) + reach;
    y0 = (point ? src.y : src.y_min) - reach, y1 = (point ? src.y : src.y_max) + reach;
  }
  const Grid grid = make_grid(scene, x0, x1, y0, y1, sequence.r_min());

  // H by bisection: the volume grows with H without bound on an open floor, and within a container once
  // the surface clears the walls it grows linearly, so doubling finds an upper bracket.
  double lo = 0.0, hi = std::max(x1 - x0, y1 - y0) * slope;
  for (int k = 0; k < 200 && surface_volume(grid, hi, slope) < out.volume; ++k) hi *= 2.0;
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (surface_volume(grid, mid, slope) < out.volume ? lo : hi) = mid;
  }
  out.apex_height = hi;
  out.reach = hi / slope;

  x0_ = grid.x0, y0_ = grid.y0, h_ = grid.h, nx_ = grid.nx;
  cumulative_.resize(grid.distance.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < grid.distance.size(); ++k) {
    const double d = grid.distance[k];
    if (!std::isnan(d)) sum += std::max(0.0, out.apex_height - slope * d);
    cumulative_[k] = sum;
  }
}

std::vector<Drop> HeapSurfaceSampler::draw(std::uint64_t draw) const {
  const int dim = scene_.dimension;
  const Container& c = scene_.container;
  const double sum = cumulative_.back();
  std::vector<Drop> drops = drops_;
  // Stratified: drop n takes stratum order[n] of N equal shares of the surface's volume (in the grid's row-major
  // order, so each stretch of the floor receives its share to within one grain) and a uniform point in it; the
  // strata are visited in a random order, so the heap rises everywhere at once. Plain random positions would
  // leave the surface rough by the square root of each column's count, and a heap of a few thousand grains
  // would stand a degree or two off the angle asked.
  std::mt19937_64 rng(seed_ ^ (kPositionStream * (draw + 1)));
  const std::size_t n_drops = drops.size();
  std::vector<std::size_t> order(n_drops);
  for (std::size_t k = 0; k < n_drops; ++k) order[k] = k;
  for (std::size_t k = n_drops; k > 1; --k)  // Fisher-Yates with the generator's own doubles (portable)
    std::swap(order[k - 1], order[static_cast<std::size_t>(unit(rng) * static_cast<double>(k))]);
  for (std::size_t n = 0; n < n_drops; ++n) {
    Drop& d = drops[n];
    for (int tries = 0;; ++tries) {
      if (tries == kTries)
        throw SceneError(scene_name(scene_) + ": the heap's surface leaves no room for grain " + std::to_string(n + 1) +
                         " (radius " + std::to_string(d.r) + " m) inside the container");
      // A grain that does not fit in its stratum (against a wall) is drawn anywhere after a few tries.
      const double share = tries < 16 ? (static_cast<double>(order[n]) + unit(rng)) / static_cast<double>(n_drops)
                                      : unit(rng);
      const std::size_t k = static_cast<std::size_t>(
          std::min<std::ptrdiff_t>(std::upper_bound(cumulative_.begin(), cumulative_.end(), share * sum) -
                                       cumulative_.begin(),
                                   static_cast<std::ptrdiff_t>(cumulative_.size()) - 1));
      const long i = static_cast<long>(k) % nx_, j = static_cast<long>(k) / nx_;
      double x = x0_ + (i + unit(rng)) * h_;
      double y = dim == 3 ? y0_ + (j + unit(rng)) * h_ : 0.0;
      if (!fits(c, dim, x, y, d.r)) continue;
      if (wraps_x(c)) x = wrap_coordinate(x, c.size_x);
      if (wraps_y(c, dim)) y = wrap_coordinate(y, c.size_y);
      d.x = x, d.y = y;
      break;
    }
  }
  return drops;
}

}  // namespace btr
