#include "coupling/preload.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "btr/obstacle.h"
#include "btr/walls.h"
#include "coupling/materials.h"
#include "coupling/timestep.h"

namespace btr {

namespace {

// A grain whose vertical load is not carried beyond this fraction cannot be pre-loaded.
constexpr double kVerticalResidual = 1e-6;
constexpr int kNewtonIterations = 30;

const Component& component_of(const Scene& scene, const Grain& g) {
  return scene.grains.components[component_index(scene, g.species)];
}

}  // namespace

ForceNetwork packing_forces(const Grains& grains, const Scene& scene) {
  std::vector<double> w = grain_masses(grains, scene);
  for (double& m : w) m *= kGravity;
  return static_forces(grains, scene.dimension, scene.container, w);
}

double law_overlap(const Grains& grains, const Scene& scene, std::int64_t i, std::int64_t j, double force) {
  if (!(force > 0.0)) return 0.0;
  const Grain& a = grains[static_cast<std::size_t>(i - 1)];
  const Component& ca = component_of(scene, a);
  const double ma = grain_mass(a.r, ca.density);
  double r_eff = a.r, m_eff = ma, y_eff = 0.0;
  if (j > 0) {
    const Grain& b = grains[static_cast<std::size_t>(j - 1)];
    const Component& cb = component_of(scene, b);
    const double mb = grain_mass(b.r, cb.density);
    r_eff = a.r * b.r / (a.r + b.r);
    m_eff = ma * mb / (ma + mb);
    y_eff = effective_young(ca.material, cb.material);
  } else {
    y_eff = effective_young(ca.material, wall_material(scene));
  }
  if (scene.relax.model == "hooke")
    return force / hooke_stiffness(r_eff, m_eff, y_eff, hooke_characteristic_velocity(grains));
  return std::pow(3.0 * force / (4.0 * y_eff * std::sqrt(r_eff)), 2.0 / 3.0);
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
  std::vector<double> delta(contacts.size());
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const ContactForce& cf = contacts[k];
    delta[k] = law_overlap(grains, scene, cf.i, cf.j, cf.f.norm());
    const auto key = cf.j > 0 ? std::make_pair(cf.j, cf.i) : std::make_pair(cf.i, cf.j);
    double& d = out.intended[key];
    d = std::max(d, delta[k]);  // two periodic images of one pair: keep the larger
    const double r = cf.j > 0 ? std::min(grains[cf.i - 1].r, grains[cf.j - 1].r) : grains[cf.i - 1].r;
    if (delta[k] / r > out.largest_relative) out.largest_relative = delta[k] / r, out.largest_depth = delta[k];
  }

  std::vector<Obstacle> walls;
  std::vector<Obstacle> obstacles;
  std::vector<double> targets;
  std::size_t k = 0;
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const std::int64_t id = static_cast<std::int64_t>(i) + 1;
    obstacles.clear();
    targets.clear();
    container_walls(c, dim, grains[i].r, walls);
    Vec3 shift_sum = Vec3::Zero();
    int grain_supports = 0;
    for (; k < contacts.size() && contacts[k].i == id; ++k) {
      const ContactForce& cf = contacts[k];
      if (cf.j > 0) {
        const std::size_t j = static_cast<std::size_t>(cf.j - 1);
        Obstacle o;
        o.kind = Obstacle::Kind::Sphere;
        o.c = moved[j].x + cf.shift;
        o.R = grains[i].r + grains[j].r;
        obstacles.push_back(o);
        Vec3 s = moved[j].x - grains[j].x;
        if (c.kind == ContainerKind::Periodic) {  // a support wrapped across the period
          s.x() -= c.size_x * std::round(s.x() / c.size_x);
          if (dim == 3) s.y() -= c.size_y * std::round(s.y() / c.size_y);
        }
        shift_sum += s;
        ++grain_supports;
      } else {
        obstacles.push_back(walls[static_cast<std::size_t>(-cf.j)]);
      }
      targets.push_back(-delta[k]);
    }
    if (obstacles.empty()) continue;
    Vec3 x = grains[i].x + (grain_supports ? Vec3(shift_sum / grain_supports) : Vec3::Zero());
    // Gauss-Newton with minimum-norm steps on gap_k(x) = -delta_k (in 2D in the x-z plane).
    const int cols = dim;
    const int m = static_cast<int>(obstacles.size());
    Eigen::MatrixXd J(m, cols);
    Eigen::VectorXd g(m);
    for (int it = 0; it < kNewtonIterations; ++it) {
      for (int a = 0; a < m; ++a) {
        const Vec3 n = obstacles[a].normal(x);
        g(a) = obstacles[a].gap(x) - targets[a];
        if (dim == 3) J.row(a) << n.x(), n.y(), n.z();
        else J.row(a) << n.x(), n.z();
      }
      if (g.cwiseAbs().maxCoeff() < 1e-14 * grains[i].r) break;
      const Eigen::VectorXd step = J.completeOrthogonalDecomposition().solve(-g);
      if (dim == 3) x += Vec3(step(0), step(1), step(2));
      else x += Vec3(step(0), 0.0, step(1));
      if (step.norm() < 1e-16 * grains[i].r) break;
    }
    if (c.kind == ContainerKind::Periodic) {
      x.x() -= c.size_x * std::floor(x.x() / c.size_x + 0.5);
      if (dim == 3) x.y() -= c.size_y * std::floor(x.y() / c.size_y + 0.5);
    }
    moved[i].x = x;
    Vec3 d = x - grains[i].x;
    if (c.kind == ContainerKind::Periodic) {
      d.x() -= c.size_x * std::round(d.x() / c.size_x);
      if (dim == 3) d.y() -= c.size_y * std::round(d.y() / c.size_y);
    }
    out.largest_move = std::max(out.largest_move, d.norm());
  }
  return out;
}

}  // namespace btr
