#include "btr/dynamics/redeposition.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

#include "btr/measures/metrics.h"
#include "btr/model/cluster.h"
#include "btr/model/number_text.h"
#include "btr/placement/deposition.h"
#include "btr/placement/drops.h"
#include "btr/placement/pair_search.h"
#include "btr/scene/cluster_list.h"
#include "btr/scene/scene_toml.h"

namespace btr {
namespace {

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void join(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

double mean_diameter(const Grains& grains) {
  double d = 0.0;
  for (const Grain& g : grains) d += 2.0 * g.r;
  return grains.empty() ? 0.0 : d / static_cast<double>(grains.size());
}

}  // namespace

std::vector<std::vector<std::size_t>> touching_clusters_in_blocks(const Grains& grains, int dimension,
                                                                  const Container& c, double side,
                                                                  double contact_tol) {
  std::vector<std::array<long, 3>> block(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Vec3& x = grains[i].x;
    block[i] = {static_cast<long>(std::floor((x.x() + 0.5 * c.size_x) / side)),
                dimension == 3 ? static_cast<long>(std::floor((x.y() + 0.5 * c.size_y) / side)) : 0,
                static_cast<long>(std::floor(x.z() / side))};
  }
  const double r_max = max_radius(grains);
  UnionFind uf(grains.size());
  // Plain distances, no periodic image: the blocks cut the cell, and a cluster never spans a cut.
  const PairSearch pairs(grains, dimension, Container{}, r_max * (2.0 + std::max(contact_tol, 0.0)) * 1.0001);
  pairs.for_each_pair([&](std::size_t a, std::size_t b, const Vec3& d) {
    if (block[a] != block[b] || std::abs(d.x()) > 2.0 * r_max) return;
    // the radii subtracted in order of x, then of index, as the sweep along x did
    const bool a_first = grains[a].x.x() < grains[b].x.x() || (grains[a].x.x() == grains[b].x.x() && a < b);
    const Grain &gi = grains[a_first ? a : b], &gj = grains[a_first ? b : a];
    const double gap = d.norm() - gi.r - gj.r;
    if (gap <= contact_tol * std::min(gi.r, gj.r)) uf.join(a, b);
  });
  std::map<std::size_t, std::vector<std::size_t>> by_root;
  for (std::size_t i = 0; i < grains.size(); ++i) by_root[uf.find(i)].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  for (auto& [root, members] : by_root) out.push_back(std::move(members));
  return out;  // roots are the smallest index of each cluster: already ordered by first index
}

CycleMeasures measure_cycle(const Grains& grains, int dimension, const Container& c) {
  CycleMeasures m;
  const BedHeightMeasures bed = bed_height_measures(grains, dimension, c, mean_diameter(grains));
  m.mean_height = bed.mean_height;
  m.packing_fraction = bed.packing_fraction;
  for (const auto& body : rigid_bodies(grains)) {
    if (m.size_counts.size() <= body.size()) m.size_counts.resize(body.size() + 1, 0);
    ++m.size_counts[body.size()];
  }
  return m;
}

Redeposition::Redeposition(const Scene& scene, std::uint64_t seed)
    : scene_(scene), seed_(seed), rng_(seed ^ 0x434c555354455253ULL) {
  if (!scene.clusters) throw std::invalid_argument(scene.file + ": the scene has no [clusters] table");
}

Grains Redeposition::drop_all(const std::vector<ClusterShape>& shapes) {
  Deposition dep(scene_.dimension, scene_.container, r_max_);
  const Container& c = scene_.container;
  for (const ClusterShape& shape : shapes) {
    ClusterDrop d;
    d.shape = shape;
    d.orientation = random_orientation(scene_.dimension, rng_);
    const double e = c.kind == ContainerKind::Periodic ? 0.0 : shape.extent();
    auto coordinate = [&](double size, const char* axis) {
      if (size - 2.0 * e < 0.0)
        throw SceneError(scene_.file + ": container.size: a cluster of " + std::to_string(shape.size()) +
                         " grains (extent " + g6(e) + " m) does not fit the container's " + axis + " size (" + g6(size) +
                         " m); expected a wider container or smaller clusters "
                         "(clusters.size or clusters.file, and clusters.block = " +
                         g6(scene_.clusters->block) + " mean diameters for those cut from the deposit)");
      return -0.5 * size + e + uniform(rng_) * (size - 2.0 * e);
    };
    d.x = coordinate(c.size_x, "x");
    d.y = scene_.dimension == 3 ? coordinate(c.size_y, "y") : 0.0;
    dep.place_cluster(d);
  }
  return dep.release();
}

Grains Redeposition::initial() {
  if (!scene_.clusters->file.empty()) {  // the listed clusters, in file order
    const std::vector<ClusterShape> shapes = read_cluster_list(scene_.clusters->file, scene_.dimension);
    for (const ClusterShape& s : shapes) r_max_ = std::max(r_max_, *std::max_element(s.radii.begin(), s.radii.end()));
    return drop_all(shapes);
  }
  DropSequence drops(scene_, seed_);
  r_max_ = drops.r_max();
  const std::int64_t n = drops.count(), size = scene_.clusters->size;
  std::vector<ClusterShape> shapes;
  for (std::int64_t i = 0; i < n; i += size) {
    std::vector<Drop> members;
    for (std::int64_t k = i; k < std::min(n, i + size); ++k) members.push_back(drops.next());
    std::size_t next = 0;
    shapes.push_back(random_compact_cluster(
        scene_.dimension, static_cast<int>(members.size()), rng_,
        [&](std::mt19937_64&) { return members[next++].r; }, members.front().species));
    for (std::size_t k = 0; k < members.size(); ++k) shapes.back().species[k] = members[k].species;
  }
  return drop_all(shapes);
}

Grains Redeposition::cycle(const Grains& deposit) {
  if (r_max_ == 0.0)
    for (const Grain& g : deposit) r_max_ = std::max(r_max_, g.r);
  const double side = scene_.clusters->block * mean_diameter(deposit);
  auto clusters = touching_clusters_in_blocks(deposit, scene_.dimension, scene_.container, side);
  // Random order (Fisher-Yates with the engine's own draws, the same on every platform).
  for (std::size_t i = clusters.size(); i > 1; --i) std::swap(clusters[i - 1], clusters[rng_() % i]);
  std::vector<ClusterShape> shapes;
  for (const auto& members : clusters) {
    ClusterShape s;
    for (std::size_t i : members) s.add(deposit[i].x, deposit[i].r, deposit[i].species);
    s.centre(scene_.dimension);
    shapes.push_back(std::move(s));
  }
  return drop_all(shapes);
}

}  // namespace btr
