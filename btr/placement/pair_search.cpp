#include "btr/placement/pair_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace btr {

namespace {
// Cell coordinates are kept within +-2^52 (a centre astronomically far out shares an edge cell).
constexpr double kMaxCoordinate = 4503599627370496.0;
}  // namespace

PairSearch::PairSearch(const Grains& grains, int dimension, const Container& container, double cutoff,
                       int cells_per_cutoff)
    : cut2_(cutoff * cutoff) {
  const double r_max = max_radius(grains);
  // As many cells to the cut-off as asked for, but none narrower than the largest diameter (narrower
  // cells would mostly be empty).
  const int most = std::clamp(cells_per_cutoff, 1, kMaxReach);
  const double fit = std::floor(cutoff / (2.0 * r_max));
  reach_ = fit >= most ? most : fit >= 1.0 ? static_cast<int>(fit) : 1;  // NaN (no grains): 1
  const double w = std::max({cutoff / reach_, 2.0 * r_max, 1e-300});
  for (int a = 0; a < 3; ++a) {
    period_[a] = a < 2 ? period_along(container, dimension, a) : 0.0;
    if (period_[a] > 0.0) {
      n_[a] = std::max(1L, static_cast<long>(std::floor(period_[a] / w)));
      width_[a] = period_[a] / static_cast<double>(n_[a]);
    } else {
      width_[a] = w;
    }
  }
  const std::size_t count = grains.size();
  long hi[3] = {0, 0, 0};
  for (std::size_t i = 0; i < count; ++i)
    for (int a = 0; a < 3; ++a) {
      if (period_[a] > 0.0) continue;
      const long c = coordinate(grains[i].x[a], a);
      if (i == 0 || c < lo_[a]) lo_[a] = c;
      if (i == 0 || c > hi[a]) hi[a] = c;
    }
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (!(period_[a] > 0.0)) n_[a] = hi[a] - lo_[a] + 1;
    cells *= static_cast<double>(n_[a]);
  }
  auto cell_of = [&](std::size_t i) {
    const Vec3& x = grains[i].x;
    return std::array<long, 3>{coordinate(x.x(), 0), coordinate(x.y(), 1), coordinate(x.z(), 2)};
  };
  // A dense table of cells while it stays within a few times the grains; beyond that (a few grains far
  // from the rest) only the occupied cells, looked up by binary search.
  dense_ = cells <= 8.0 * static_cast<double>(count) + 4096.0;
  index_.resize(count);
  if (dense_) {
    auto id = [&](std::size_t i) {
      const std::array<long, 3> c = cell_of(i);
      return static_cast<std::size_t>(((c[2] - lo_[2]) * n_[1] + (c[1] - lo_[1])) * n_[0] + (c[0] - lo_[0]));
    };
    start_.assign(static_cast<std::size_t>(cells) + 1, 0);
    for (std::size_t i = 0; i < count; ++i) ++start_[id(i) + 1];
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < count; ++i) index_[fill[id(i)]++] = static_cast<std::uint32_t>(i);
  } else {
    std::vector<std::array<long, 3>> key(count);  // z, y, x: the dense table's order
    for (std::size_t i = 0; i < count; ++i) {
      const std::array<long, 3> c = cell_of(i);
      key[i] = {c[2], c[1], c[0]};
    }
    std::iota(index_.begin(), index_.end(), 0u);
    std::stable_sort(index_.begin(), index_.end(), [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
    for (std::uint32_t p = 0; p < count; ++p) {
      const auto& k = key[index_[p]];
      if (cells_.empty() || cells_.back().x != k[2] || cells_.back().y != k[1] || cells_.back().z != k[0])
        cells_.push_back({k[2], k[1], k[0], p, p});
      cells_.back().end = p + 1;
    }
  }
  where_.resize(count);
  pos_.resize(count);
  for (std::uint32_t p = 0; p < count; ++p) {
    where_[index_[p]] = p;
    pos_[p] = grains[index_[p]].x;
  }
}

long PairSearch::coordinate(double v, int a) const {
  if (period_[a] > 0.0) {
    const double u = (v + 0.5 * period_[a]) / period_[a];
    const long k = static_cast<long>(std::floor((u - std::floor(u)) * static_cast<double>(n_[a])));
    return std::clamp(k, 0L, n_[a] - 1);
  }
  double t = std::floor(v / width_[a]);
  if (!(t > -kMaxCoordinate)) t = -kMaxCoordinate;  // NaN too
  if (t > kMaxCoordinate) t = kMaxCoordinate;
  return static_cast<long>(t);
}

int PairSearch::axis_cells(int a, long c, long* out) const {
  int m = 0;
  for (long d = -reach_; d <= reach_; ++d) {
    long k = c + d;
    if (period_[a] > 0.0) k = ((k % n_[a]) + n_[a]) % n_[a];
    else if (dense_ && (k < lo_[a] || k >= lo_[a] + n_[a])) continue;
    bool seen = false;
    for (int q = 0; q < m; ++q) seen = seen || out[q] == k;
    if (!seen) out[m++] = k;
  }
  return m;
}

void PairSearch::range(long x, long y, long z, std::uint32_t& begin, std::uint32_t& end) const {
  if (dense_) {
    const std::size_t id = static_cast<std::size_t>(((z - lo_[2]) * n_[1] + (y - lo_[1])) * n_[0] + (x - lo_[0]));
    begin = start_[id], end = start_[id + 1];
    return;
  }
  const auto it = std::lower_bound(cells_.begin(), cells_.end(), std::array<long, 3>{z, y, x},
                                   [](const Cell& c, const std::array<long, 3>& k) {
                                     return std::array<long, 3>{c.z, c.y, c.x} < k;
                                   });
  if (it != cells_.end() && it->x == x && it->y == y && it->z == z) begin = it->begin, end = it->end;
  else begin = end = 0;
}

}  // namespace btr
