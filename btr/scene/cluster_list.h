#pragma once
// The CSV file of a cluster list ([clusters] file): the rigid clusters to drop, one member grain per row,
// header "cluster,x,y,z,radius,species". Rows with the same cluster number form one cluster (any order);
// clusters are listed in the order of their first row. Positions are in any frame: each cluster is
// centred on its centre of mass and dropped with a random orientation. 2D: y = 0. Blank and '#' lines
// are skipped.
#include <string>
#include <vector>

#include "btr/model/cluster.h"

namespace btr {

// Throws SceneError naming the file and line on a missing file, a malformed row, a radius <= 0, a
// species < 1, y != 0 in 2D, or two members of one cluster overlapping. The caller checks the species
// against the scene.
std::vector<ClusterShape> read_cluster_list(const std::string& path, int dimension);

}  // namespace btr
