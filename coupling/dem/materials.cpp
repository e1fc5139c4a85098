#include "coupling/dem/materials.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace btr {

int component_index(const Scene& scene, int species) {
  const auto& comps = scene.grains.components;
  for (std::size_t i = 0; i < comps.size(); ++i)
    if (comps[i].species == species) return static_cast<int>(i);
  std::string have;
  for (const Component& c : comps) have += (have.empty() ? "" : ", ") + std::to_string(c.species);
  throw std::runtime_error("species " + std::to_string(species) + " is not a component of scene '" + scene.name +
                           "' (its species: " + (have.empty() ? "none" : have) + ")");
}

Material pair_material(const Material& a, const Material& b) {
  Material m;
  m.young = effective_young(a, b);
  m.poisson = 0.5 * (a.poisson + b.poisson);  // not used by the contact laws; kept meaningful
  m.restitution = 0.5 * (a.restitution + b.restitution);
  m.friction = 0.5 * (a.friction + b.friction);
  m.rolling_friction = 0.5 * (a.rolling_friction + b.rolling_friction);
  m.kn = 0.5 * (a.kn + b.kn);
  m.kt = 0.5 * (a.kt + b.kt);
  m.gamma_n = 0.5 * (a.gamma_n + b.gamma_n);
  m.gamma_t = 0.5 * (a.gamma_t + b.gamma_t);
  m.wall_gamma_t = 0.5 * (a.wall_gamma_t + b.wall_gamma_t);
  return m;
}

const Component& wall_component(const Scene& scene) {
  if (scene.grains.components.empty())
    throw std::runtime_error("scene '" + scene.name + "' has no grain component, so no wall material");
  return scene.grains.components.front();
}

const Material& wall_material(const Scene& scene) { return wall_component(scene).material; }

double effective_young(const Material& a, const Material& b) {
  return 1.0 / ((1.0 - a.poisson * a.poisson) / a.young + (1.0 - b.poisson * b.poisson) / b.young);
}

double grain_mass(double radius, double density) { return grain_volume(radius, 3) * density; }

std::vector<double> grain_masses(const Grains& grains, const Scene& scene) {
  std::vector<double> m(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Component& c = scene.grains.components[component_index(scene, grains[i].species)];
    m[i] = grain_mass(grains[i].r, c.density);
  }
  return m;
}

bool uses_rolling_friction(const Scene& scene) {
  for (const Component& c : scene.grains.components)
    if (c.material.rolling_friction > 0.0) return true;
  return false;
}

}  // namespace btr
