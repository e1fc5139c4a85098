#pragma once
// Dynamic BTR in a slowly rotating drum (seed 000 section 6, Fig. 12): one step rotates every grain
// with the drum about its axis, lifts every grain, and redeposits all of them with the placement
// engine in order of increasing height.
#include <vector>

#include "btr/container.h"
#include "btr/grain.h"

namespace btr {

class DrumStepper {
 public:
  // container.kind must be Drum; lift > 0 (the paper: radius / 10).
  DrumStepper(int dimension, const Container& container, double lift);

  // One step by the angle dphi (radians; positive: the drum's lowest point moves towards +x, so the
  // material climbs the +x side). Grain i of the result is grain i of the input. Throws PlacementError.
  Grains step(const Grains& grains, double dphi) const;

  // Rotation of one centre about the drum's axis (x-z plane), without lift or redeposition.
  Vec3 rotate(const Vec3& x, double dphi) const;

 private:
  int dimension_;
  Container container_;
  double lift_;
};

struct DrumMeasures {
  double split_radius = 0.0;       // grains with r <= split are "small" (the median radius)
  double axis_small = 0.0, axis_large = 0.0;  // mean distance from the axis [m] (x-z plane)
  double core_small = 0.0, core_large = 0.0;  // mean distance from the centre of mass [m]
  double segregation_index = 0.0;  // (axis_large - axis_small) / radius: > 0 when small grains are inner
  double com_x = 0.0, com_z = 0.0;  // centre of mass (volume-weighted) [m]
  bool surface_valid = false;
  double surface_angle_deg = 0.0;   // slope of the free surface (rising towards +x is positive)
};

// Free surface: columns one largest diameter wide over |x| <= 0.6 radius, highest grain top in each;
// the angle is that of the least-squares line through them (needs 3 columns holding grains).
DrumMeasures drum_measures(const Grains& grains, int dimension, const Container& container);

}  // namespace btr
