// Random packings of every container kind, checked by the independent self-check: no overlap,
// every grain supported, every grain inside. Each packing is then broken on purpose to show the
// check would have noticed. Drops come from a generator local to this file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "btr/placement/deposition.h"
#include "btr/verify/check.h"

namespace btr {
namespace {

enum class Sizes { Mono, Poly, Wide };

struct Case {
  int dim;
  ContainerKind kind;
  Sizes sizes;
  int count;
};

std::string name_of(const Case& c) {
  static const char* sizes[] = {"mono", "poly", "wide"};
  return std::to_string(c.dim) + "d_" + to_string(c.kind) + "_" + sizes[int(c.sizes)];
}

class Uniform {
 public:
  explicit Uniform(std::uint64_t seed) : gen_(seed) {}
  double operator()() { return double(gen_() >> 11) * 0x1.0p-53; }  // [0, 1)

 private:
  std::mt19937_64 gen_;
};

constexpr double kRmax = 1e-3;

double radius(Sizes s, Uniform& u) {
  switch (s) {
    case Sizes::Mono: return kRmax;
    case Sizes::Poly: return kRmax * (0.6 + 0.4 * u());
    case Sizes::Wide: {  // constant-mass law with r_max / r_min = 8
      const double rmin = kRmax / 8;
      return rmin * kRmax / (kRmax - u() * (kRmax - rmin));
    }
  }
  return kRmax;
}

Container container_for(const Case& c) {
  Container k;
  k.kind = c.kind;
  const double L = 16 * kRmax;  // small floors, so that grains stack several layers
  switch (c.kind) {
    case ContainerKind::Open: break;
    case ContainerKind::Box:
    case ContainerKind::Periodic:
      k.size_x = c.dim == 2 ? 2 * L : L;
      k.size_y = c.dim == 2 ? 0 : L;
      break;
    case ContainerKind::HeleShaw:
      k.size_x = 2 * L;
      k.gap = 3 * kRmax;  // 1.5 largest diameters: grains pass each other only partly
      break;
    case ContainerKind::Cylinder: k.radius = 0.6 * L; break;
    case ContainerKind::Drum:  // filled to about a third, so that the grains pile up against the wall
      k.radius = c.dim == 2 ? 2 * L : L;
      k.size_y = c.dim == 2 ? 0 : 0.75 * L;
      break;
    case ContainerKind::Mesh: break;  // not among these cases: triangle meshes have tests/btr/test_mesh.cpp
  }
  return k;
}

// Drops inside the container; the open container gets a point source (a heap).
std::vector<Drop> drops_for(const Case& c, const Container& k, std::uint64_t seed) {
  Uniform u(seed);
  std::vector<Drop> d(c.count);
  for (Drop& q : d) {
    q.r = radius(c.sizes, u);
    q.species = q.r > 0.5 * kRmax ? 1 : 2;
    switch (c.kind) {
      case ContainerKind::Open: {
        const double rho = 2 * kRmax * std::sqrt(u()), a = 2 * M_PI * u();
        q.x = rho * std::cos(a);
        q.y = c.dim == 3 ? rho * std::sin(a) : 0.0;
        break;
      }
      case ContainerKind::Periodic:
        q.x = (u() - 0.5) * k.size_x;
        q.y = c.dim == 3 ? (u() - 0.5) * k.size_y : 0.0;
        break;
      case ContainerKind::Box:
        q.x = (u() - 0.5) * (k.size_x - 2 * q.r);
        q.y = c.dim == 3 ? (u() - 0.5) * (k.size_y - 2 * q.r) : 0.0;
        break;
      case ContainerKind::HeleShaw:
        q.x = (u() - 0.5) * (k.size_x - 2 * q.r);
        q.y = (u() - 0.5) * (k.gap - 2 * q.r);
        break;
      case ContainerKind::Cylinder: {
        const double rho = (k.radius - q.r) * std::sqrt(u()), a = 2 * M_PI * u();
        q.x = rho * std::cos(a);
        q.y = rho * std::sin(a);
        break;
      }
      case ContainerKind::Drum:
        q.x = (u() - 0.5) * 2 * (k.radius - q.r);
        q.y = c.dim == 3 ? (u() - 0.5) * (k.size_y - 2 * q.r) : 0.0;
        break;
      case ContainerKind::Mesh: break;  // not among these cases
    }
  }
  return d;
}

Grains deposit(const Case& c, const Container& k, const std::vector<Drop>& drops) {
  Deposition dep(c.dim, k, kRmax);
  for (const Drop& q : drops) dep.place(q);
  return dep.grains();
}

std::string describe(const CheckReport& rep) {
  std::string s = "overlaps " + std::to_string(rep.overlaps) + " (max " + std::to_string(rep.max_overlap) +
                  "), unsupported " + std::to_string(rep.unsupported) + ", outside " +
                  std::to_string(rep.outside) + ", e.g. ids";
  for (auto id : rep.examples) s += " " + std::to_string(id);
  return s;
}

class Invariants : public ::testing::TestWithParam<Case> {};

TEST_P(Invariants, PackingIsValidAndBreakingItIsCaught) {
  const Case c = GetParam();
  const Container k = container_for(c);
  const std::vector<Drop> drops = drops_for(c, k, 12345 + c.count);
  const Grains g = deposit(c, k, drops);
  ASSERT_EQ(g.size(), drops.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    ASSERT_EQ(g[i].r, drops[i].r) << "grain " << i + 1;
    ASSERT_EQ(g[i].species, drops[i].species) << "grain " << i + 1;
    if (c.dim == 2) {
      ASSERT_EQ(g[i].x.y(), 0.0) << "grain " << i + 1;
    }
  }

  const CheckReport rep = check_packing(g, c.dim, k, 1e-9, 1e-7);
  EXPECT_TRUE(rep.ok()) << describe(rep);
  EXPECT_LT(rep.max_overlap, 1e-9);
  // Not trivially a single layer: grains were stacked.
  std::size_t off_floor = 0;
  double top = 0;
  for (const Grain& q : g) {
    off_floor += q.x.z() - q.r > 0.01 * q.r;
    top = std::max(top, q.x.z() - q.r);
  }
  EXPECT_GT(off_floor, g.size() / 4);
  EXPECT_GT(top, 2 * kRmax);

  // Broken on purpose. 1) The last grain lifted by 1% of its radius hovers (nothing rests on it).
  {
    Grains b = g;
    b.back().x.z() += 0.01 * b.back().r;
    const CheckReport br = check_packing(b, c.dim, k);
    EXPECT_EQ(br.unsupported, 1) << describe(br);
    EXPECT_NE(std::find(br.examples.begin(), br.examples.end(), std::int64_t(b.size())), br.examples.end());
  }
  // 2) A grain pushed 5% of the smaller radius into its nearest neighbour overlaps it.
  {
    Grains b = g;
    const std::size_t i = b.size() / 2;
    std::size_t best = i == 0 ? 1 : 0;
    double best_gap = INFINITY;
    for (std::size_t j = 0; j < b.size(); ++j) {
      if (j == i) continue;
      Vec3 d = b[j].x - b[i].x;
      if (k.kind == ContainerKind::Periodic) {
        d.x() -= k.size_x * std::round(d.x() / k.size_x);
        if (c.dim == 3) d.y() -= k.size_y * std::round(d.y() / k.size_y);
      }
      const double gap = d.norm() - b[i].r - b[j].r;
      if (gap < best_gap) best_gap = gap, best = j;
    }
    Vec3 d = b[best].x - b[i].x;
    if (k.kind == ContainerKind::Periodic) {
      d.x() -= k.size_x * std::round(d.x() / k.size_x);
      if (c.dim == 3) d.y() -= k.size_y * std::round(d.y() / k.size_y);
    }
    b[i].x += (best_gap + 0.05 * std::min(b[i].r, b[best].r)) * d.normalized();
    const CheckReport br = check_packing(b, c.dim, k);
    EXPECT_GE(br.overlaps, 1) << describe(br);
    EXPECT_GT(br.max_overlap, 0.04);
  }
  // 3) A grain through the floor, or through the wall where there is one, is outside.
  {
    Grains b = g;
    Grain& q = b[b.size() / 3];
    switch (k.kind) {
      case ContainerKind::Open:
      case ContainerKind::Periodic: q.x.z() = 0.5 * q.r; break;
      case ContainerKind::Box:
      case ContainerKind::HeleShaw: q.x.x() = 0.5 * k.size_x - 0.5 * q.r; break;
      case ContainerKind::Cylinder: q.x.x() = k.radius - 0.5 * q.r, q.x.y() = 0; break;
      case ContainerKind::Drum: q.x.x() = k.radius - 0.5 * q.r, q.x.z() = k.radius; break;  // through the wall
      case ContainerKind::Mesh: break;  // not among these cases
    }
    const CheckReport br = check_packing(b, c.dim, k);
    EXPECT_GE(br.outside, 1) << describe(br);
  }
}

std::vector<Case> all_cases() {
  std::vector<Case> v;
  for (Sizes s : {Sizes::Mono, Sizes::Poly, Sizes::Wide}) {
    for (ContainerKind kind : {ContainerKind::Open, ContainerKind::Box, ContainerKind::Periodic})
      v.push_back({2, kind, s, 2000});
    for (ContainerKind kind : {ContainerKind::Open, ContainerKind::Box, ContainerKind::Periodic,
                               ContainerKind::HeleShaw, ContainerKind::Cylinder})
      v.push_back({3, kind, s, 2000});
    v.push_back({2, ContainerKind::Drum, s, 350});
    v.push_back({3, ContainerKind::Drum, s, 400});
  }
  return v;
}

INSTANTIATE_TEST_SUITE_P(AllContainers, Invariants, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           std::string n = name_of(info.param);
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

TEST(HeleShawTwoDiameters, GrainsOnTopOfTwoSupportsBlockedOnBothSidesRest) {
  // Equal spheres between plates exactly two diameters apart, poured from one end: many grains touch a
  // plate, so their supports lie in one vertical plane and a grain can sit on top of two of them with
  // the plate on one side and a grain on the other. It cannot roll off either way, so it rests there.
  // (Seeds 6 and 17 once ran out of events: "no stable position after 10000 events".)
  Container k;
  k.kind = ContainerKind::HeleShaw;
  k.size_x = 140 * kRmax;
  k.gap = 4 * kRmax;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Uniform u(seed);
    std::vector<Drop> drops(1500);
    for (Drop& q : drops) {
      q.r = kRmax;
      q.x = -0.47 * k.size_x + 0.48 * kRmax * (2 * u() - 1);
      q.y = (k.gap / 2 - kRmax) * (2 * u() - 1);
    }
    Deposition dep(3, k, kRmax);
    try {
      for (const Drop& q : drops) dep.place(q);
    } catch (const PlacementError& e) {
      ADD_FAILURE() << "seed " << seed << ": " << e.what();
      continue;
    }
    const Grains& g = dep.grains();
    const CheckReport rep = check_packing(g, 3, k, 1e-9, 1e-7);
    EXPECT_TRUE(rep.ok()) << "seed " << seed << ": " << describe(rep);
    std::size_t on_plates = 0;
    for (const Grain& q : g) on_plates += std::abs(std::abs(q.x.y()) - (k.gap / 2 - q.r)) < 1e-12 * q.r;
    EXPECT_GT(on_plates, g.size() / 2) << "seed " << seed;  // most grains against a plate: the case described
  }
}

TEST(Determinism, SameDropsGiveBitIdenticalGrains) {
  for (const Case c : {Case{3, ContainerKind::Periodic, Sizes::Wide, 1500},
                       Case{2, ContainerKind::Box, Sizes::Poly, 1000},
                       Case{3, ContainerKind::Cylinder, Sizes::Poly, 800}}) {
    const Container k = container_for(c);
    const std::vector<Drop> drops = drops_for(c, k, 99);
    const Grains a = deposit(c, k, drops), b = deposit(c, k, drops);
    ASSERT_EQ(a.size(), b.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double pa[4] = {a[i].x.x(), a[i].x.y(), a[i].x.z(), a[i].r};
      const double pb[4] = {b[i].x.x(), b[i].x.y(), b[i].x.z(), b[i].r};
      if (std::memcmp(pa, pb, sizeof pa) != 0 || a[i].species != b[i].species) ++differing;
    }
    EXPECT_EQ(differing, 0u) << name_of(c);
    // A different drop list gives a different packing (the comparison is not vacuous).
    const Grains other = deposit(c, k, drops_for(c, k, 100));
    EXPECT_NE(std::memcmp(&other[0].x[0], &a[0].x[0], 3 * sizeof(double)), 0);
  }
}

}  // namespace
}  // namespace btr
