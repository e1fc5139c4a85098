#pragma once
// Dynamic BTR in a slowly rotating drum (seed 000 section 6, Fig. 12): one step rotates every grain
// with the drum about its axis, lifts every grain, and redeposits all of them with the placement
// engine in order of increasing height.
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

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
  Vec3 rotate(const Vec3& x, double cos_dphi, double sin_dphi) const;
  int dimension_;
  Container container_;
  double lift_;
};

}  // namespace btr
