#pragma once
// Coarsening of a cohesive nano-powder by redeposition (seed 000 section 5): the grains are first
// deposited as random compact clusters of [clusters].size grains; each cycle then cuts the deposit
// into square (2D) or cubic (3D) blocks, splits every block into clusters of mutually touching grains
// (cohesion: grains that touch stay together) and drops those clusters again, in random order, at
// random positions over the container, into an empty container.
#include <cstdint>
#include <random>
#include <vector>

#include "btr/model/cluster.h"
#include "btr/model/grain.h"
#include "btr/scene/scene.h"

namespace btr {

// The clusters of touching grains within each block of side `side` (blocks aligned with the
// container's -x (-y) side and the floor): grain indices per cluster, each ascending, ordered by their
// first index. Grains touch when their gap is at most contact_tol times the smaller radius.
std::vector<std::vector<std::size_t>> touching_clusters_in_blocks(const Grains& grains, int dimension,
                                                                  const Container& container, double side,
                                                                  double contact_tol = 1e-7);

struct CycleMeasures {
  double mean_height = 0.0;       // <h>, strips one mean diameter wide (metrics.h: bed_height_measures)
  double packing_fraction = 0.0;  // grain volume / (footprint * <h>) (metrics.h: bed_height_measures)
  std::vector<std::int64_t> size_counts;  // size_counts[s]: clusters of s grains (index 0 unused)
};

CycleMeasures measure_cycle(const Grains& grains, int dimension, const Container& container);

class Redeposition {
 public:
  // The scene must have a [clusters] table.
  Redeposition(const Scene& scene, std::uint64_t seed);
  // The first deposit: scene.grains.count grains in clusters of [clusters].size.
  Grains initial();
  // One cycle: blocks, touching clusters, dropped again.
  Grains cycle(const Grains& deposit);

 private:
  Grains drop_all(const std::vector<ClusterShape>& shapes);
  Scene scene_;
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  double r_max_ = 0.0;
};

}  // namespace btr
