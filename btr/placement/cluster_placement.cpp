// A rigid cluster falls straight down until one member touches, then moves by steepest descent of
// its centre of mass: each step projects gravity onto the rigid-body motions (translation and
// rotation, 6 degrees of freedom in 3D, 3 in 2D) that do not push any member into a contact, and
// moves along that projection, members rolling and sliding over the fixed grains, floor and walls.
// It rests when gravity's generalised force lies in the cone of the contacts' wrenches (normal
// forces through the members' centres, as for a single grain: the generalisation of the 3-support
// test to force and torque balance). Steps are bounded by conservative advancement (no member can
// reach an obstacle it is not touching), loaded contacts are kept closed by a Newton projection (at
// rest, where it does not converge, by Newton steps that also keep every other gap >= 0), and
// a step that does not lower the centre of mass is halved; when the step becomes negligible the
// cluster rests (a smooth minimum or a wedge), so no degenerate case loops. An event budget per
// cluster ends the rest with an error naming the cluster.
#include "btr/placement/cluster_placement.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "btr/placement/deposition.h"
#include "btr/placement/nnls.h"
#include "btr/placement/obstacle.h"
#include "btr/placement/walls.h"

namespace btr {
namespace {

using VecX = Eigen::VectorXd;

// Obstacles nearer than this (times the smallest member radius) count as contacts of the descent: a
// contact that a grazing motion approaches only slowly is taken as closed (a loaded one is then closed
// exactly by the Newton projection) instead of being approached in ever shorter steps.
constexpr double kContactTol = 1e-6;
using MatX = Eigen::MatrixXd;

struct Contact {
  int member;
  Obstacle o;
  double gap;
};

class Placer {
 public:
  Placer(ClusterEngine& e, const ClusterDrop& drop, std::int32_t number)
      : e_(e), shape_(drop.shape), q_(drop.orientation.normalized()), number_(number) {
    const std::size_t n = shape_.size();
    r_min_ = std::numeric_limits<double>::infinity();
    double mass = 0.0, inertia = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double r = shape_.radii[k], m = std::pow(r, e.dimension);
      r_min_ = std::min(r_min_, r);
      mass += m;
      inertia += m * (shape_.offsets[k].squaredNorm() + (e.dimension == 3 ? 0.4 : 0.5) * r * r);
      walls_.emplace_back();
      container_walls(e.container, e.dimension, r, walls_.back());
    }
    rho_ = std::sqrt(inertia / mass);
    dof_ = e.dimension == 3 ? std::vector<int>{0, 1, 2, 3, 4, 5} : std::vector<int>{0, 2, 4};
    h_max_ = 0.25 * r_min_;
    margin_ = 2.0 * h_max_;
  }

  void run(const ClusterDrop& drop);
  // Adds the members at rest to the engine's grains and grid.
  void commit() {
    for (std::size_t k = 0; k < shape_.size(); ++k) {
      Vec3 x = wrap_into_cell(e_.container, e_.dimension, member(k));
      if (e_.dimension == 2) x.y() = 0.0;
      Grain g{x, shape_.radii[k], shape_.species[k]};
      g.cluster = number_;
      e_.grains.push_back(g);
      e_.grid.insert(static_cast<std::int32_t>(e_.grains.size() - 1), x, g.r);
      e_.top = std::max(e_.top, x.z() + g.r);
    }
    e_.clusters = number_;
  }

 private:
  Vec3 member(std::size_t k) const { return G_ + q_ * shape_.offsets[k]; }
  // The largest displacement of a member since the cluster was at (G0, q0).
  double moved_from(const Vec3& G0, const Eigen::Quaterniond& q0) const {
    double d = 0.0;
    for (std::size_t k = 0; k < shape_.size(); ++k) d = std::max(d, (member(k) - (G0 + q0 * shape_.offsets[k])).norm());
    return d;
  }
  [[noreturn]] void fail(const std::string& why) const {
    std::ostringstream s;
    s << "cluster " << number_ << " (" << shape_.size() << " grains, centre of mass at (" << G_.x() << ", "
      << G_.y() << ", " << G_.z() << ")): " << why;
    throw PlacementError(static_cast<std::int64_t>(e_.grains.size()) + 1, s.str());
  }
  double weight(int d) const { return d < 3 ? 1.0 : rho_; }  // metric: sqrt of the mass matrix's diagonal
  void gather(double margin);
  void fall();
  // Reduced, scaled Jacobian row of a contact: d gap / d u' for the motion u = M^-1/2 u'.
  Eigen::RowVectorXd row(const Contact& c) const {
    const Vec3 p = member(c.member), n = c.o.normal(p);
    const Vec3 t = (p - G_).cross(n);
    double full[6] = {n.x(), n.y(), n.z(), t.x(), t.y(), t.z()};
    Eigen::RowVectorXd r(dof_.size());
    for (std::size_t a = 0; a < dof_.size(); ++a) r(a) = full[dof_[a]] / weight(dof_[a]);
    return r;
  }
  void move(const VecX& u_scaled, double s) {
    Vec3 v = Vec3::Zero(), w = Vec3::Zero();
    for (std::size_t a = 0; a < dof_.size(); ++a) {
      const double c = u_scaled(a) * s / weight(dof_[a]);
      if (dof_[a] < 3) v[dof_[a]] = c; else w[dof_[a] - 3] = c;
    }
    G_ += v;
    const double angle = w.norm();
    if (angle > 0.0) q_ = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle)) * q_).normalized();
  }
  bool project(const std::vector<std::int64_t>& loaded);
  bool settle(const std::vector<std::int64_t>& loaded);
  void rest_projection(const std::vector<std::int64_t>& loaded);
  static std::int64_t key(const Contact& c) { return c.o.key * (std::int64_t(1) << 20) + c.member; }
  static bool is_loaded(const Contact& c, const std::vector<std::int64_t>& loaded) {
    return std::find(loaded.begin(), loaded.end(), key(c)) != loaded.end();
  }
  // Projection of gravity (-e_z on the centre of mass) onto the allowed motions at the current
  // state, in the metric of the mass matrix: u' = a + C^T lambda, lambda >= 0 (non-negative least
  // squares). Returns the loaded contacts' keys (key()).
  std::vector<std::int64_t> descend(VecX& u) {
    refresh_gaps();
    const double contact_tol = kContactTol * r_min_;
    std::vector<const Contact*> active;
    for (const Contact& c : cand_)
      if (c.gap <= contact_tol) active.push_back(&c);
    const Eigen::Index d = static_cast<Eigen::Index>(dof_.size());
    MatX Ct(d, static_cast<Eigen::Index>(active.size()));
    for (std::size_t i = 0; i < active.size(); ++i) Ct.col(i) = row(*active[i]).transpose();
    VecX a = VecX::Zero(d);
    a(e_.dimension == 3 ? 2 : 1) = -1.0;
    const VecX lambda = active.empty() ? VecX() : nnls(Ct, -a);
    u = active.empty() ? a : VecX(a + Ct * lambda);
    std::vector<std::int64_t> loaded;
    for (std::size_t i = 0; i < active.size(); ++i)
      if (lambda(i) > 1e-12) loaded.push_back(key(*active[i]));
    return loaded;
  }
  bool lifts_off(const std::vector<std::int64_t>& before) {
    VecX u;
    const std::vector<std::int64_t> now = descend(u);
    for (std::int64_t k : before)
      if (std::find(now.begin(), now.end(), k) == now.end()) return true;
    return false;
  }
  void refresh_gaps() {
    for (Contact& c : cand_) c.gap = c.o.gap(member(c.member));
  }

  ClusterEngine& e_;
  const ClusterShape& shape_;
  Eigen::Quaterniond q_;
  Vec3 G_ = Vec3::Zero();
  std::int32_t number_;
  double r_min_, rho_, h_max_;
  // Obstacles within margin_ of a member are its candidates: a step moves a member at most h_max_
  // (plus its projection), so the overlap test after a step sees every obstacle the step can reach;
  // a step whose projection went further (a diverging Newton) is refused.
  double margin_;
  std::vector<int> dof_;
  std::vector<std::vector<Obstacle>> walls_;  // per member radius
  std::vector<Contact> cand_;                 // obstacles within reach of a member
};

void Placer::gather(double margin) {
  cand_.clear();
  for (std::size_t k = 0; k < shape_.size(); ++k) {
    const Vec3 p = member(k);
    const double r = shape_.radii[k];
    for (const Obstacle& w : walls_[k]) cand_.push_back({static_cast<int>(k), w, w.gap(p)});
    const Vec3 reach = Vec3::Constant(r + e_.r_max + margin);
    e_.grid.visit_box(p - reach, p + reach, [&](std::int32_t i, const Vec3& c, double radius, int image) {
      Obstacle o;
      o.kind = Obstacle::Kind::Sphere;
      o.key = sphere_key(i, image);
      o.c = c;
      o.R = r + radius;
      const double gap = o.gap(p);
      if (gap <= margin) cand_.push_back({static_cast<int>(k), o, gap});
    });
  }
}

// Straight down to the first touch of any member (the fall of one grain, taken over the members).
void Placer::fall() {
  double t = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < shape_.size(); ++k) {
    const Vec3 x = member(k);
    const double r = shape_.radii[k], reach = r + e_.r_max;
    t = std::min(t, x.z() - r);  // the floor
    e_.grid.visit_column_down(
        x.x(), x.y(), reach, x.z() + reach, [&](double layer_top) { return layer_top + reach > x.z() - t; },
        [&](std::int32_t, const Vec3& c, double radius, int) {
          const double R = r + radius, dx = x.x() - c.x(), dy = x.y() - c.y();
          const double s = R * R - dx * dx - dy * dy;
          if (s <= 1e-12 * R * R) return;
          const double z_hit = c.z() + std::sqrt(s);
          if (z_hit <= x.z() + 1e-12 * r) t = std::min(t, x.z() - z_hit);
        });
  }
  G_.z() -= std::max(0.0, t);
}

// Newton steps closing the loaded contacts and opening any overlap the curved step made. Returns
// whether it converged: every loaded contact closed and no obstacle entered, to 1e-13 r.
bool Placer::project(const std::vector<std::int64_t>& loaded) {
  const double tol = 1e-13 * r_min_;
  const Eigen::Index d = static_cast<Eigen::Index>(dof_.size());
  for (int iter = 0; iter < 8; ++iter) {
    refresh_gaps();
    std::vector<const Contact*> set;
    double worst = 0.0;
    for (const Contact& c : cand_)
      if (is_loaded(c, loaded) || c.gap < 0.0) {
        set.push_back(&c);
        worst = std::max(worst, std::abs(c.gap));
      }
    if (worst <= tol) return true;
    MatX J(static_cast<Eigen::Index>(set.size()), d);
    VecX g(static_cast<Eigen::Index>(set.size()));
    for (std::size_t a = 0; a < set.size(); ++a) {
      J.row(a) = row(*set[a]);
      g(a) = set[a]->gap;
    }
    move(J.completeOrthogonalDecomposition().solve(-g), 1.0);
  }
  return false;
}

// The projection above solves "loaded and overlapping contacts closed" as equations. Where two
// obstacles take turns (closing a member's overlap with a wall pushes it into a neighbour, which the
// next step pushes back: a grain in a corner) it alternates and stops with a member inside one of
// them, up to ~1e-7 r in 3D. These Newton steps keep the loaded contacts as equations and every other
// gap >= 0 as inequalities, each step the shortest such move (least-distance programming), so they
// cannot alternate. Returns whether they converged to 1e-13 r.
bool Placer::settle(const std::vector<std::int64_t>& loaded) {
  const double tol = 1e-13 * r_min_;
  const Eigen::Index d = static_cast<Eigen::Index>(dof_.size());
  for (int iter = 0; iter < 16; ++iter) {
    refresh_gaps();
    std::vector<const Contact*> eq, ineq;
    double worst = 0.0;
    for (const Contact& c : cand_) {
      const bool on = is_loaded(c, loaded);
      (on ? eq : ineq).push_back(&c);
      worst = std::max(worst, on ? std::abs(c.gap) : -c.gap);
    }
    if (worst <= tol) return true;
    // Loaded contacts: u = u_p + N z, u_p their minimum-norm closing move, N their null space.
    VecX u_p = VecX::Zero(d);
    MatX N = MatX::Identity(d, d);
    if (!eq.empty()) {
      MatX J(static_cast<Eigen::Index>(eq.size()), d);
      VecX g(static_cast<Eigen::Index>(eq.size()));
      for (std::size_t a = 0; a < eq.size(); ++a) {
        J.row(a) = row(*eq[a]);
        g(a) = eq[a]->gap;
      }
      const Eigen::JacobiSVD<MatX> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
      u_p = svd.solve(-g);
      N = svd.matrixV().rightCols(d - svd.rank());
    }
    MatX G(static_cast<Eigen::Index>(ineq.size()), N.cols());
    VecX h(static_cast<Eigen::Index>(ineq.size()));
    for (std::size_t a = 0; a < ineq.size(); ++a) {
      const Eigen::RowVectorXd J = row(*ineq[a]);
      G.row(a) = J * N;
      h(a) = -ineq[a]->gap - J.dot(u_p);
    }
    const std::optional<VecX> z = least_distance(G, h);
    if (!z) return false;  // the loaded contacts cannot stay closed without entering another obstacle
    move(u_p + N * *z, 1.0);
  }
  return false;
}

// At rest the loaded contacts (gaps within kContactTol) are closed exactly and no member may be left
// inside an obstacle (the check allows 1e-9 r). A back-off out of a residual overlap would open the
// loaded contacts by as much (~1e-7 r: the check's contact tolerance), so instead, where the plain
// projection does not converge, the constrained steps start again from the position before it. The
// plain projection stays first so that every rest position it reached before is unchanged. A result
// is taken only if no member moved as far as the candidates' margin; otherwise the cluster rests where
// the descent stopped (no overlap beyond the step's 1e-10 r, contacts within kContactTol), by rule.
void Placer::rest_projection(const std::vector<std::int64_t>& loaded) {
  const Vec3 G0 = G_;
  const Eigen::Quaterniond q0 = q_;
  if (project(loaded) && moved_from(G0, q0) < margin_) return;
  G_ = G0;
  q_ = q0;
  if (settle(loaded) && moved_from(G0, q0) < margin_) return;
  G_ = G0;
  q_ = q0;
}

void Placer::run(const ClusterDrop& drop) {
  const std::size_t n = shape_.size();
  if (n == 0) fail("no grains");
  if (e_.container.kind == ContainerKind::Drum) fail("clusters are not placed in a drum (no rule for its curved wall)");
  for (std::size_t k = 0; k < n; ++k) {
    if (!(shape_.radii[k] > 0.0) || shape_.radii[k] > e_.r_max * (1.0 + 1e-12)) {
      std::ostringstream why;
      why << "member " << k + 1 << ": radius " << shape_.radii[k] << " is not in (0, r_max = " << e_.r_max << "]";
      fail(why.str());
    }
    if (e_.dimension == 2 && std::abs(shape_.offsets[k].y()) > 1e-12 * shape_.radii[k]) fail("a 2D cluster has a member off y = 0");
  }
  if (e_.dimension == 2 && (q_ * Vec3::UnitY() - Vec3::UnitY()).norm() > 1e-12)
    fail("a 2D cluster's orientation must be a rotation about the y axis");
  G_ = Vec3(drop.x, e_.dimension == 3 ? drop.y : 0.0, 0.0);
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) lowest = std::min(lowest, (q_ * shape_.offsets[k]).z() - shape_.radii[k]);
  G_.z() = e_.top + 2.0 * e_.r_max - lowest;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 p = member(k);
    std::string misfit = drop_misfit(e_.container, e_.dimension, p.x(), p.y(), shape_.radii[k]);
    if (!misfit.empty()) fail("dropped outside the container: member " + std::to_string(k + 1) + ": " + misfit);
  }

  const double contact_tol = kContactTol * r_min_;
  const long budget = 20L * e_.max_events;
  double h = h_max_;
  bool rest = false;
  double z_window = std::numeric_limits<double>::infinity();  // G's height at the start of a window of steps
  for (long step = 0; step < budget && !rest; ++step) {
    // Creeping: the centre of mass went down less than 1e-10 r in 500 steps (a wedge the steps cannot
    // resolve, each step cut short by a contact about to close): at rest, by rule.
    if (step % 500 == 0) {
      if (z_window - G_.z() < 1e-10 * r_min_) { rest = true; break; }
      z_window = G_.z();
    }
    gather(margin_);
    bool touching = false;
    for (const Contact& c : cand_) touching |= c.gap <= contact_tol;
    if (!touching) {
      fall();
      continue;
    }
    VecX u;
    const std::vector<std::int64_t> loaded = descend(u);
    if (u.norm() <= 1e-9) {
      rest_projection(loaded);
      rest = true;
      break;
    }

    // Step length s along u: members move at most h (and the cluster turns at most 0.1 rad), and no
    // member reaches an obstacle it does not touch (conservative advancement).
    Vec3 v = Vec3::Zero(), w = Vec3::Zero();
    for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(dof_.size()); ++k) {
      const double c = u(k) / weight(dof_[k]);
      if (dof_[k] < 3) v[dof_[k]] = c; else w[dof_[k] - 3] = c;
    }
    std::vector<double> speed(n);
    double fastest = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      speed[k] = v.norm() + w.norm() * (member(k) - G_).norm();
      fastest = std::max(fastest, speed[k]);
    }
    double s = h / fastest;
    if (w.norm() > 0.0) s = std::min(s, 0.1 / w.norm());
    std::vector<double> gap0;
    double s_safe = s;
    for (const Contact& c : cand_) {
      gap0.push_back(c.gap);
      if (c.gap > contact_tol) s_safe = std::min(s_safe, c.gap / speed[c.member]);
    }

    const Vec3 G0 = G_;
    const Eigen::Quaterniond q0 = q_;
    // Does the step of length t bring a member into an obstacle it did not touch?
    auto enters = [&](double t) {
      G_ = G0;
      q_ = q0;
      move(u, t);
      refresh_gaps();
      for (std::size_t i = 0; i < cand_.size(); ++i)
        if (gap0[i] > contact_tol && cand_[i].gap < 0.0) return true;
      return false;
    };
    // Conservative advancement gives the step no member can close a gap in; when that is shorter than
    // the full step (a gap passed at a grazing angle), try the full step and, if it enters an
    // obstacle, bisect to the first touch instead of creeping along in ever shorter safe steps.
    if (s_safe < s && enters(s)) {
      double lo = s_safe, hi = s;
      for (int it = 0; it < 60 && (hi - lo) * fastest > 1e-3 * contact_tol; ++it) {
        const double mid = 0.5 * (lo + hi);
        (enters(mid) ? hi : lo) = mid;
      }
      s = lo;
    }
    G_ = G0;
    q_ = q0;
    move(u, s);
    project(loaded);
    // A support that unloads within the step: go back to just past the point where it does (to a
    // member displacement of 1e-10 r), so the path leaves it where the single-grain engine does.
    const bool lifted = lifts_off(loaded);
    if (lifted) {
      double lo = 0.0, hi = s;
      while ((hi - lo) * fastest > 1e-10 * r_min_) {
        const double mid = 0.5 * (lo + hi);
        G_ = G0;
        q_ = q0;
        move(u, mid);
        project(loaded);
        (lifts_off(loaded) ? hi : lo) = mid;
      }
      G_ = G0;
      q_ = q0;
      move(u, hi);
      project(loaded);
    }
    // A step after which the projection leaves a member inside an obstacle (closing the loaded contacts
    // and opening the others is inconsistent there) or took it beyond the candidates' margin (it
    // diverged) is refused like one that does not go down. A step cut short where a support unloads
    // counts as going down if it does not go up: over ~1e-10 r the descent is below the resolution of
    // z when gravity is almost balanced, and refusing it would end the descent by the halving rule
    // with the old supports, short of balance (a cluster the check found unsupported).
    bool overlapping = !(moved_from(G0, q0) < margin_);
    refresh_gaps();
    for (const Contact& c : cand_) overlapping |= c.gap < -1e-10 * r_min_;
    const bool lower = G_.z() < G0.z() || (lifted && G_.z() <= G0.z());
    if (overlapping || !lower) {
      G_ = G0;
      q_ = q0;
      h *= 0.5;
      if (h < 1e-9 * r_min_) rest = true;  // no step lowers the centre of mass: a minimum, by rule
      continue;
    }
    h = std::min(h_max_, 2.0 * h);
  }
  if (!rest) {
    std::ostringstream why;
    why << "no stable position after " << budget << " steps";
    fail(why.str());
  }
}

}  // namespace

std::int32_t place_rigid_cluster(ClusterEngine& e, const ClusterDrop& drop) {
  const std::int32_t number = e.clusters + 1;
  Placer placer(e, drop, number);
  placer.run(drop);
  placer.commit();
  return number;
}

}  // namespace btr
