#pragma once
// The BTR placement engine: grains are dropped one at a time and each falls, rolls over the grains
// already fixed and stops where gravity is balanced by its supports (docs/design.md section 3).
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "btr/model/cluster.h"
#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

// One grain to place: where it is dropped (x, y; y is ignored in 2D) and its size.
// z is the height its centre starts from: NaN (the default) drops it from above the pile; a number
// starts it there (dynamic BTR: a lifted grain falls from its lifted position). A start inside a
// fixed grain is moved straight up until free, so the grain falls onto what is already fixed.
struct Drop {
  double x = 0.0, y = 0.0;
  double r = 0.0;
  int species = 1;
  double z = std::numeric_limits<double>::quiet_NaN();
};

// A grain that could not be placed (event budget exhausted, a drop outside the container, ...).
class PlacementError : public std::runtime_error {
 public:
  PlacementError(std::int64_t grain_id, const std::string& what)
      : std::runtime_error("grain " + std::to_string(grain_id) + ": " + what), grain_id_(grain_id) {}
  std::int64_t grain_id() const { return grain_id_; }

 private:
  std::int64_t grain_id_;
};

// A closed container (the drum) has no room left for the grain: the scene asks for more grains than it
// holds, a fault of the input rather than of the placement.
class ContainerFull : public PlacementError {
 public:
  using PlacementError::PlacementError;
};

class Deposition {
 public:
  // r_max bounds every radius that will be placed (it sizes the neighbour grid).
  Deposition(int dimension, const Container& container, double r_max, int max_events_per_grain = 10000);
  ~Deposition();
  Deposition(const Deposition&) = delete;
  Deposition& operator=(const Deposition&) = delete;

  // Places one grain and returns it as fixed (its id is grains().size()). Throws PlacementError.
  const Grain& place(const Drop& drop);
  // Places one rigid cluster (btr/placement/cluster_placement.cpp) and returns its number (1, 2, ...), which its
  // members carry as Grain::cluster. Throws PlacementError naming the cluster.
  std::int32_t place_cluster(const ClusterDrop& drop);

  // A hint that `drop` is placed `ahead` drops from now (2, 1 or 0 for the next): the memory its fall
  // reads starts loading while the current grain is placed. No effect on any result.
  void prefetch(const Drop& drop, int ahead) const;
  // A hint that about `grains` grains will be placed in all: their array is allocated once (in 2 MiB pages
  // when large), and when they spread `evenly` over the footprint (rain) the neighbour grid's columns get room
  // for their share (NeighbourGrid::reserve). No effect on any result.
  void reserve(std::int64_t grains, bool evenly);

  const Grains& grains() const;
  // Hands the placed grains over (the engine is empty afterwards); saves a copy of a large packing.
  Grains release();
  int dimension() const;
  const Container& container() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace btr
