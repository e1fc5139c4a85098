// The shared pair search finds exactly the pairs a brute-force loop over every pair and every periodic
// image finds, in 2D and 3D, with polydisperse grains, narrow periods and grains far from the rest.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>

#include "btr/placement/pair_search.h"
#include "containers.h"

namespace btr {
namespace {

using Pairs = std::map<std::pair<std::size_t, std::size_t>, Vec3>;  // (i < j) -> x_j - x_i, nearest image

Grains random_grains(std::size_t n, int dimension, double lx, double ly, double height, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Grains g(n);
  for (Grain& a : g) {
    a.r = 0.2 + 0.8 * u(rng);  // radii 0.2 to 1: polydisperse
    a.x = Vec3((u(rng) - 0.5) * lx, dimension == 3 ? (u(rng) - 0.5) * ly : 0.0, u(rng) * height);
  }
  return g;
}

// Every pair i < j, every image shift of up to 5 periods along each periodic axis; the nearest image
// decides, as for the pair search.
Pairs brute_force(const Grains& g, double px, double py, double cutoff) {
  Pairs out;
  const int kx = px > 0.0 ? 5 : 0, ky = py > 0.0 ? 5 : 0;
  for (std::size_t i = 0; i < g.size(); ++i)
    for (std::size_t j = i + 1; j < g.size(); ++j) {
      Vec3 best = Vec3::Constant(1e300);
      for (int a = -kx; a <= kx; ++a)
        for (int b = -ky; b <= ky; ++b) {
          const Vec3 d = g[j].x + Vec3(a * px, b * py, 0.0) - g[i].x;
          if (d.squaredNorm() < best.squaredNorm()) best = d;
        }
      if (best.squaredNorm() <= cutoff * cutoff) out[{i, j}] = best;
    }
  return out;
}

Pairs from_each_pair(const PairSearch& s) {
  Pairs out;
  int repeated = 0;
  s.for_each_pair([&](std::size_t i, std::size_t j, const Vec3& d) {
    const bool swap = j < i;
    const auto key = swap ? std::make_pair(j, i) : std::make_pair(i, j);
    repeated += out.count(key);
    out[key] = swap ? Vec3(-d) : d;
  });
  EXPECT_EQ(repeated, 0) << "a pair reported twice";
  return out;
}

Pairs from_neighbours(const PairSearch& s, std::size_t n) {
  Pairs out;
  for (std::size_t i = 0; i < n; ++i)
    s.for_neighbours(i, [&](std::size_t j, const Vec3& d) {
      EXPECT_NE(i, j);
      if (i < j) {
        EXPECT_EQ(out.count({i, j}), 0u) << "neighbour " << j << " of " << i << " reported twice";
        out[{i, j}] = d;
      }
    });
  return out;
}

void expect_same(const Pairs& found, const Pairs& expected, const char* what) {
  EXPECT_EQ(found.size(), expected.size()) << what;
  for (const auto& [key, d] : expected) {
    const auto it = found.find(key);
    if (it == found.end()) {
      ADD_FAILURE() << what << ": pair " << key.first << ", " << key.second << " missed";
      continue;
    }
    EXPECT_LT((it->second - d).norm(), 1e-12) << what << ": separation of " << key.first << ", " << key.second;
  }
  for (const auto& [key, d] : found)
    if (!expected.count(key)) ADD_FAILURE() << what << ": pair " << key.first << ", " << key.second << " is not within reach";
}

void check(const Grains& g, int dimension, const Container& c, double cutoff, int cells_per_cutoff) {
  const double px = wraps_x(c) ? c.size_x : 0.0, py = wraps_y(c, dimension) ? c.size_y : 0.0;
  const Pairs expected = brute_force(g, px, py, cutoff);
  ASSERT_GT(expected.size(), g.size() / 2) << "the case should have many pairs";
  const PairSearch s(g, dimension, c, cutoff, cells_per_cutoff);
  expect_same(from_each_pair(s), expected, "for_each_pair");
  expect_same(from_neighbours(s, g.size()), expected, "for_neighbours");
}

TEST(PairSearch, Periodic3DPolydisperse) {
  const Grains g = random_grains(700, 3, 12.0, 9.0, 6.0, 1);
  check(g, 3, test::periodic(12.0, 9.0), 2.0, 1);
  check(g, 3, test::periodic(12.0, 9.0), 5.0, 3);  // a cut-off of several diameters, searched 3 cells out
}

TEST(PairSearch, Periodic2DPolydisperse) {
  const Grains g = random_grains(400, 2, 20.0, 0.0, 8.0, 2);
  check(g, 2, test::periodic(20.0), 2.0, 1);
  check(g, 2, test::periodic(20.0), 4.5, 2);
  check(g, 2, test::periodic(20.0), 1.2, 3);  // cells never narrower than a grain: one cell out
}

TEST(PairSearch, PeriodsNarrowerThanTheCutoff) {
  // One or two cells per period: a neighbour's images lie in the same cells; the nearest one counts once.
  check(random_grains(200, 3, 1.5, 3.1, 12.0, 3), 3, test::periodic(1.5, 3.1), 2.0, 1);
  check(random_grains(120, 2, 2.5, 0.0, 20.0, 4), 2, test::periodic(2.5), 6.0, 3);
}

TEST(PairSearch, CentresOutsideTheCellWrap) {
  Grains g = random_grains(400, 3, 10.0, 10.0, 5.0, 5);
  for (std::size_t i = 0; i < g.size(); i += 3) g[i].x.x() += 10.0 * ((i % 2) ? 1 : -2);  // other images
  check(g, 3, test::periodic(10.0, 10.0), 2.0, 1);
}

TEST(PairSearch, DrumWithPeriodicEndsWrapsAlongItsAxisOnly) {
  Container drum;
  drum.kind = ContainerKind::Drum;
  drum.radius = 5.0;
  drum.size_y = 8.0;
  drum.periodic_ends = true;
  check(random_grains(500, 3, 10.0, 8.0, 10.0, 6), 3, drum, 2.0, 1);
}

TEST(PairSearch, BoundedAndOpenContainersDoNotWrap) {
  check(random_grains(500, 3, 8.0, 8.0, 8.0, 7), 3, test::box(8.0, 8.0), 2.0, 1);
  check(random_grains(300, 2, 30.0, 0.0, 5.0, 8), 2, Container{}, 4.0, 2);
}

TEST(PairSearch, GrainsFarFromTheRestKeepEveryPair) {
  // A few grains astronomically far out: the cells are kept sparse, and pairs out there are found too.
  Grains g = random_grains(300, 3, 8.0, 8.0, 8.0, 9);
  for (std::size_t i = 0; i < 6; ++i) g[i].x = Vec3(1e6 + 0.5 * i, -3e5, 2e4 + 0.3 * i);
  check(g, 3, Container{}, 2.0, 1);
}

TEST(PairSearch, NoGrainsAndOneGrain) {
  const PairSearch none(Grains{}, 3, test::periodic(1.0, 1.0), 1.0);
  int calls = 0;
  none.for_each_pair([&](std::size_t, std::size_t, const Vec3&) { ++calls; });
  Grains one(1);
  one[0].r = 1.0;
  const PairSearch single(one, 3, test::periodic(1.0, 1.0), 2.0);
  single.for_each_pair([&](std::size_t, std::size_t, const Vec3&) { ++calls; });
  single.for_neighbours(0, [&](std::size_t, const Vec3&) { ++calls; });
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace btr
