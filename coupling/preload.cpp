#include "coupling/preload.h"

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

  // Grains are lowered, never moved sideways: s_i >= 0 is grain i's downward move. A contact k of
  // grain i on partner j (s_j already known: supports come first in id order; the floor and walls do
  // not move) gets the overlap gap_k(s_i - s_j) = |d_k - (s_i - s_j) e_z| - (r_i + r_j). One number
  // per grain cannot match three overlaps exactly, so s_i minimises the squared misfit
  // sum_k (overlap_k - delta_k)^2 over the grain's loaded contacts (1D Newton on the exact distances).
  // Why vertical only: the lateral moves that would match every overlap exactly are ill-conditioned
  // for grains on steep supports (measured: up to 0.07 r moves for 1e-3 r overlaps, overlapping
  // hundreds of neighbours that are not contacts), while a column sinks as a whole, so neighbours
  // that are not in contact keep their gaps to within the overlaps' size.
  std::vector<double> sink(moved.size(), 0.0);
  struct Term {
    Vec3 d;       // x_i - x_j (the partner's image), original positions; for a wall: its normal
    double s_j;   // the partner's downward move
    double reach; // r_i + r_j; for a wall: r_i
    double delta; // the law's overlap
    bool wall;
    double gap0;  // the wall's gap before the move
  };
  std::vector<Term> terms;
  std::vector<Obstacle> walls;
  std::size_t k = 0;
  double misfit_sq = 0.0;
  std::size_t misfit_count = 0;
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const std::int64_t id = static_cast<std::int64_t>(i) + 1;
    terms.clear();
    container_walls(c, dim, grains[i].r, walls);
    double mean_partner = 0.0;
    int partners = 0;
    for (; k < contacts.size() && contacts[k].i == id; ++k) {
      const ContactForce& cf = contacts[k];
      Term t{};
      if (cf.j > 0) {
        const std::size_t j = static_cast<std::size_t>(cf.j - 1);
        t.d = grains[i].x - (grains[j].x + cf.shift);
        t.s_j = sink[j];
        t.reach = grains[i].r + grains[j].r;
        mean_partner += sink[j], ++partners;
      } else {
        const Obstacle& w = walls[static_cast<std::size_t>(-cf.j)];
        t.d = w.normal(grains[i].x);
        t.wall = true;
        t.gap0 = w.gap(grains[i].x);
        ++partners;
      }
      t.delta = delta[k];
      if (cf.f.norm() > 0.0) terms.push_back(t);
    }
    auto overlap = [&](const Term& t, double s) {  // overlap of the contact with grain i lowered by s
      if (t.wall) return -(t.gap0 - s * t.d.z());
      const Vec3 d = t.d - Vec3(0.0, 0.0, s - t.s_j);
      return t.reach - d.norm();
    };
    auto slope = [&](const Term& t, double s) {  // d overlap / d s
      if (t.wall) return t.d.z();
      const Vec3 d = t.d - Vec3(0.0, 0.0, s - t.s_j);
      return d.z() / d.norm();
    };
    // Start from the partners' mean move (a grain with no loaded contact just sinks with them).
    double s = partners ? mean_partner / partners : 0.0;
    for (int it = 0; it < kNewtonIterations && !terms.empty(); ++it) {
      double grad = 0.0, hess = 0.0;
      for (const Term& t : terms) {
        const double e = overlap(t, s) - t.delta, a = slope(t, s);
        grad += e * a;
        hess += a * a;
      }
      if (!(hess > 0.0)) break;  // only horizontal contacts (walls): a vertical move changes nothing
      const double step = -grad / hess;
      s += step;
      if (std::abs(step) < 1e-14 * grains[i].r) break;
    }
    for (const Term& t : terms) misfit_sq += std::pow(overlap(t, s) - t.delta, 2), ++misfit_count;
    for (const Term& t : terms)
      out.largest_misfit = std::max(out.largest_misfit, std::abs(overlap(t, s) - t.delta) / grains[i].r);
    sink[i] = s;
    moved[i].x.z() -= s;
    out.largest_move = std::max(out.largest_move, std::abs(s));
  }
  out.rms_misfit = misfit_count ? std::sqrt(misfit_sq / static_cast<double>(misfit_count)) : 0.0;
  return out;
}

}  // namespace btr
