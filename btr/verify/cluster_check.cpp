#include "btr/verify/cluster_check.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>

#include "btr/model/cluster.h"
#include "btr/verify/check.h"
#include "btr/verify/cluster_unwrap.h"

namespace btr {
namespace {

struct Touch {
  std::size_t grain;
  Vec3 normal;  // from the partner towards the grain
};

// Walls as (normal into the container, the wall's position along it) for a grain at x of radius r:
// returns the gaps and normals of the walls.
void wall_touches(const Grain& g, std::size_t i, int dimension, const Container& c, double overlap_tol,
                  double contact_tol, ClusterCheckReport& report, std::vector<std::vector<Touch>>& per_grain) {
  auto plane = [&](const Vec3& n, double dist) {  // dist = distance of the centre from the wall
    const double gap = dist - g.r;
    if (gap < -overlap_tol * g.r) {
      ++report.overlaps;
      report.max_overlap = std::max(report.max_overlap, -gap / g.r);
    }
    if (gap <= contact_tol * g.r) per_grain[i].push_back({i, n});
  };
  plane(Vec3::UnitZ(), g.x.z());
  const double hx = 0.5 * c.size_x, hy = 0.5 * (c.kind == ContainerKind::HeleShaw ? c.gap : c.size_y);
  if (c.kind == ContainerKind::Box || c.kind == ContainerKind::HeleShaw) {
    plane(Vec3::UnitX(), g.x.x() + hx);
    plane(-Vec3::UnitX(), hx - g.x.x());
    if (dimension == 3) {
      plane(Vec3::UnitY(), g.x.y() + hy);
      plane(-Vec3::UnitY(), hy - g.x.y());
    }
  }
  if (c.kind == ContainerKind::Cylinder) {
    const double rho = std::hypot(g.x.x(), g.x.y());
    if (rho > 0.0) plane(Vec3(-g.x.x() / rho, -g.x.y() / rho, 0.0), c.radius - rho);
  }
}

// Is e_z (the weight, carried) a non-negative combination of the wrench columns? Up to 14 contacts:
// enumerates the subsets of at most d columns with least squares. More: accelerated projected gradient
// (FISTA) on |A x - b|^2 over x >= 0 (enumeration would take too long).
bool carried(const std::vector<Eigen::VectorXd>& wrenches, int d) {
  const int k = static_cast<int>(wrenches.size());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(d);
  b(d == 6 ? 2 : 1) = 1.0;
  constexpr double kResidual = 1e-6;
  if (k > 14) {
    Eigen::MatrixXd A(d, k);
    for (int i = 0; i < k; ++i) A.col(i) = wrenches[i];
    const double L = (A.transpose() * A).eigenvalues().real().maxCoeff();
    Eigen::VectorXd x = Eigen::VectorXd::Zero(k), y = x, prev = x;
    double t = 1.0;
    for (int it = 0; it < 200000; ++it) {
      prev = x;
      x = (y - A.transpose() * (A * y - b) / L).cwiseMax(0.0);
      if ((A * x - b).norm() <= kResidual) return true;
      const double t_next = 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * t * t));
      y = x + ((t - 1.0) / t_next) * (x - prev);
      t = t_next;
    }
    return false;
  }
  std::vector<int> pick;
  bool found = false;
  // All subsets of size 1..d.
  std::function<void(int)> rec = [&](int start) {
    if (found) return;
    if (!pick.empty()) {
      Eigen::MatrixXd A(d, static_cast<Eigen::Index>(pick.size()));
      for (std::size_t a = 0; a < pick.size(); ++a) A.col(a) = wrenches[pick[a]];
      const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
      if ((A * x - b).norm() <= kResidual && x.minCoeff() >= -1e-9) { found = true; return; }
    }
    if (static_cast<int>(pick.size()) == d) return;
    for (int i = start; i < k && !found; ++i) {
      pick.push_back(i);
      rec(i + 1);
      pick.pop_back();
    }
  };
  rec(0);
  return found;
}

}  // namespace

ClusterCheckReport check_clusters(const Grains& grains, int dimension, const Container& c, double overlap_tol,
                                  double contact_tol) {
  ClusterCheckReport report;
  const auto bodies = rigid_bodies(grains);
  report.bodies = static_cast<std::int64_t>(bodies.size());
  std::vector<std::size_t> body_of(grains.size());
  for (std::size_t b = 0; b < bodies.size(); ++b)
    for (std::size_t i : bodies[b]) body_of[i] = b;

  std::vector<std::vector<Touch>> touches(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i)
    wall_touches(grains[i], i, dimension, c, overlap_tol, contact_tol, report, touches);

  // Pairs of grains of different bodies, at the minimum image.
  const MinimumImage image(c, dimension);
  const double r_max = max_radius(grains);
  const double reach = r_max * (2.0 + contact_tol) * (1.0 + 1e-12);
  std::vector<Vec3> x(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) x[i] = grains[i].x;
  for_each_pair_within(x, reach, image, [&](std::size_t i, std::size_t j, const Vec3& dx) {
    if (body_of[i] == body_of[j]) return;
    const double rmin = std::min(grains[i].r, grains[j].r);
    const double gap = dx.norm() - grains[i].r - grains[j].r;
    if (gap < -overlap_tol * rmin) {
      ++report.overlaps;
      report.max_overlap = std::max(report.max_overlap, -gap / rmin);
    }
    if (gap <= contact_tol * rmin) {
      touches[i].push_back({i, dx.normalized()});
      touches[j].push_back({j, -dx.normalized()});
    }
  });

  const int d = dimension == 3 ? 6 : 3;
  // Centres of mass and lever arms of bodies made one piece again: members are wrapped into the cell one
  // by one in a packing. The unwrapping is geometry shared with the DEM export, not placement code.
  const std::vector<Vec3> at = unwrap_clusters(grains, dimension, c);
  for (const auto& body : bodies) {
    Vec3 G = Vec3::Zero();
    double m = 0.0, L = 0.0;
    for (std::size_t i : body) {
      const double mi = std::pow(grains[i].r, dimension);
      G += mi * at[i];
      m += mi;
      L += grains[i].r;
    }
    G /= m;
    L /= static_cast<double>(body.size());
    std::vector<Eigen::VectorXd> wrenches;
    for (std::size_t i : body)
      for (const Touch& t : touches[i]) {
        const Vec3 torque = (at[i] - G).cross(t.normal) / L;
        Eigen::VectorXd w(d);
        if (d == 6) w << t.normal, torque;
        else w << t.normal.x(), t.normal.z(), torque.y();
        wrenches.push_back(w);
      }
    if (!carried(wrenches, d)) {
      ++report.unsupported;
      if (report.examples.size() < 10) report.examples.push_back(static_cast<std::int64_t>(body.front()) + 1);
    }
  }
  return report;
}

}  // namespace btr
