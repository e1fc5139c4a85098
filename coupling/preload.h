#pragma once
// Pre-loaded start of a DEM relaxation (issue 7, part 2). The static force network of a BTR packing
// (btr/force_network.h, weights m g of the scene's materials) gives every contact its normal force;
// the contact law the engines run (relax.model: LIGGGHTS' "hertz" or "hooke", which YADE's laws are
// set to match, coupling/README.md) gives the overlap that carries it:
//   Hertz  F = 4/3 Y* sqrt(R*) delta^(3/2)   (R* = r_i r_j / (r_i + r_j); a wall: R* = r)
//   Hooke  F = k_n delta, k_n = hooke_stiffness(R*, m*, Y*, V) (timestep.h; a wall: m* = m)
// The grains are then moved in id order (deposition order: every support is moved before the grains
// it carries) so that the distance to each (already moved) support is r_i + r_j - delta_ij, by
// Gauss-Newton on those distance equations from the grain's position shifted by the mean shift of
// its supports (minimum-norm steps: a grain with fewer supports than the dimension keeps its
// position along the free directions).
#include <cstdint>
#include <map>
#include <utility>

#include "btr/force_network.h"
#include "btr/scene.h"
#include "coupling/overlap.h"

namespace btr {

// The weights m g of the grains with the scene's densities, and their static force network.
ForceNetwork packing_forces(const Grains& grains, const Scene& scene);

// Overlap [m] of a contact carrying normal force `force` [N] under the scene's contact law; partner
// j > 0 a grain id, j <= 0 the floor or a wall (ForceNetwork codes).
double law_overlap(const Grains& grains, const Scene& scene, std::int64_t i, std::int64_t j, double force);

struct Preloaded {
  Grains grains;              // the moved grains (same ids, radii, species)
  IntendedOverlaps intended;  // the overlap each contact was given
  ForceNetwork forces;        // of the input packing
  double largest_relative = 0.0;  // largest intended overlap / smaller radius of its pair
  double largest_depth = 0.0;     // [m]
  double largest_move = 0.0;      // largest displacement of a grain [m]
};

// Throws std::runtime_error if the network has unbalanced grains whose vertical load is not carried
// (a grain held from above or floating: no pre-load can hold it), naming the grain.
Preloaded preload_packing(const Grains& grains, const Scene& scene);

}  // namespace btr
