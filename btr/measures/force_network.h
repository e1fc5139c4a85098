#pragma once
// The static normal-force network of a BTR packing. BTR places grains in id order and no later grain
// moves an earlier one, so the forces that hold the packing up follow top down: visit the grains in
// reverse id order; a grain's load is its weight plus the forces of the grains resting on it; split
// it on its supports (the touching grains with a smaller id, the floor and the walls) with
// non-negative normal forces.
//
// What is split is the vertical part of the load. BTR made sure each grain's supports carry a
// vertical weight with non-negative forces, but not a lateral push: splitting the whole force vector
// of the grains above on three supports amplifies the lateral parts from layer to layer (measured on
// bed3d: the floor then carries 1.24x the weight and 64 grains end up pushed upwards). The lateral
// part is left to friction and measured (lateral_grains, largest_lateral). So every grain's vertical
// balance is exact and the floor and walls carry exactly the total weight plus the upward loads of
// "lifted" grains (below), which no top-down split can carry.
//
// The supports are found from the packing alone (touching within contact_tol), so the network of any
// BTR packing file can be recomputed; the placement engine is not involved.
//
// Partner codes (j): a grain id > 0; 0 the floor; -1, -2, ... the container's side walls in the order
// x-, x+, y-, y+ (box, hele-shaw) or the cylinder (-1), the order of coupling's dem_walls after the floor.
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

struct ContactForce {
  std::int64_t i = 0;       // grain id (the upper one: j < i for grain partners)
  std::int64_t j = 0;       // partner: grain id, 0 floor, < 0 wall
  Vec3 f = Vec3::Zero();    // force on i from j [N] (along the contact normal, pointing into i)
  Vec3 shift = Vec3::Zero();  // periodic image of j touching i: x_j + shift (zero unless periodic)
};

// A grain whose supports cannot carry its vertical load with non-negative normal forces.
struct UnbalancedGrain {
  std::int64_t id = 0;
  Vec3 residual = Vec3::Zero();  // vertical load not carried [N] (load + sum of the support forces)
  double load = 0.0;             // vertical load [N]
};

struct ForceNetwork {
  std::vector<ContactForce> contacts;      // sorted by i, then by j (walls and floor first)
  std::vector<UnbalancedGrain> unbalanced; // grains whose vertical load is not carried (a broken packing)
  // Grains pushed sideways by the grains above (the lateral part of the load, left to friction):
  // their number and the largest lateral part, as a fraction of the grain's own weight.
  std::int64_t lateral_grains = 0;
  double largest_lateral = 0.0;
  // Grains whose net vertical load points up: a later grain leaning on them below its equator
  // pushes them up more than their weight and the grains above push them down. No downward support
  // exists for them; their supports get no force and the upward load is left (lifted_force [N]).
  // So: container_force.z() == total_weight + lifted_force - sum of the unbalanced residuals' z.
  std::int64_t lifted_grains = 0;
  double lifted_force = 0.0;
  // Grains with a singular support set (collinear normals in 2D, coplanar in 3D, e.g. two supports
  // in a line with the load): the rule is the smallest subset of supports (by size, then by partner
  // order) that carries the vertical load exactly; the others get zero force. Counted, never silent.
  std::int64_t singular_grains = 0;
  double total_weight = 0.0;               // [N]
  Vec3 container_force = Vec3::Zero();     // sum of the forces the floor and walls exert [N]
};

// A packing whose network cannot be built (a weight missing, a grain with no support at all).
class ForceNetworkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// weights[i] is grain i's weight [N] (m g, g along -z). contact_tol: a contact is a gap below
// contact_tol times the smaller radius (overlaps of round-off size count as contacts).
// residual_tol: a grain is unbalanced when |residual| > residual_tol * |load|.
ForceNetwork static_forces(const Grains& grains, int dimension, const Container& container,
                           const std::vector<double>& weights, double contact_tol = 1e-7,
                           double residual_tol = 1e-9);

}  // namespace btr
