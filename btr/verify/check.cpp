// Self-check of a packing. Deliberately shares no code with the placement engine: its own
// neighbour grid, its own wall geometry, and a support test that asks only whether gravity can be
// balanced by non-negative normal forces (docs/design.md section 3), not how the grain got there.
#include "btr/verify/check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
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

// A copy of one grain's data, stored contiguously in grid order.
struct Entry {
  Vec3 x;
  double r;
  std::uint32_t id;  // index into the packing
};

// Hashed grid of vertical columns over a subset of the grains: entries sorted by column, then by z;
// a hash map from column to its range of entries. Columns are at least `reach` wide, so every
// grain within reach of a point is in the 3x3 block of columns around it, within reach in z.
// Periodic axes have a whole number of columns per period and wrap their indices.
class ColumnGrid {
 public:
  ColumnGrid(const Grains& grains, const std::vector<std::uint32_t>& members, int dimension,
             const Container& c, double reach)
      : reach_(reach) {
    period_[0] = c.size_x;
    period_[1] = c.size_y;
    periodic_[0] = wraps_x(c) && std::isfinite(c.size_x) && c.size_x > 0;
    periodic_[1] = wraps_y(c, dimension) && std::isfinite(c.size_y) && c.size_y > 0;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (std::uint32_t i : members)
      for (int a = 0; a < 2; ++a) {
        lo[a] = std::min(lo[a], grains[i].x[a]);
        hi[a] = std::max(hi[a], grains[i].x[a]);
      }
    // Keep both axes within 2^31 columns so that a key packs into 64 bits.
    double width = reach;
    for (int a = 0; a < 2; ++a)
      if (hi[a] > lo[a]) width = std::max(width, (hi[a] - lo[a]) / double(1u << 30));
    for (int a = 0; a < 2; ++a) {
      origin_[a] = std::isfinite(lo[a]) ? lo[a] : 0.0;
      size_[a] = std::isfinite(lo[a]) ? std::int64_t(std::floor((hi[a] - lo[a]) / width)) + 1 : 1;
      width_[a] = width;
      if (periodic_[a]) {
        size_[a] = std::max<std::int64_t>(1, std::int64_t(std::floor(period_[a] / width)));
        width_[a] = period_[a] / size_[a];
        origin_[a] = -0.5 * period_[a];
      }
    }

    struct Keyed {
      std::uint64_t key;
      double z;
      std::uint32_t id;
    };
    std::vector<Keyed> keyed;
    keyed.reserve(members.size());
    for (std::uint32_t i : members) keyed.push_back({key(column(grains[i].x)), grains[i].x.z(), i});
    std::sort(keyed.begin(), keyed.end(), [](const Keyed& p, const Keyed& q) {
      return p.key != q.key ? p.key < q.key : p.z < q.z;
    });
    entries_.resize(keyed.size());
    columns_.reserve(keyed.size());
    for (std::size_t k = 0; k < keyed.size(); ++k) {
      const Grain& g = grains[keyed[k].id];
      entries_[k] = {g.x, g.r, keyed[k].id};
      Range& r = columns_[keyed[k].key];
      if (r.end == 0) r.begin = std::uint32_t(k);
      r.end = std::uint32_t(k + 1);
    }
  }

  // The grains of this grid, in grid order (neighbours in space are mostly neighbours here).
  const std::vector<Entry>& entries() const { return entries_; }

  // Calls f(entry) once for every grain of the 3x3 columns around p whose z is within `reach` of
  // p's (reach at most the column width).
  template <class F>
  void for_each_near(const Vec3& p, double reach, F&& f) const {
    const Column c = column(p);
    std::int64_t cand[2][3];
    int count[2];
    for (int a = 0; a < 2; ++a) count[a] = neighbours(a, c[a], cand[a]);
    reach = std::min(reach, reach_);
    const double z_lo = p.z() - reach, z_hi = p.z() + reach;
    for (int i = 0; i < count[0]; ++i)
      for (int j = 0; j < count[1]; ++j) {
        auto it = columns_.find(key({cand[0][i], cand[1][j]}));
        if (it == columns_.end()) continue;
        const Entry* first = entries_.data() + it->second.begin;
        const Entry* last = entries_.data() + it->second.end;
        first = std::lower_bound(first, last, z_lo, [](const Entry& e, double z) { return e.x.z() < z; });
        for (; first != last && first->x.z() <= z_hi; ++first) f(*first);
      }
  }

 private:
  using Column = std::array<std::int64_t, 2>;

  // Column of p along x and y; off-grid positions give -2 or size + 1 (empty, as are their
  // neighbours except the edge columns).
  Column column(const Vec3& p) const {
    Column c;
    for (int a = 0; a < 2; ++a) {
      double v = p[a];
      if (periodic_[a]) v -= period_[a] * std::floor((v - origin_[a]) / period_[a]);
      const double t = std::floor((v - origin_[a]) / width_[a]);
      c[a] = t < -1 ? -2 : t > double(size_[a]) ? size_[a] + 1 : std::int64_t(t);
      if (periodic_[a]) c[a] = std::clamp<std::int64_t>(c[a], 0, size_[a] - 1);
    }
    return c;
  }

  // In-grid neighbours of column index i along one axis, without duplicates when a period holds
  // fewer than three columns.
  int neighbours(int axis, std::int64_t i, std::int64_t out[3]) const {
    const std::int64_t n = size_[axis];
    int count = 0;
    for (std::int64_t d = -1; d <= 1; ++d) {
      std::int64_t j = i + d;
      if (periodic_[axis]) j = ((j % n) + n) % n;
      else if (j < 0 || j >= n) continue;
      bool seen = false;
      for (int k = 0; k < count; ++k) seen = seen || out[k] == j;
      if (!seen) out[count++] = j;
    }
    return count;
  }

  static std::uint64_t key(const Column& c) { return (std::uint64_t(c[0]) << 32) | std::uint64_t(c[1]); }

  double reach_;
  bool periodic_[2] = {false, false};
  double period_[2] = {0, 0};
  double origin_[2] = {0, 0}, width_[2] = {0, 0};
  std::int64_t size_[2] = {1, 1};
  std::vector<Entry> entries_;
  std::unordered_map<std::uint64_t, Range> columns_;
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

struct Walls {
  WallContact w[5];
  int n = 0;
  void push_back(const WallContact& c) { w[n++] = c; }
  const WallContact* begin() const { return w; }
  const WallContact* end() const { return w + n; }
};

// The floor and every lateral wall of the container, as seen by a grain at p of radius r.
Walls walls_of(const Container& c, int dimension, const Vec3& p, double r) {
  Walls w;
  w.push_back({p.z() - r, Vec3(0, 0, 1)});
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
    case ContainerKind::Mesh:  // the triangles are judged apart (MeshJudge)
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
    case ContainerKind::Drum: {
      // Axis along y at height z = radius; the gap is measured to the circle of the drum's section.
      if (dimension == 3 && !c.periodic_ends) pair_of_planes(1, 0.5 * c.size_y);
      const double dx = p.x(), dz = p.z() - c.radius, rho = std::hypot(dx, dz);
      const Vec3 n = rho > 0 ? Vec3(-dx / rho, 0, -dz / rho) : Vec3(0, 0, 1);
      w.push_back({c.radius - rho - r, n});
      break;
    }
  }
  return w;
}

// A mesh container's triangles, judged with geometry of the check's own (not the placement's): the
// nearest point of a triangle by projection onto its plane and, outside it, onto its three sides; inside
// or outside by counting the triangles a ray from the centre crosses, the ray tilted off the vertical so
// that it passes beside the shared edges and vertices of a symmetric mesh.
class MeshJudge {
 public:
  explicit MeshJudge(const TriangleMesh& m) : m_(m) {
    for (const auto& f : m.triangles) {
      const Vec3 &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
      lo_.push_back(a.cwiseMin(b).cwiseMin(c));
      hi_.push_back(a.cwiseMax(b).cwiseMax(c));
    }
  }
  std::size_t size() const { return m_.triangles.size(); }
  bool near(std::size_t t, const Vec3& p, double reach) const {
    return ((p.array() + reach) >= lo_[t].array()).all() && ((p.array() - reach) <= hi_[t].array()).all();
  }
  Vec3 nearest(std::size_t t, const Vec3& p) const {
    const auto& f = m_.triangles[t];
    const Vec3 &a = m_.vertices[f[0]], &b = m_.vertices[f[1]], &c = m_.vertices[f[2]];
    const Vec3 n = (b - a).cross(c - a);
    const Vec3 q = p - n * (n.dot(p - a) / n.squaredNorm());
    // q inside: on the inner side of every edge.
    const bool in = n.dot((b - a).cross(q - a)) >= 0 && n.dot((c - b).cross(q - b)) >= 0 && n.dot((a - c).cross(q - c)) >= 0;
    if (in) return q;
    auto on_segment = [&](const Vec3& u, const Vec3& v) {
      const double s = std::clamp((p - u).dot(v - u) / (v - u).squaredNorm(), 0.0, 1.0);
      return Vec3(u + s * (v - u));
    };
    Vec3 best = on_segment(a, b);
    for (const Vec3& cand : {on_segment(b, c), on_segment(c, a)})
      if ((p - cand).squaredNorm() < (p - best).squaredNorm()) best = cand;
    return best;
  }
  // Triangles crossed by the ray from p going down (tilted by about 1e-6 rad): odd is inside.
  int crossings_below(const Vec3& p) const {
    const Vec3 dir = Vec3(0.7071067811865476e-6, 0.5773502691896258e-6, -1.0).normalized();
    int count = 0;
    for (std::size_t t = 0; t < size(); ++t) {
      if (lo_[t].z() > p.z()) continue;  // the ray goes down
      const double drift = 1e-6 * (p.z() - lo_[t].z()) + 1e-12 * (1.0 + std::abs(p.x()) + std::abs(p.y()));
      if (p.x() < lo_[t].x() - drift || p.x() > hi_[t].x() + drift || p.y() < lo_[t].y() - drift ||
          p.y() > hi_[t].y() + drift)
        continue;
      const auto& f = m_.triangles[t];
      const Vec3 &a = m_.vertices[f[0]], &b = m_.vertices[f[1]], &c = m_.vertices[f[2]];
      // Moller-Trumbore
      const Vec3 e1 = b - a, e2 = c - a, h = dir.cross(e2);
      const double det = e1.dot(h);
      if (std::abs(det) < 1e-300) continue;
      const Vec3 s = p - a;
      const double u = s.dot(h) / det;
      if (u < 0.0 || u > 1.0) continue;
      const Vec3 q = s.cross(e1);
      const double v = dir.dot(q) / det;
      if (v < 0.0 || u + v > 1.0) continue;
      if (e2.dot(q) / det > 0.0) ++count;
    }
    return count;
  }

 private:
  const TriangleMesh& m_;
  std::vector<Vec3> lo_, hi_;
};

}  // namespace

MinimumImage::MinimumImage(const Container& c, int dimension)
    : px(wraps_x(c) && std::isfinite(c.size_x) && c.size_x > 0),
      py(wraps_y(c, dimension) && std::isfinite(c.size_y) && c.size_y > 0),
      lx(c.size_x),
      ly(c.size_y) {}

Vec3 MinimumImage::operator()(Vec3 d) const {
  // Not container.h's minimum_image: the self-check shares no geometry code with what it checks.
  auto wrap = [](double& v, double period) {
    if (std::abs(v) <= 0.5 * period) return;
    if (std::abs(v) <= 1.5 * period) v -= v > 0 ? period : -period;
    else v -= period * std::nearbyint(v / period);
  };
  if (px) wrap(d.x(), lx);
  if (py) wrap(d.y(), ly);
  return d;
}

void for_each_pair_within(const std::vector<Vec3>& x, double reach, const MinimumImage& image,
                          const std::function<void(std::size_t, std::size_t, const Vec3&)>& f) {
  const std::size_t n = x.size();
  std::vector<double> xs(n);
  for (std::size_t i = 0; i < n; ++i) xs[i] = image(x[i]).x();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return xs[a] < xs[b]; });
  auto pair = [&](std::size_t i, std::size_t j) {
    const Vec3 d = image(x[i] - x[j]);
    if (d.norm() <= reach) f(i, j, d);
  };
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      if (xs[order[b]] - xs[order[a]] > reach) break;
      pair(order[a], order[b]);
    }
  if (image.px)  // the pairs the sweep left out: farther than reach apart in the cell, close across x = +-L/2
    for (std::size_t a = 0; a < n && xs[order[a]] < -0.5 * image.lx + reach; ++a)
      for (std::size_t b = n - 1; b > a && xs[order[b]] > 0.5 * image.lx - reach; --b)
        if (xs[order[b]] - xs[order[a]] > reach) pair(order[a], order[b]);
}

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

  const MinimumImage min_image(container, dimension);
  const bool px = min_image.px, py = min_image.py;

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
  std::vector<std::unique_ptr<ColumnGrid>> grids(kLevels);
  for (int l = 0; l < kLevels; ++l)
    if (!members[l].empty())
      grids[l] = std::make_unique<ColumnGrid>(grains, members[l], dimension, container,
                                              2 * level_r[l] * (1 + 2 * contact_tol) * (1 + 1e-12));

  // Grain pairs in contact (or overlapping), each once. Grains are visited in grid order so that
  // consecutive searches touch the same memory.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(4 * n);
  for (int li = 0; li < kLevels; ++li) {
    if (!grids[li]) continue;
    for (const Entry& ei : grids[li]->entries()) {
      const std::uint32_t i = ei.id;
      for (int l = 0; l <= li; ++l) {
        if (!grids[l]) continue;
        const double reach = (ei.r + level_r[l]) * (1 + 2 * contact_tol) * (1 + 1e-12);
        grids[l]->for_each_near(ei.x, reach, [&](const Entry& ej) {
          const std::uint32_t j = ej.id;
          if (l == li && j <= i) return;
          const double dist = min_image(ei.x - ej.x).norm();
          const double rmin = std::min(ei.r, ej.r);
          const double gap = dist - (ei.r + ej.r);
          const double pen = -gap / rmin;
          if (pen > rep.max_overlap) rep.max_overlap = pen;
          if (gap < contact_tol * rmin) {
            pairs.emplace_back(i, j);
            if (pen > overlap_tol) {
              ++rep.overlaps;
              note(std::min(i, j));
              note(std::max(i, j));
            }
          }
        });
      }
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
  const bool mesh = container.kind == ContainerKind::Mesh && container.mesh;
  std::unique_ptr<MeshJudge> judge;
  if (mesh) judge = std::make_unique<MeshJudge>(*container.mesh);
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const Grain& gi = grains[i];
    normals.clear();
    bool outside = false;

    if (mesh) {
      // No floor: the triangles are the container (an open outlet has nothing under it).
      for (std::size_t t = 0; t < judge->size(); ++t) {
        if (!judge->near(t, gi.x, gi.r * (1 + 2 * contact_tol))) continue;
        const Vec3 d = gi.x - judge->nearest(t, gi.x);
        const double gap = d.norm() - gi.r, pen = -gap / gi.r;
        rep.max_overlap = std::max(rep.max_overlap, pen);
        if (pen > overlap_tol) {
          ++rep.overlaps;
          outside = true;
        }
        if (gap < contact_tol * gi.r && d.norm() > 0) normals.push_back(d / d.norm());
      }
      if (judge->crossings_below(gi.x) % 2 == 0) outside = true;
      if (outside) {
        ++rep.outside;
        note(i);
      }
      for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) {
        const Vec3 d = gi.x - grains[partner[k]].x;
        if (d.norm() > 0) normals.push_back(d / d.norm());
      }
      if (!balanced(normals, dimension)) {
        ++rep.unsupported;
        note(i);
      }
      continue;
    }

    // Floor and walls.
    const double floor_gap = gi.x.z() - gi.r;
    for (const WallContact& w : walls_of(container, dimension, gi.x, gi.r)) {
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
