#include "coupling/dem/timestep.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>

#include "btr/model/number_text.h"
#include "coupling/dem/materials.h"

namespace btr {

namespace {

// Smallest and largest radius present for each component index.
struct RadiusRange { double min = std::numeric_limits<double>::infinity(), max = 0.0; };

std::map<int, RadiusRange> radius_ranges(const Grains& grains, const Scene& scene) {
  std::map<int, RadiusRange> ranges;
  for (const Grain& g : grains) {
    RadiusRange& rr = ranges[component_index(scene, g.species)];
    rr.min = std::min(rr.min, g.r);
    rr.max = std::max(rr.max, g.r);
  }
  return ranges;
}

}  // namespace

double lowest_restitution(const Scene& scene) {
  double e = 1.0;
  for (const Component& c : scene.grains.components) e = std::min(e, c.material.restitution);
  return e;
}

double damping_ratio(double restitution) {
  if (restitution >= 1.0) return 0.0;
  const double l = std::log(restitution);
  return -l / std::sqrt(M_PI * M_PI + l * l);
}

double rayleigh_time(double radius, double density, double young, double poisson) {
  const double shear = young / (2.0 * (1.0 + poisson));
  return M_PI * radius * std::sqrt(density / shear) / (0.1631 * poisson + 0.8766);
}

double hooke_stiffness(double r_eff, double m_eff, double y_eff, double velocity) {
  const double s = std::sqrt(r_eff);
  return 16.0 / 15.0 * s * y_eff * std::pow(15.0 * m_eff * velocity * velocity / (16.0 * s * y_eff), 0.2);
}

double hooke_damping(double m_eff, double stiffness, double restitution) {
  if (restitution >= 1.0) return 0.0;
  const double q = M_PI / std::log(restitution);
  return std::sqrt(4.0 * m_eff * stiffness / (1.0 + q * q));
}

double hooke_contact_time(double stiffness, double m_eff, double damping) {
  const double half_rate = damping / (2.0 * m_eff);
  return M_PI / std::sqrt(stiffness / m_eff - half_rate * half_rate);
}

double hooke_characteristic_velocity(const Grains& grains) {
  double r_max = 0.0;
  for (const Grain& g : grains) r_max = std::max(r_max, g.r);
  return std::sqrt(2.0 * kGravity * 2.0 * r_max);
}

StableStep stable_timestep(const Grains& grains, const Scene& scene, DampedMode mode) {
  if (grains.empty()) throw std::runtime_error("the packing has no grains: no time step can be derived");
  const auto& comps = scene.grains.components;
  const auto ranges = radius_ranges(grains, scene);
  StableStep s;
  s.fraction = scene.relax.timestep_fraction;
  const double e_low = lowest_restitution(scene);
  double zeta = damping_ratio(e_low);
  std::string which = "normal";
  if (mode == DampedMode::TangentialSameDashpot) {
    double kappa = 1.0;  // linear law: ks = kn
    if (scene.relax.model == "hertz")
      for (const Component& c : comps)
        kappa = std::min(kappa, 2.0 * (1.0 - c.material.poisson) / (2.0 - c.material.poisson));
    zeta *= std::sqrt(7.0 / (2.0 * kappa));
    which = "tangential, same dashpot as the normal one";
  }
  const double verlet = std::sqrt(1.0 + zeta * zeta) - zeta;
  auto damping_note = [&]() {
    return " x damping factor " + g6(s.damping_factor) + " (lowest restitution " + g6(e_low) + ", " + which +
           " damping ratio " + g6(zeta) + ")";
  };

  if (scene.relax.model == "hertz") {
    double best = std::numeric_limits<double>::infinity();
    int best_c = -1;
    for (const auto& [c, rr] : ranges) {
      const Material& m = comps[c].material;
      const double t = rayleigh_time(rr.min, comps[c].density, m.young, m.poisson);
      if (t < best) { best = t; best_c = c; }
    }
    const Component& c = comps[best_c];
    s.characteristic_time = best;
    s.damping_factor = verlet;
    s.step = s.fraction * s.damping_factor * best;
    s.rule = "Rayleigh time pi R sqrt(rho/G)/(0.1631 nu + 0.8766) = " + g6(best) + " s (Hertz; smallest grain R = " +
             g6(ranges.at(best_c).min) + " m of species " + std::to_string(c.species) + ", rho = " + g6(c.density) +
             " kg/m^3, E = " + g6(c.material.young) + " Pa, nu = " + g6(c.material.poisson) + ") x " +
             g6(s.fraction) + damping_note() + " = " + g6(s.step) + " s";
    return s;
  }
  if (scene.relax.model == "hooke-stiffness") {
    // Explicit stiffness: contact time pi / sqrt(kn/m_eff - (gamma_n/2)^2) (gamma_n per unit effective
    // mass), shortest over grain pairs (unlike species: the mean kn, gamma_n) and grain-wall contacts
    // (m_eff = m) at the ends of each species' radius range.
    double best = std::numeric_limits<double>::infinity();
    std::string what;
    auto consider = [&](double kn, double gamma_n, double m_eff, const std::string& label) {
      const double w2 = kn / m_eff - 0.25 * gamma_n * gamma_n;
      if (!(w2 > 0.0))
        throw std::runtime_error("relax.model = \"hooke-stiffness\": " + label + " is overdamped (gamma_n/2 = " +
                                 g6(0.5 * gamma_n) + " 1/s >= sqrt(kn/m_eff) = " + g6(std::sqrt(kn / m_eff)) +
                                 " 1/s); no contact time");
      const double t = M_PI / std::sqrt(w2);
      if (t < best) best = t, what = label + ": kn = " + g6(kn) + " N/m, m_eff = " + g6(m_eff) + " kg, gamma_n = " +
                                     g6(gamma_n) + " 1/s";
    };
    for (const auto& [ca, ra] : ranges) {
      const Component& a = comps[ca];
      for (double r1 : {ra.min, ra.max}) {
        const double m1 = grain_mass(r1, a.density);
        consider(a.material.kn, a.material.gamma_n, m1, "grain R = " + g6(r1) + " m of species " +
                                                            std::to_string(a.species) + " on a wall");
        for (const auto& [cb, rb] : ranges) {
          if (cb < ca) continue;
          const Component& b = comps[cb];
          const Material p = pair_material(a.material, b.material);
          for (double r2 : {rb.min, rb.max}) {
            const double m2 = grain_mass(r2, b.density);
            consider(p.kn, p.gamma_n, m1 * m2 / (m1 + m2),
                     "grains R = " + g6(r1) + " m (species " + std::to_string(a.species) + ") and R = " + g6(r2) +
                         " m (species " + std::to_string(b.species) + ")");
          }
        }
      }
    }
    s.characteristic_time = best;
    s.damping_factor = verlet;  // the contact time above already includes the damping
    s.step = s.fraction * s.damping_factor * best;
    s.rule = "contact time pi/sqrt(kn/m_eff - (gamma_n/2)^2) = " + g6(best) + " s (hooke-stiffness; " + what +
             ") x " + g6(s.fraction) + damping_note() + " = " + g6(s.step) + " s";
    return s;
  }
  if (scene.relax.model != "hooke")
    throw std::runtime_error("relax.model: expected \"hertz\", \"hooke\" or \"hooke-stiffness\", got \"" +
                             scene.relax.model + "\"");

  // Hooke: the shortest contact time over the contacts the packing can make. For a pair of species
  // k/m* is largest at an end of each species' radius range; a wall contact is a partner of infinite
  // radius and mass.
  const double v = hooke_characteristic_velocity(grains);
  const Material& wall = wall_material(scene);
  double best = std::numeric_limits<double>::infinity();
  std::string what;
  auto consider = [&](double r_eff, double m_eff, const Material& a, const Material& b, const std::string& label) {
    const double k = hooke_stiffness(r_eff, m_eff, effective_young(a, b), v);
    const double gamma = hooke_damping(m_eff, k, pair_material(a, b).restitution);
    const double t = hooke_contact_time(k, m_eff, gamma);
    if (t < best) {
      best = t;
      what = label + ": k = " + g6(k) + " N/m, m_eff = " + g6(m_eff) + " kg, gamma_n = " + g6(gamma) + " kg/s";
    }
  };
  for (const auto& [ca, ra] : ranges) {
    const Component& a = comps[ca];
    for (double r1 : {ra.min, ra.max}) {
      const double m1 = grain_mass(r1, a.density);
      // grain-wall: the grain's restitution (pair_material of the grain with itself keeps it)
      {
        const double k = hooke_stiffness(r1, m1, effective_young(a.material, wall), v);
        const double gamma = hooke_damping(m1, k, a.material.restitution);
        const double t = hooke_contact_time(k, m1, gamma);
        if (t < best) {
          best = t;
          what = "grain R = " + g6(r1) + " m of species " + std::to_string(a.species) + " on a wall: k = " + g6(k) +
                 " N/m, m_eff = " + g6(m1) + " kg, gamma_n = " + g6(gamma) + " kg/s";
        }
      }
      for (const auto& [cb, rb] : ranges) {
        if (cb < ca) continue;
        const Component& b = comps[cb];
        for (double r2 : {rb.min, rb.max}) {
          const double m2 = grain_mass(r2, b.density);
          consider(r1 * r2 / (r1 + r2), m1 * m2 / (m1 + m2), a.material, b.material,
                   "grains R = " + g6(r1) + " m (species " + std::to_string(a.species) + ") and R = " + g6(r2) +
                       " m (species " + std::to_string(b.species) + ")");
        }
      }
    }
  }
  s.characteristic_time = best;
  s.damping_factor = std::sqrt(1.0 - zeta * zeta) * verlet;
  s.step = s.fraction * s.damping_factor * best;
  s.rule = "contact time pi/sqrt(k/m_eff - (gamma/2)^2) = " + g6(best) + " s (Hooke, V = " + g6(v) + " m/s; " +
           what + ") x " + g6(s.fraction) + damping_note() + " = " + g6(s.step) + " s";
  return s;
}

}  // namespace btr
