#pragma once
// Rigid clusters made one piece again in a periodic container, where a packing wraps every member into the
// cell on its own. A geometric utility, not placement code: shared by the cluster check (btr/verify/cluster_check.cpp,
// which stays independent of btr/placement/cluster_placement.cpp) and the DEM export of clusters (coupling/).
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

// Each grain's centre with every cluster's members together: a walk over the members within two largest
// radii of each other, each member at the periodic image nearest the member it was reached from (right also
// for a cluster of touching grains wider than half the cell); a member no walk reaches starts a walk at its
// image nearest the cluster's first member. The first member, free grains, and every grain of a container
// that does not wrap keep their positions; an unwrapped centre may lie outside the cell.
std::vector<Vec3> unwrap_clusters(const Grains& grains, int dimension, const Container& container);

}  // namespace btr
