#pragma once
// Pre-loaded start of a DEM relaxation (issue 7, part 2). The static force network of a BTR packing
// (btr/measures/force_network.h, weights m g of the scene's materials) gives every contact its normal force;
// the contact law the engines run (relax.model: LIGGGHTS' "hertz" or "hooke", which YADE's laws are
// set to match, coupling/README.md) gives the overlap that carries it:
//   Hertz  F = 4/3 Y* sqrt(R*) delta^(3/2)   (R* = r_i r_j / (r_i + r_j); a wall: R* = r)
//   Hooke  F = k_n delta, k_n = hooke_stiffness(R*, m*, Y*, V) (timestep.h; a wall: m* = m)
// The grains are then moved in id order (deposition order: every support is moved before the grains
// it carries), each to the position that best gives its loaded contacts the law's overlaps (regularised
// least squares on the exact distances, preload.cpp). The overlaps accumulate from the floor up, so
// the bed starts compressed as it is under its weight.
#include <cstdint>
#include <map>
#include <string>
#include <utility>

#include "btr/measures/force_network.h"
#include "btr/scene/scene.h"
#include "coupling/dem/overlap.h"

namespace btr {

// The weights m g of the grains with the scene's densities, and their static force network.
ForceNetwork packing_forces(const Grains& grains, const Scene& scene);

// The scene's normal contact law (relax.model) as the engines run it, for the grains of one packing:
//   hertz            F = 4/3 Y* sqrt(R*) delta^(3/2)
//   hooke            F = k_n delta, k_n = hooke_stiffness(R*, m*, Y*, V) (timestep.h), V from the largest grain
//   hooke-stiffness  F = kn delta, kn of pair_material (a wall: the grain's own kn, as LIGGGHTS is given)
// Y*, R*, m* mix the two grains' materials (materials.h); a wall is wall_material(scene) with R* = r, m* = m.
class ContactLaw {
 public:
  ContactLaw(const Grains& grains, const Scene& scene);
  // Overlap [m] of a contact carrying normal force `force` [N] (0 if force <= 0); partner j > 0 a grain id,
  // j <= 0 the floor or a wall (ForceNetwork codes).
  double overlap(std::int64_t i, std::int64_t j, double force) const;

 private:
  const Grains& grains_;
  const Scene& scene_;
  double hooke_velocity_ = 0.0;
};

// ContactLaw(grains, scene).overlap(i, j, force).
double law_overlap(const Grains& grains, const Scene& scene, std::int64_t i, std::int64_t j, double force);

// The contact law's static overlap of the grains resting on the floor (`btr relax --predict-overlap`):
// each alone, carrying its own weight m g, and under its column, carrying the packing's whole weight shared
// equally among the grains on the floor. Floor grains: those whose gap to the floor (z - r) is at most
// kFloorContact of their radius; if none is, the lowest (bottom within kFloorContact r of the lowest bottom).
struct StaticOverlap {
  std::string law;                // relax.model
  std::int64_t floor_grains = 0;
  double total_weight = 0.0;      // N, sum m g
  double column_force = 0.0;      // N, total_weight / floor_grains
  struct Load {
    double mean_relative = 0.0;     // mean over the floor grains of delta / r
    double largest_relative = 0.0;  // largest delta / r
    double mean_depth = 0.0;        // mean delta [m]
  };
  Load single;  // each floor grain under its own weight
  Load column;  // each floor grain under column_force
};
constexpr double kFloorContact = 1e-3;

// Throws std::runtime_error for an empty packing or a species the scene does not have.
StaticOverlap predict_static_overlap(const Grains& grains, const Scene& scene);

struct Preloaded {
  Grains grains;              // the moved grains (same ids, radii, species)
  IntendedOverlaps intended;  // the overlap each contact was given
  ForceNetwork forces;        // of the input packing
  double largest_relative = 0.0;  // largest intended overlap / smaller radius of its pair
  double largest_depth = 0.0;     // [m]
  double largest_move = 0.0;      // largest displacement of a grain [m]
  // Misfit of the loaded contacts' overlaps against the law's (one vertical move per grain cannot
  // match three overlaps exactly): the largest relative to the grain's radius, and the rms [m].
  double largest_misfit = 0.0;
  double rms_misfit = 0.0;
  std::int64_t column_fallbacks = 0;  // grains given their column's move (no good fit, preload.cpp)
};

// Throws std::runtime_error if the network has unbalanced grains whose vertical load is not carried
// (a grain held from above or floating: no pre-load can hold it), naming the grain.
Preloaded preload_packing(const Grains& grains, const Scene& scene);

}  // namespace btr
