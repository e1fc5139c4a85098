#include "btr/verify/cluster_unwrap.h"

#include <algorithm>

#include "btr/model/cluster.h"
#include "btr/verify/check.h"

namespace btr {

std::vector<Vec3> unwrap_clusters(const Grains& grains, int dimension, const Container& container) {
  std::vector<Vec3> at(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) at[i] = grains[i].x;
  const MinimumImage image(container, dimension);
  if (!image.px && !image.py) return at;
  const double r_max = max_radius(grains);
  const double reach = 2.0 * r_max * (1.0 + 1e-6);  // touching members, with room for round-off

  std::vector<Vec3> x;                         // one body's members, as in the packing
  std::vector<std::vector<std::size_t>> links;  // members within reach of each other (indices into x)
  std::vector<char> placed;
  std::vector<std::size_t> walk;
  for (const auto& body : rigid_bodies(grains)) {
    const std::size_t m = body.size();
    if (m < 2) continue;
    x.resize(m);
    for (std::size_t k = 0; k < m; ++k) x[k] = grains[body[k]].x;
    links.assign(m, {});
    for_each_pair_within(x, reach, image, [&](std::size_t a, std::size_t b, const Vec3&) {
      links[a].push_back(b);
      links[b].push_back(a);
    });
    placed.assign(m, 0);
    for (std::size_t start = 0; start < m; ++start) {
      if (placed[start]) continue;
      at[body[start]] = x[0] + image(x[start] - x[0]);
      placed[start] = 1;
      walk.assign(1, start);
      while (!walk.empty()) {
        const std::size_t a = walk.back();
        walk.pop_back();
        for (std::size_t b : links[a])
          if (!placed[b]) {
            at[body[b]] = at[body[a]] + image(x[b] - x[a]);
            placed[b] = 1;
            walk.push_back(b);
          }
      }
    }
  }
  return at;
}

}  // namespace btr
