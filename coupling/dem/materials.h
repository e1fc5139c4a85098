#pragma once
// Contact materials as both engines see them: one material per species (scene component), a mixing
// rule for unlike pairs, the material of the container walls, and the grains' masses.
//
// Decisions (documented in coupling/README.md):
//  - an unlike pair (species a, b) takes the arithmetic mean of the two species' restitution,
//    friction and rolling friction; elastic constants combine as the contact laws do (Y*, G*);
//  - walls are made of the first component's material; a grain-wall contact takes the grain's
//    restitution, friction and rolling friction;
//  - every grain is a sphere of its radius, also in 2D (disks are relaxed as spheres kept in y = 0).
#include <vector>

#include "btr/model/grain.h"
#include "btr/scene/scene.h"

namespace btr {

constexpr double kGravity = 9.81;  // m/s^2, along -z

// Index into scene.grains.components of the component with this species; throws std::runtime_error
// naming the species and the species the scene has if there is none.
int component_index(const Scene& scene, int species);

// Restitution, friction, rolling friction and the explicit stiffness/damping (hooke-stiffness) of a
// contact between two materials (mean of the two).
Material pair_material(const Material& a, const Material& b);

// The component whose material (and density, where an engine wants one for its wall bodies) every wall of
// the container takes: the first component. The one place that decides it; the writers (LIGGGHTS' wall
// type, YADE's "walls" material), the time-step rule, the blow-up bound and the contact law's overlaps
// (preload.h) all ask here. Throws std::runtime_error if the scene has no component.
const Component& wall_component(const Scene& scene);

// wall_component(scene).material.
const Material& wall_material(const Scene& scene);

// Effective Young's modulus Y* of a contact: 1/Y* = (1 - nu_a^2)/Y_a + (1 - nu_b^2)/Y_b.
double effective_young(const Material& a, const Material& b);

// Mass of a grain of radius r: a sphere of the component's density.
double grain_mass(double radius, double density);

// Per-grain masses of a packing (component densities looked up by species).
std::vector<double> grain_masses(const Grains& grains, const Scene& scene);

// True if any component sets rolling friction (the only case where a rolling model is emitted).
bool uses_rolling_friction(const Scene& scene);

}  // namespace btr
