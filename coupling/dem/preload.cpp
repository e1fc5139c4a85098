#include "coupling/dem/preload.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "btr/placement/obstacle.h"
#include "btr/placement/walls.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/timestep.h"

namespace btr {

namespace {

// A grain whose vertical load is not carried beyond this fraction cannot be pre-loaded.
constexpr double kVerticalResidual = 1e-6;
constexpr int kNewtonIterations = 30;
// Weight of the pull towards the grain's column (preload_packing), relative to a contact's.
constexpr double kRegularisation = 0.1;
// A fit further than this many times the grain's deepest overlap from its column is not used.
constexpr double kFallback = 4.0;

const Component& component_of(const Scene& scene, const Grain& g) {
  return scene.grains.components[component_index(scene, g.species)];
}

}  // namespace

ForceNetwork packing_forces(const Grains& grains, const Scene& scene) {
  std::vector<double> w = grain_masses(grains, scene);
  for (double& m : w) m *= kGravity;
  return static_forces(grains, scene.dimension, scene.container, w);
}

ContactLaw::ContactLaw(const Grains& grains, const Scene& scene) : grains_(grains), scene_(scene) {
  if (scene.relax.model == "hooke") hooke_velocity_ = hooke_characteristic_velocity(grains);
}

double ContactLaw::overlap(std::int64_t i, std::int64_t j, double force) const {
  if (!(force > 0.0)) return 0.0;
  const Grain& a = grains_[static_cast<std::size_t>(i - 1)];
  const Component& ca = component_of(scene_, a);
  const double ma = grain_mass(a.r, ca.density);
  double r_eff = a.r, m_eff = ma, y_eff = 0.0;
  const Material* partner = &wall_material(scene_);
  if (j > 0) {
    const Grain& b = grains_[static_cast<std::size_t>(j - 1)];
    const Component& cb = component_of(scene_, b);
    const double mb = grain_mass(b.r, cb.density);
    r_eff = a.r * b.r / (a.r + b.r);
    m_eff = ma * mb / (ma + mb);
    partner = &cb.material;
  }
  y_eff = effective_young(ca.material, *partner);
  if (scene_.relax.model == "hooke-stiffness")  // a wall contact takes the grain's own kn (liggghts_script.cpp)
    return force / pair_material(ca.material, j > 0 ? *partner : ca.material).kn;
  if (scene_.relax.model == "hooke") return force / hooke_stiffness(r_eff, m_eff, y_eff, hooke_velocity_);
  return std::pow(3.0 * force / (4.0 * y_eff * std::sqrt(r_eff)), 2.0 / 3.0);
}

double law_overlap(const Grains& grains, const Scene& scene, std::int64_t i, std::int64_t j, double force) {
  return ContactLaw(grains, scene).overlap(i, j, force);
}

StaticOverlap predict_static_overlap(const Grains& grains, const Scene& scene) {
  if (grains.empty()) throw std::runtime_error("the packing has no grains");
  StaticOverlap out;
  out.law = scene.relax.model;
  const std::vector<double> m = grain_masses(grains, scene);
  std::vector<std::size_t> floor;
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < grains.size(); ++i) {
    out.total_weight += m[i] * kGravity;
    lowest = std::min(lowest, grains[i].x.z() - grains[i].r);
    if (grains[i].x.z() - grains[i].r <= kFloorContact * grains[i].r) floor.push_back(i);
  }
  if (floor.empty())
    for (std::size_t i = 0; i < grains.size(); ++i)
      if (grains[i].x.z() - grains[i].r <= lowest + kFloorContact * grains[i].r) floor.push_back(i);
  out.floor_grains = static_cast<std::int64_t>(floor.size());
  out.column_force = out.total_weight / static_cast<double>(floor.size());
  const ContactLaw law(grains, scene);
  auto add = [&](StaticOverlap::Load& load, double delta, double r) {
    load.mean_relative += delta / r;
    load.mean_depth += delta;
    load.largest_relative = std::max(load.largest_relative, delta / r);
  };
  for (std::size_t i : floor) {
    const std::int64_t id = static_cast<std::int64_t>(i) + 1;
    add(out.single, law.overlap(id, 0, m[i] * kGravity), grains[i].r);
    add(out.column, law.overlap(id, 0, out.column_force), grains[i].r);
  }
  for (StaticOverlap::Load* load : {&out.single, &out.column}) {
    load->mean_relative /= static_cast<double>(floor.size());
    load->mean_depth /= static_cast<double>(floor.size());
  }
  return out;
}

Preloaded preload_packing(const Grains& grains, const Scene& scene) {
  Preloaded out;
  out.forces = packing_forces(grains, scene);
  for (const UnbalancedGrain& u : out.forces.unbalanced)
    if (std::abs(u.residual.z()) > kVerticalResidual * u.load)
      throw std::runtime_error("pre-load: grain " + std::to_string(u.id) + " is not carried by its supports: " +
                               std::to_string(u.residual.z()) + " N of its " + std::to_string(u.load) +
                               " N load is left vertically (a grain held from above or floating; is this a BTR "
                               "packing?)");
  const int dim = scene.dimension;
  const Container& c = scene.container;
  out.grains = grains;
  Grains& moved = out.grains;

  // Contacts are sorted by i: walk them grain by grain, in id order.
  const auto& contacts = out.forces.contacts;
  const ContactLaw law(grains, scene);
  std::vector<double> delta(contacts.size());
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactForce& cf = contacts[k];
    delta[k] = law.overlap(cf.i, cf.j, cf.f.norm());
    const auto key = cf.j > 0 ? std::make_pair(cf.j, cf.i) : std::make_pair(cf.i, cf.j);
    double& d = out.intended[key];
    d = std::max(d, delta[k]);  // two periodic images of one pair: keep the larger
    const double r = cf.j > 0 ? std::min(grains[cf.i - 1].r, grains[cf.j - 1].r) : grains[cf.i - 1].r;
    if (delta[k] / r > out.largest_relative) out.largest_relative = delta[k] / r, out.largest_depth = delta[k];
  }

  // Grain i (supports first: id order) is moved to x minimising
  //   sum_k (gap_k(x) + delta_k)^2 + mu^2 |x - x_col|^2,   x_col = x_i - (mean_j s_j + mean_k delta_k) e_z
  // over its loaded contacts k (gap_k to the already moved partner, or to the floor/wall), s_j the
  // partners' downward moves: Gauss-Newton with Levenberg-Marquardt regularisation (mu = kRegularisation).
  // With three well-spread supports the contacts fix x and the overlaps match the law to within a few
  // percent of mu^2; a grain wedged between supports at nearly its own height (normals almost
  // horizontal, an ill-conditioned fit) would instead be pushed by delta / n_z ~ ten times its overlap,
  // up and sideways into neighbours that are not its contacts (measured without mu: moves of 0.07 r for
  // 1e-3 r overlaps, hundreds of new overlaps): mu keeps it near its column, such a contact starts with
  // less than its overlap and the engine finishes it. Steps are limited to the deepest overlap, and a
  // fit that ends further than kFallback overlaps from the column is replaced by the column move
  // (counted in column_fallbacks). A lowered grain with fewer supports than the
  // dimension keeps its position along the free directions (the regularisation holds it).
  std::vector<double> sink(moved.size(), 0.0);
  std::vector<Vec3> unwrapped(moved.size());  // moved centres before wrapping into the period
  std::vector<Obstacle> walls, obstacles;
  std::vector<double> targets;
  std::size_t k = 0;
  double misfit_sq = 0.0;
  std::size_t misfit_count = 0;
  const int cols = dim;
  auto to_vec = [&](const Eigen::VectorXd& v) { return dim == 3 ? Vec3(v(0), v(1), v(2)) : Vec3(v(0), 0.0, v(1)); };
  auto from_vec = [&](const Vec3& v) {
    Eigen::VectorXd e(cols);
    if (dim == 3) e << v.x(), v.y(), v.z();
    else e << v.x(), v.z();
    return e;
  };
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const std::int64_t id = static_cast<std::int64_t>(i) + 1;
    obstacles.clear();
    targets.clear();
    container_walls(c, dim, grains[i].r, walls);
    double mean_partner = 0.0, mean_delta = 0.0;
    int partners = 0;
    for (; k < contacts.size() && contacts[k].i == id; ++k) {
      const ContactForce& cf = contacts[k];
      if (cf.j > 0) {
        const std::size_t j = static_cast<std::size_t>(cf.j - 1);
        mean_partner += sink[j];
        ++partners;
        if (!(cf.f.norm() > 0.0)) continue;
        Obstacle o;
        o.kind = Obstacle::Kind::Sphere;
        o.c = unwrapped[j] + cf.shift;
        o.R = grains[i].r + grains[j].r;
        obstacles.push_back(o);
      } else {
        ++partners;
        if (!(cf.f.norm() > 0.0)) continue;
        obstacles.push_back(walls[static_cast<std::size_t>(-cf.j)]);
      }
      targets.push_back(delta[k]);
      mean_delta += delta[k];
    }
    if (!targets.empty()) mean_delta /= static_cast<double>(targets.size());
    const double column = (partners ? mean_partner / partners : 0.0) + mean_delta;
    const Vec3 x_col = grains[i].x - Vec3(0.0, 0.0, column);
    Vec3 x = x_col;
    const int m = static_cast<int>(obstacles.size());
    Eigen::MatrixXd J(m, cols);
    Eigen::VectorXd g(m);
    const double mu2 = kRegularisation * kRegularisation;
    const double deepest = m > 0 ? *std::max_element(targets.begin(), targets.end()) : 0.0;
    const double trust = deepest + 1e-9 * grains[i].r;
    for (int it = 0; it < kNewtonIterations && m > 0; ++it) {
      for (int a = 0; a < m; ++a) {
        g(a) = obstacles[a].gap(x) + targets[a];
        J.row(a) = from_vec(obstacles[a].normal(x)).transpose();
      }
      const Eigen::MatrixXd A = J.transpose() * J + mu2 * Eigen::MatrixXd::Identity(cols, cols);
      const Eigen::VectorXd b = -(J.transpose() * g + mu2 * from_vec(x - x_col));
      Vec3 step = to_vec(A.ldlt().solve(b));
      if (step.norm() > trust) step *= trust / step.norm();  // Gauss-Newton overshoots on wedged grains
      x += step;
      if (step.norm() < 1e-14 * grains[i].r) break;
    }
    if ((x - x_col).norm() > kFallback * deepest) {  // no good fit near the column: sink with it
      x = x_col;
      ++out.column_fallbacks;
    }
    for (int a = 0; a < m; ++a) {
      const double e = obstacles[a].gap(x) + targets[a];
      misfit_sq += e * e, ++misfit_count;
      out.largest_misfit = std::max(out.largest_misfit, std::abs(e) / grains[i].r);
    }
    sink[i] = grains[i].x.z() - x.z();
    out.largest_move = std::max(out.largest_move, (x - grains[i].x).norm());
    unwrapped[i] = x;
    if (c.kind == ContainerKind::Periodic) {
      x.x() -= c.size_x * std::floor(x.x() / c.size_x + 0.5);
      if (dim == 3) x.y() -= c.size_y * std::floor(x.y() / c.size_y + 0.5);
    }
    moved[i].x = x;
  }
  out.rms_misfit = misfit_count ? std::sqrt(misfit_sq / static_cast<double>(misfit_count)) : 0.0;
  return out;
}

}  // namespace btr
