// Self-check of a packing. Deliberately shares no code with the placement engine: its own
// neighbour grid, its own wall geometry, and a support test that asks only whether gravity can be
// balanced by non-negative normal forces (DESIGN.md section 3), not how the grain got there.
#include "btr/check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>

namespace btr {
namespace {

constexpr double kSupportResidual = 1e-6;  // |sum f_k n_k - e_z| accepted as balanced
constexpr std::size_t kMaxExamples = 10;

struct Range {
  std::uint32_t begin = 0, end = 0;
};

// Hashed uniform grid over a subset of the grains: sorted by cell, a hash map from cell key to the
// range of its grains. Cells are at least `reach` wide, so every grain within reach of a point is in
// the 3x3x3 block of cells around it. Periodic axes have a whole number of cells per period and
// wrap their indices.
class CellGrid {
 public:
  CellGrid(const Grains& grains, const std::vector<std::uint32_t>& members, int dimension,
           const Container& c, double reach) {
    periodic_[0] = c.kind == ContainerKind::Periodic;
    periodic_[1] = periodic_[0] && dimension == 3;
    period_[0] = c.size_x;
    period_[1] = c.size_y;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::uint32_t i : members)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], grains[i].x[a]);
        hi[a] = std::max(hi[a], grains[i].x[a]);
      }
    // Keep every axis within 2^20 cells so that a key packs into 63 bits.
    const double max_cells = double(1 << 20) - 8;
    cell_ = reach;
    for (int a = 0; a < 3; ++a)
      if (hi[a] > lo[a]) cell_ = std::max(cell_, (hi[a] - lo[a]) / max_cells);
    for (int a = 0; a < 3; ++a) {
      origin_[a] = std::isfinite(lo[a]) ? lo[a] : 0.0;
      size_[a] = std::isfinite(lo[a]) ? std::int64_t(std::floor((hi[a] - lo[a]) / cell_)) + 1 : 1;
      width_[a] = cell_;
    }
    for (int a = 0; a < 2; ++a)
      if (periodic_[a]) {
        size_[a] = std::max<std::int64_t>(1, std::int64_t(std::floor(period_[a] / cell_)));
        width_[a] = period_[a] / size_[a];
        origin_[a] = -0.5 * period_[a];
      }

    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
    keyed.reserve(members.size());
    for (std::uint32_t i : members) {
      const Index c3 = index(grains[i].x);
      keyed.emplace_back(key(c3), i);
    }
    std::sort(keyed.begin(), keyed.end());
    order_.resize(keyed.size());
    cells_.reserve(keyed.size());
    for (std::size_t k = 0; k < keyed.size(); ++k) {
      order_[k] = keyed[k].second;
      Range& r = cells_[keyed[k].first];
      if (r.end == 0) r.begin = std::uint32_t(k);
      r.end = std::uint32_t(k + 1);
    }
  }

  // Calls f(j) once for every grain j in the 3x3x3 block of cells around position p.
  template <class F>
  void for_each_near(const Vec3& p, F&& f) const {
    const Index c = index(p);
    std::int64_t cand[3][3];
    int count[3];
    for (int a = 0; a < 3; ++a) count[a] = neighbours(a, c[a], cand[a]);
    for (int i = 0; i < count[0]; ++i)
      for (int j = 0; j < count[1]; ++j)
        for (int k = 0; k < count[2]; ++k) {
          auto it = cells_.find(key({cand[0][i], cand[1][j], cand[2][k]}));
          if (it == cells_.end()) continue;
          for (std::uint32_t m = it->second.begin; m < it->second.end; ++m) f(order_[m]);
        }
  }

 private:
  using Index = std::array<std::int64_t, 3>;

  // Cell index of p along each axis; off-grid positions give -2 or size + 1 (no grains there, and
  // no grains in their neighbours either, except the edge cells).
  Index index(const Vec3& p) const {
    Index c;
    for (int a = 0; a < 3; ++a) {
      double v = p[a];
      if (a < 2 && periodic_[a]) v -= period_[a] * std::floor((v - origin_[a]) / period_[a]);
      const double t = std::floor((v - origin_[a]) / width_[a]);
      c[a] = t < -1 ? -2 : t > double(size_[a]) ? size_[a] + 1 : std::int64_t(t);
      if (a < 2 && periodic_[a]) c[a] = std::clamp<std::int64_t>(c[a], 0, size_[a] - 1);
    }
    return c;
  }

  // In-grid neighbours of cell i along one axis, without duplicates when a period holds fewer than
  // three cells.
  int neighbours(int axis, std::int64_t i, std::int64_t out[3]) const {
    const bool periodic = axis < 2 && periodic_[axis];
    const std::int64_t n = size_[axis];
    int count = 0;
    for (std::int64_t d = -1; d <= 1; ++d) {
      std::int64_t j = i + d;
      if (periodic) j = ((j % n) + n) % n;
      else if (j < 0 || j >= n) continue;
      bool seen = false;
      for (int k = 0; k < count; ++k) seen = seen || out[k] == j;
      if (!seen) out[count++] = j;
    }
    return count;
  }

  static std::uint64_t key(const Index& c) {
    return (std::uint64_t(c[0]) << 42) | (std::uint64_t(c[1]) << 21) | std::uint64_t(c[2]);
  }

  bool periodic_[2] = {false, false};
  double period_[2] = {0, 0};
  double cell_ = 0, origin_[3] = {0, 0, 0}, width_[3] = {0, 0, 0};
  std::int64_t size_[3] = {1, 1, 1};
  std::vector<std::uint32_t> order_;
  std::unordered_map<std::uint64_t, Range> cells_;
};

// Does e_z lie in the cone of the unit normals (non-negative forces balance the weight)?
// By Caratheodory a balancing set needs at most `dimension` normals, so enumerating the subsets of
// size 1..dimension solves the small non-negative least-squares problem exactly.
bool balanced(std::vector<Vec3>& normals, int dimension) {
  // Upward normals first: the balancing subset is usually found among the first few.
  std::sort(normals.begin(), normals.end(), [](const Vec3& a, const Vec3& b) { return a.z() > b.z(); });
  const std::size_t n = normals.size();
  const Vec3 ez(0, 0, 1);
  const double tol2 = kSupportResidual * kSupportResidual;
  for (std::size_t i = 0; i < n; ++i)
    if (normals[i].z() > 0 && 1.0 - normals[i].z() * normals[i].z() < tol2) return true;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec3 &a = normals[i], &b = normals[j];
      const double c = a.dot(b), det = 1.0 - c * c;
      if (det < 1e-14) continue;  // parallel pair: covered by the single normals
      const double fa = (a.z() - c * b.z()) / det, fb = (b.z() - c * a.z()) / det;
      if (fa < 0 || fb < 0) continue;
      if ((fa * a + fb * b - ez).squaredNorm() < tol2) return true;
    }
  if (dimension < 3) return false;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      for (std::size_t k = j + 1; k < n; ++k) {
        const Vec3 jk = normals[j].cross(normals[k]);
        const double det = normals[i].dot(jk);
        if (std::abs(det) < 1e-14) continue;  // coplanar: covered by the pairs
        // Cramer's rule for [n_i n_j n_k] f = e_z.
        const Vec3 f(jk.z(), normals[k].cross(normals[i]).z(), normals[i].cross(normals[j]).z());
        if ((f / det).minCoeff() >= 0) return true;
      }
  return false;
}

// A wall the grain may touch: its signed gap (negative = penetration) and the unit normal pointing
// from the wall into the container.
struct WallContact {
  double gap;
  Vec3 normal;
};

// Every lateral wall of the container, as seen by a grain at p of radius r.
std::vector<WallContact> walls_of(const Container& c, int dimension, const Vec3& p, double r) {
  std::vector<WallContact> w;
  auto pair_of_planes = [&](int axis, double half) {
    Vec3 n = Vec3::Zero();
    n[axis] = -1;
    w.push_back({half - p[axis] - r, n});
    n[axis] = 1;
    w.push_back({p[axis] + half - r, n});
  };
  switch (c.kind) {
    case ContainerKind::Open:
    case ContainerKind::Periodic:
      break;
    case ContainerKind::Box:
      pair_of_planes(0, 0.5 * c.size_x);
      if (dimension == 3) pair_of_planes(1, 0.5 * c.size_y);
      break;
    case ContainerKind::HeleShaw:
      pair_of_planes(0, 0.5 * c.size_x);
      pair_of_planes(1, 0.5 * c.gap);
      break;
    case ContainerKind::Cylinder: {
      const double rho = std::hypot(p.x(), p.y());
      const Vec3 n = rho > 0 ? Vec3(-p.x() / rho, -p.y() / rho, 0) : Vec3(1, 0, 0);
      w.push_back({c.radius - rho - r, n});
      break;
    }
  }
  return w;
}

}  // namespace

CheckReport check_packing(const Grains& grains, int dimension, const Container& container,
                          double overlap_tol, double contact_tol) {
  CheckReport rep;
  const std::size_t n = grains.size();
  auto note = [&](std::size_t i) {
    const std::int64_t id = std::int64_t(i) + 1;
    if (rep.examples.size() < kMaxExamples &&
        std::find(rep.examples.begin(), rep.examples.end(), id) == rep.examples.end())
      rep.examples.push_back(id);
  };

  // Grains with non-finite data, a non-positive radius, or y != 0 in 2D are outside by definition
  // and take no further part.
  std::vector<char> valid(n, 1);
  double r_max = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Grain& g = grains[i];
    if (!g.x.allFinite() || !std::isfinite(g.r) || g.r <= 0 || (dimension == 2 && g.x.y() != 0)) {
      valid[i] = 0;
      ++rep.outside;
      note(i);
      continue;
    }
    r_max = std::max(r_max, g.r);
  }
  if (r_max == 0) return rep;

  const bool px = container.kind == ContainerKind::Periodic;
  const bool py = px && dimension == 3;
  auto min_image = [&](Vec3 d) {
    if (px) d.x() -= container.size_x * std::nearbyint(d.x() / container.size_x);
    if (py) d.y() -= container.size_y * std::nearbyint(d.y() / container.size_y);
    return d;
  };

  // Size levels: level L holds radii in (r_max / 2^(L+1), r_max / 2^L], in a grid whose cells are
  // one largest diameter of that level wide. A pair is examined once, by the grain of the higher
  // level (the smaller grain), which searches its own level and every level of larger grains; the
  // reach r_i + r_j is then at most the larger level's cell. This keeps wide size distributions
  // linear: a small grain never scans cells sized for the largest grains.
  constexpr int kLevels = 40;
  std::vector<int> level(n, 0);
  std::vector<std::vector<std::uint32_t>> members(kLevels);
  std::vector<double> level_r(kLevels, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const int l = std::min(kLevels - 1, int(std::floor(std::log2(r_max / grains[i].r))));
    level[i] = std::max(0, l);
    members[level[i]].push_back(std::uint32_t(i));
    level_r[level[i]] = std::max(level_r[level[i]], grains[i].r);
  }
  std::vector<std::unique_ptr<CellGrid>> grids(kLevels);
  for (int l = 0; l < kLevels; ++l)
    if (!members[l].empty())
      grids[l] = std::make_unique<CellGrid>(grains, members[l], dimension, container,
                                            2 * level_r[l] * (1 + 2 * contact_tol) * (1 + 1e-12));

  // Grain pairs in contact (or overlapping), each once.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const Grain& gi = grains[i];
    for (int l = 0; l <= level[i]; ++l) {
      if (!grids[l]) continue;
      grids[l]->for_each_near(gi.x, [&](std::uint32_t j) {
        if (l == level[i] && j <= i) return;
        const Grain& gj = grains[j];
        const double dist = min_image(gi.x - gj.x).norm();
        const double rmin = std::min(gi.r, gj.r);
        const double gap = dist - (gi.r + gj.r);
        const double pen = -gap / rmin;
        rep.max_overlap = std::max(rep.max_overlap, pen);
        if (pen > overlap_tol) {
          ++rep.overlaps;
          note(std::min<std::size_t>(i, j));
          note(std::max<std::size_t>(i, j));
        }
        if (gap < contact_tol * rmin) pairs.emplace_back(std::uint32_t(i), j);
      });
    }
  }
  // Partners of every grain, in compressed rows.
  std::vector<std::uint32_t> start(n + 1, 0), partner(2 * pairs.size());
  for (const auto& p : pairs) ++start[p.first + 1], ++start[p.second + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const auto& p : pairs) partner[fill[p.first]++] = p.second, partner[fill[p.second]++] = p.first;
  }

  std::vector<Vec3> normals;
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const Grain& gi = grains[i];
    normals.clear();
    bool outside = false;

    // Floor and walls.
    const double floor_gap = gi.x.z() - gi.r;
    std::vector<WallContact> walls = walls_of(container, dimension, gi.x, gi.r);
    walls.push_back({floor_gap, Vec3(0, 0, 1)});
    for (const WallContact& w : walls) {
      const double pen = -w.gap / gi.r;
      rep.max_overlap = std::max(rep.max_overlap, pen);
      if (pen > overlap_tol) {
        ++rep.overlaps;
        outside = true;
      }
      if (w.gap < contact_tol * gi.r) normals.push_back(w.normal);
    }
    const bool on_floor = floor_gap < contact_tol * gi.r;
    if (px && std::abs(gi.x.x()) > 0.5 * container.size_x + overlap_tol * gi.r) outside = true;
    if (py && std::abs(gi.x.y()) > 0.5 * container.size_y + overlap_tol * gi.r) outside = true;
    if (outside) {
      ++rep.outside;
      note(i);
    }

    // Normals point from the partner to this grain's centre.
    for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) {
      const Vec3 d = min_image(gi.x - grains[partner[k]].x);
      const double dist = d.norm();
      if (dist > 0) normals.push_back(d / dist);
    }
    if (!on_floor && !balanced(normals, dimension)) {
      ++rep.unsupported;
      note(i);
    }
  }
  return rep;
}

}  // namespace btr
