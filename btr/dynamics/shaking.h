#pragma once
// Dynamic BTR by shaking (seed 001 section 6.6, Jullien-Meakin): one cycle numbers the grains by
// height, lifts the whole pile, and redeposits every grain with the placement engine, lowest first,
// each falling from its lifted position onto the grains already redeposited.
#include <cstdint>
#include <random>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

class Shaker {
 public:
  // noise: amplitude a of a uniform horizontal displacement in [-a, a] per axis, per grain and cycle;
  // the draws come from a std::mt19937_64 seeded with `seed`, in redeposition order (x, then y in 3D).
  Shaker(int dimension, const Container& container, double lift, double noise, std::uint64_t seed);

  // One cycle. Grain i of the result is grain i of the input (same radius and species, new centre).
  // Throws PlacementError if the engine cannot place a grain.
  Grains cycle(const Grains& grains);

  // Redeposition order: by centre height, ties by index.
  static std::vector<std::size_t> height_order(const Grains& grains);

 private:
  double uniform() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  // A displaced (x, y) brought back where a grain of radius r fits: clamped to box and Hele-Shaw walls,
  // pulled radially inside a cylinder; periodic domains are wrapped by the engine.
  void keep_inside(double& x, double& y, double r) const;

  int dimension_;
  Container container_;
  double lift_, noise_;
  std::mt19937_64 rng_;
};

}  // namespace btr
