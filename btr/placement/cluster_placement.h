#pragma once
// Placement of one rigid cluster inside the Deposition engine: the engine's grains, neighbour grid
// and container walls are shared, the cluster's members are added to them when it comes to rest.
#include <cstdint>

#include "btr/model/cluster.h"
#include "btr/model/container.h"
#include "btr/placement/neighbour_grid.h"

namespace btr {

struct ClusterEngine {
  int dimension;
  const Container& container;
  double r_max;
  int max_events;  // per grain; a cluster gets 20 times as many steps
  Grains& grains;
  NeighbourGrid& grid;
  double& top;
  std::int32_t& clusters;
};

std::int32_t place_rigid_cluster(ClusterEngine& engine, const ClusterDrop& drop);

}  // namespace btr
