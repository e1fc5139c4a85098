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
    : cut2_(cutoff * cutoff), reach_(std::clamp(cells_per_cutoff, 1, kMaxReach)) {
  const double w = std::max(cutoff / reach_, 1e-300);
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
  std::vector<std::array<long, 3>> cell(count);
  long hi[3] = {0, 0, 0};
  for (std::size_t i = 0; i < count; ++i)
    for (int a = 0; a < 3; ++a) {
      const long c = cell[i][a] = coordinate(grains[i].x[a], a);
      if (period_[a] > 0.0) continue;
      if (i == 0 || c < lo_[a]) lo_[a] = c;
      if (i == 0 || c > hi[a]) hi[a] = c;
    }
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (!(period_[a] > 0.0)) n_[a] = hi[a] - lo_[a] + 1;
    cells *= static_cast<double>(n_[a]);
  }
  // A dense table of cells while it stays within a few times the grains; beyond that (a few grains far
  // from the rest) only the occupied cells, looked up by binary search.
  dense_ = cells <= 8.0 * static_cast<double>(count) + 4096.0;
  std::vector<std::uint32_t> order(count);
  if (dense_) {
    start_.assign(static_cast<std::size_t>(cells) + 1, 0);
    std::vector<std::uint32_t> id(count);
    for (std::size_t i = 0; i < count; ++i) {
      id[i] = static_cast<std::uint32_t>(((cell[i][2] - lo_[2]) * n_[1] + (cell[i][1] - lo_[1])) * n_[0] +
                                         (cell[i][0] - lo_[0]));
      ++start_[id[i] + 1];
    }
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < count; ++i) order[fill[id[i]]++] = static_cast<std::uint32_t>(i);
  } else {
    std::iota(order.begin(), order.end(), 0u);
    auto key = [&](std::uint32_t i) { return std::array<long, 3>{cell[i][2], cell[i][1], cell[i][0]}; };
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    for (std::uint32_t p = 0; p < count; ++p) {
      const auto& c = cell[order[p]];
      if (cells_.empty() || cells_.back().x != c[0] || cells_.back().y != c[1] || cells_.back().z != c[2])
        cells_.push_back({c[0], c[1], c[2], p, p});
      cells_.back().end = p + 1;
    }
  }
  index_ = order;
  where_.resize(count);
  pos_.resize(count);
  for (std::uint32_t p = 0; p < count; ++p) {
    where_[order[p]] = p;
    pos_[p] = grains[order[p]].x;
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
