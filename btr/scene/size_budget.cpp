#include "btr/scene/size_budget.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>

#include "btr/model/number_text.h"
#include "btr/scene/scene_toml.h"

namespace btr {
namespace {

// The grid's column record: two std::vector (layer starts, entries).
constexpr double kBytesPerColumn = 48.0;

std::string gigabytes(double bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.3g GB", bytes / 1e9);
  return text;
}

std::string rounded(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

}  // namespace

double machine_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

double grid_bytes(int dimension, double lx, double ly, double cell) {
  const double nx = std::ceil(lx / cell) + 1.0;
  const double ny = dimension == 3 ? std::ceil(ly / cell) + 1.0 : 1.0;
  return nx * ny * kBytesPerColumn;
}

std::optional<std::string> count_does_not_fit(std::int64_t count, const std::string& field) {
  const double need = static_cast<double>(count) * kBytesPerGrain, have = machine_memory_bytes();
  if (have <= 0.0 || need <= have) return std::nullopt;
  return field + " = " + std::to_string(count) + ": " + std::to_string(count) + " grains need about " +
         gigabytes(need) + " (" + g6(kBytesPerGrain) + " bytes per grain), more than this machine's memory (" +
         gigabytes(have) + "); expected at most about " + rounded(have / kBytesPerGrain) + " grains";
}

std::optional<std::string> grid_does_not_fit(int dimension, double lx, double ly, double cell,
                                             const std::string& field, double value) {
  const double need = grid_bytes(dimension, lx, ly, cell), have = machine_memory_bytes();
  if (have <= 0.0 || (std::isfinite(need) && need <= 0.5 * have)) return std::nullopt;
  return field + " = " + g6(value) + " m: the placement's neighbour grid over a footprint of " + g6(lx) +
         (dimension == 3 ? " x " + g6(ly) : std::string()) + " m in cells of " + g6(cell) +
         " m (a largest grain diameter) needs about " + gigabytes(need) +
         ", more than half this machine's memory (" + gigabytes(have) + ")";
}

std::optional<std::string> drum_overfilled(const Scene& s, std::int64_t count, const std::string& field) {
  if (s.container.kind != ContainerKind::Drum || s.source.kind == SourceSpec::Kind::List) return std::nullopt;
  double r_min = std::numeric_limits<double>::infinity();
  for (const Component& c : s.grains.components) {
    const RadiusSpec& r = c.radius;
    if (r.kind == RadiusSpec::Kind::Constant) r_min = std::min(r_min, r.value);
    else if (r.kind == RadiusSpec::Kind::List) r_min = std::min(r_min, *std::min_element(r.list.begin(), r.list.end()));
    else r_min = std::min(r_min, r.min);
  }
  if (!(r_min > 0.0)) return std::nullopt;
  const double pi = 3.14159265358979323846, R = s.container.radius;
  const double capacity = s.dimension == 3
                              ? pi * R * R * s.container.size_y * (pi / std::sqrt(18.0)) / (4.0 / 3.0 * pi * r_min * r_min * r_min)
                              : pi * R * R * (pi / std::sqrt(12.0)) / (pi * r_min * r_min);
  if (static_cast<double>(count) <= capacity) return std::nullopt;
  return field + " = " + std::to_string(count) + ": the drum holds at most about " + rounded(std::floor(capacity)) +
         " grains (its " + (s.dimension == 3 ? "volume" : "area") + " at the densest packing fraction, over the "
         "smallest grain's); expected at most that many";
}

void check_count_fits(const Scene& scene, std::int64_t count, const std::string& field) {
  if (auto why = count_does_not_fit(count, field)) throw SceneError(scene.file + ": " + *why);
  if (auto why = drum_overfilled(scene, count, field)) throw SceneError(scene.file + ": " + *why);
}

}  // namespace btr
