#include "btr/measures/force_network.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>

#include "btr/placement/neighbour_grid.h"
#include "btr/placement/obstacle.h"
#include "btr/placement/walls.h"

namespace btr {
namespace {

// Subsets of at most this many supports are tried (a grain rarely touches more lower grains).
constexpr std::size_t kMaxSupports = 16;

struct Support {
  std::int64_t j;
  Vec3 n;      // unit normal, from the partner into the grain
  Vec3 shift;  // periodic image shift of a grain partner
};

struct Split {
  std::vector<double> lambda;  // per support, >= 0
  Vec3 residual = Vec3::Zero();
  bool singular = false;       // a subset of `dimension` supports was singular and skipped
};

// Non-negative normal forces lambda_k with sum lambda_k n_k = -load: the first subset (by size, then
// by index) that balances the load exactly; if none does, the subset leaving the smallest residual.
Split split_load(const std::vector<Support>& s, const Vec3& load, int dimension, double residual_tol) {
  const std::size_t m = std::min(s.size(), kMaxSupports);
  Split best;
  best.lambda.assign(s.size(), 0.0);
  best.residual = load;
  const double scale = load.norm();
  if (scale == 0.0) return best;
  const std::size_t max_size = std::min<std::size_t>(m, static_cast<std::size_t>(dimension));
  std::vector<int> idx;
  for (std::size_t size = 1; size <= max_size; ++size) {
    // enumerate subsets of `size` indices in lexicographic order
    idx.resize(size);
    for (std::size_t a = 0; a < size; ++a) idx[a] = static_cast<int>(a);
    while (true) {
      Eigen::Matrix3d gram = Eigen::Matrix3d::Identity();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      for (std::size_t a = 0; a < size; ++a) {
        for (std::size_t b = 0; b < size; ++b) gram(a, b) = s[idx[a]].n.dot(s[idx[b]].n);
        rhs(a) = -s[idx[a]].n.dot(load);
      }
      bool ok = true;
      Eigen::Vector3d l = Eigen::Vector3d::Zero();
      if (size == 1) {
        l(0) = rhs(0);
      } else if (size == 2) {
        const Eigen::Matrix2d g2 = gram.topLeftCorner<2, 2>();
        if (g2.determinant() < 1e-10) ok = false, best.singular |= dimension == 2;  // collinear
        else l.head<2>() = g2.inverse() * rhs.head<2>();
      } else {
        if (gram.determinant() < 1e-10) ok = false, best.singular = true;  // coplanar: the pairs cover it
        else l = gram.inverse() * rhs;
      }
      if (ok) {
        Vec3 res = load;
        for (std::size_t a = 0; a < size; ++a) {
          if (l(a) < 0.0) ok = false;
          res += l(a) * s[idx[a]].n;
        }
        if (ok && res.norm() < best.residual.norm()) {
          best.lambda.assign(s.size(), 0.0);
          for (std::size_t a = 0; a < size; ++a) best.lambda[idx[a]] = l(a);
          best.residual = res;
          if (res.norm() <= residual_tol * scale) return best;
        }
      }
      // next combination
      int a = static_cast<int>(size) - 1;
      while (a >= 0 && idx[a] == static_cast<int>(m - size + a)) --a;
      if (a < 0) break;
      ++idx[a];
      for (std::size_t b = a + 1; b < size; ++b) idx[b] = idx[b - 1] + 1;
    }
  }
  return best;
}

}  // namespace

ForceNetwork static_forces(const Grains& grains, int dimension, const Container& container,
                           const std::vector<double>& weights, double contact_tol, double residual_tol) {
  if (dimension != 2 && dimension != 3) throw ForceNetworkError("dimension must be 2 or 3");
  if (weights.size() != grains.size())
    throw ForceNetworkError("force network: " + std::to_string(weights.size()) + " weights for " +
                            std::to_string(grains.size()) + " grains");
  ForceNetwork net;
  if (grains.empty()) return net;
  double r_max = 0.0;
  for (std::size_t i = 0; i < grains.size(); ++i) {
    if (!(weights[i] > 0.0) || !std::isfinite(weights[i]))
      throw ForceNetworkError("force network: grain " + std::to_string(i + 1) + " has weight " +
                              std::to_string(weights[i]) + " N (expected a positive number)");
    r_max = std::max(r_max, grains[i].r);
    net.total_weight += weights[i];
  }
  NeighbourGrid grid(dimension, container, r_max);
  for (std::size_t i = 0; i < grains.size(); ++i) grid.insert(static_cast<std::int32_t>(i), grains[i].x, grains[i].r);

  std::vector<Vec3> load(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) load[i] = Vec3(0.0, 0.0, -weights[i]);
  std::vector<std::vector<ContactForce>> per_grain(grains.size());
  std::vector<Obstacle> walls;
  std::vector<Support> supports;
  for (std::size_t ii = grains.size(); ii-- > 0;) {
    const Grain& g = grains[ii];
    const auto id = static_cast<std::int64_t>(ii) + 1;
    supports.clear();
    container_walls(container, dimension, g.r, walls);
    for (std::size_t k = 0; k < walls.size(); ++k)
      if (walls[k].gap(g.x) < contact_tol * g.r)
        supports.push_back({-static_cast<std::int64_t>(k), walls[k].normal(g.x), Vec3::Zero()});
    const std::size_t n_walls = supports.size();
    const Vec3 reach = Vec3::Constant((g.r + r_max) * (1.0 + 2.0 * contact_tol));
    grid.visit_box(g.x - reach, g.x + reach, [&](std::int32_t j, const Vec3& c, double radius, int) {
      if (static_cast<std::size_t>(j) >= ii) return;
      const Vec3 d = g.x - c;
      const double dist = d.norm();
      if (dist - (g.r + radius) >= contact_tol * std::min(g.r, radius) || dist == 0.0) return;
      supports.push_back({static_cast<std::int64_t>(j) + 1, d / dist, c - grains[j].x});
    });
    // Deterministic order of the grain supports whatever the grid's visiting order.
    std::sort(supports.begin() + static_cast<std::ptrdiff_t>(n_walls), supports.end(),
              [](const Support& a, const Support& b) {
                if (a.j != b.j) return a.j < b.j;
                for (int k = 0; k < 3; ++k)
                  if (a.shift[k] != b.shift[k]) return a.shift[k] < b.shift[k];
                return false;
              });
    // The vertical part of the load is split (BTR's placement made sure the supports carry a vertical
    // weight with non-negative forces); the lateral part pushed in by the grains above is left to
    // friction and measured.
    const Vec3 vertical(0.0, 0.0, load[ii].z());
    // Supports below the grain's equator push the grain beneath upwards; use them only if the
    // supports above it cannot carry the load.
    Split split;
    {
      std::vector<Support> upper;
      std::vector<std::size_t> where;
      for (std::size_t k = 0; k < supports.size(); ++k)
        if (supports[k].n.z() > 0.0) upper.push_back(supports[k]), where.push_back(k);
      if (upper.size() < supports.size()) {
        const Split u = split_load(upper, vertical, dimension, residual_tol);
        if (u.residual.norm() <= residual_tol * vertical.norm()) {
          split.lambda.assign(supports.size(), 0.0);
          for (std::size_t k = 0; k < where.size(); ++k) split.lambda[where[k]] = u.lambda[k];
          split.residual = u.residual;
          split.singular = u.singular;
        }
      }
      if (split.lambda.empty()) split = split_load(supports, vertical, dimension, residual_tol);
      if (!(load[ii].z() < 0.0)) split = Split{std::vector<double>(supports.size(), 0.0), Vec3::Zero()};
    }
    if (!(load[ii].z() < 0.0)) {
      ++net.lifted_grains;
      net.lifted_force += load[ii].z();
    } else if (split.residual.norm() > residual_tol * vertical.norm()) {
      net.unbalanced.push_back({id, split.residual, vertical.norm()});
    }
    if (split.singular) ++net.singular_grains;
    const double lateral = std::hypot(load[ii].x(), load[ii].y());
    if (lateral > 0.0) {
      ++net.lateral_grains;
      net.largest_lateral = std::max(net.largest_lateral, lateral / weights[ii]);
    }
    for (std::size_t k = 0; k < supports.size(); ++k) {
      const Support& s = supports[k];
      const Vec3 f = split.lambda[k] * s.n;
      per_grain[ii].push_back({id, s.j, f, s.shift});
      if (s.j > 0) load[static_cast<std::size_t>(s.j - 1)] -= f;
      else net.container_force += f;
    }
  }
  for (auto& list : per_grain) {
    // the floor (0), the walls (-1, -2, ...), then the grains by id
    auto rank = [](std::int64_t j) { return j <= 0 ? std::make_pair(0, -j) : std::make_pair(1, j); };
    std::stable_sort(list.begin(), list.end(),
                     [&](const ContactForce& a, const ContactForce& b) { return rank(a.j) < rank(b.j); });
    for (ContactForce& c : list) net.contacts.push_back(c);
  }
  std::reverse(net.unbalanced.begin(), net.unbalanced.end());
  return net;
}

}  // namespace btr
