// The drop generator: radius laws, mixture fractions, drop positions, determinism.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>

#include "btr/placement/drops.h"

namespace btr {
namespace {

RadiusSpec constant(double r) {
  RadiusSpec s;
  s.kind = RadiusSpec::Kind::Constant;
  s.value = r;
  return s;
}
RadiusSpec ranged(RadiusSpec::Kind kind, double a, double b) {
  RadiusSpec s;
  s.kind = kind;
  s.min = a;
  s.max = b;
  return s;
}

Component component(int species, double fraction, const RadiusSpec& r) {
  Component c;
  c.species = species;
  c.fraction = fraction;
  c.radius = r;
  return c;
}

Scene scene(int dim, std::int64_t count, std::vector<Component> comps, ContainerKind kind = ContainerKind::Box) {
  Scene s;
  s.dimension = dim;
  s.grains.count = count;
  s.grains.components = std::move(comps);
  s.container.kind = kind;
  s.container.size_x = 0.02;
  s.container.size_y = dim == 3 ? 0.03 : 0.0;
  s.container.gap = 3e-3;
  s.container.radius = 0.01;
  s.source.kind = SourceSpec::Kind::Rain;
  return s;
}

std::vector<Drop> draw_all(const Scene& s, std::uint64_t seed) {
  DropSequence q(s, seed);
  std::vector<Drop> out;
  for (std::int64_t i = 0; i < q.count(); ++i) out.push_back(q.next());
  return out;
}

TEST(Drops, ConstantMassMeanMatchesEq1) {
  // R = a b / (b - u (b - a)): E[R] = a b / (b - a) ln(b / a), E[R^2] = a b.
  const double a = 0.5e-3, b = 1.0e-3;
  const double mean = a * b / (b - a) * std::log(b / a);  // 0.693147e-3
  const double sd = std::sqrt(a * b - mean * mean);
  const int n = 200000;
  const auto drops = draw_all(scene(3, n, {component(1, 1, ranged(RadiusSpec::Kind::ConstantMass, a, b))}), 7);
  double sum = 0.0;
  for (const auto& d : drops) {
    ASSERT_GE(d.r, a);
    ASSERT_LT(d.r, b);
    sum += d.r;
  }
  EXPECT_NEAR(sum / n, 0.6931471805599453e-3, 5 * sd / std::sqrt(n));
  EXPECT_NEAR(radius_moment(ranged(RadiusSpec::Kind::ConstantMass, a, b), 1), 0.6931471805599453e-3, 1e-15);
}

TEST(Drops, ConstantMassPutsEqualDiskMassInEqualRadiusBins) {
  // In 2D a disk's mass goes as r^2 and Eq. 1 has number density ~ 1/r^2: equal mass per dr.
  const double a = 0.25e-3, b = 1.0e-3;
  const int n = 200000, bins = 10;
  const auto drops = draw_all(scene(2, n, {component(1, 1, ranged(RadiusSpec::Kind::ConstantMass, a, b))}), 3);
  std::vector<double> mass(bins, 0.0), count(bins, 0.0);
  for (const auto& d : drops) {
    const int k = std::min(bins - 1, static_cast<int>((d.r - a) / (b - a) * bins));
    mass[k] += d.r * d.r;
    count[k] += 1;
  }
  const double total = std::accumulate(mass.begin(), mass.end(), 0.0);
  for (int k = 0; k < bins; ++k) EXPECT_NEAR(mass[k] / total, 1.0 / bins, 0.05 / bins) << "bin " << k;
  // ... while the number of grains per bin falls by about (b/a)^2 = 16 from the first to the last.
  EXPECT_GT(count[0] / count[bins - 1], 8.0);
}

TEST(Drops, UniformRadiiFillTheirRange) {
  const auto drops = draw_all(scene(3, 50000, {component(1, 1, ranged(RadiusSpec::Kind::Uniform, 1e-3, 2e-3))}), 1);
  double sum = 0.0;
  for (const auto& d : drops) sum += d.r;
  // mean 1.5e-3, sd 1e-3 / sqrt(12)
  EXPECT_NEAR(sum / drops.size(), 1.5e-3, 5 * 1e-3 / std::sqrt(12.0 * drops.size()));
}

TEST(Drops, RadiusListIsCycledInOrder) {
  RadiusSpec l;
  l.kind = RadiusSpec::Kind::List;
  l.list = {1e-3, 2e-3, 1.5e-3};
  const auto drops = draw_all(scene(2, 7, {component(1, 1, l)}), 1);
  const double expect[] = {1e-3, 2e-3, 1.5e-3, 1e-3, 2e-3, 1.5e-3, 1e-3};
  for (int i = 0; i < 7; ++i) EXPECT_EQ(drops[i].r, expect[i]);
}

TEST(Drops, BidisperseVolumeFractionsIn3D) {
  // Equal volumes of r = 0.5 mm and r = 1 mm spheres: numbers go as 1/r^3, 8 : 1, so p2 = 1/9.
  Scene s = scene(3, 90000, {component(1, 0.5, constant(0.5e-3)), component(2, 0.5, constant(1.0e-3))});
  s.grains.fraction_by = GrainsSpec::FractionBy::Volume;
  const auto drops = draw_all(s, 11);
  long n2 = 0;
  for (const auto& d : drops) {
    ASSERT_EQ(d.r, d.species == 1 ? 0.5e-3 : 1.0e-3);
    n2 += d.species == 2;
  }
  const double p = 1.0 / 9.0, sd = std::sqrt(90000 * p * (1 - p));  // expected 10000 +- 94
  EXPECT_NEAR(static_cast<double>(n2), 10000.0, 5 * sd);
}

TEST(Drops, VolumeFractionsOfAPolydisperseComponent) {
  // Component 1: constant-mass on [0.5, 1] mm, mean R^3 = a b (a + b) / 2 = 0.375 mm^3;
  // component 2: 1.5 mm, R^3 = 3.375 mm^3. Volume 0.7 / 0.3 -> numbers 28/15 : 4/45, p2 = 1/22.
  Scene s = scene(3, 110000, {component(1, 0.7, ranged(RadiusSpec::Kind::ConstantMass, 0.5e-3, 1e-3)),
                              component(2, 0.3, constant(1.5e-3))});
  s.container.size_x = s.container.size_y = 0.1;
  s.grains.fraction_by = GrainsSpec::FractionBy::Volume;
  const auto f = number_fractions(s.grains, 3);
  EXPECT_NEAR(f[1], 1.0 / 22.0, 1e-12);
  const auto drops = draw_all(s, 5);
  double v[3] = {0, 0, 0};
  long n2 = 0;
  for (const auto& d : drops) v[d.species] += d.r * d.r * d.r, n2 += d.species == 2;
  EXPECT_NEAR(static_cast<double>(n2), 5000.0, 5 * std::sqrt(110000 * (1.0 / 22) * (21.0 / 22)));
  EXPECT_NEAR(v[2] / (v[1] + v[2]), 0.3, 0.015);  // sd about 0.003
}

TEST(Drops, BidisperseVolumeFractionsIn2DUseDiskAreas) {
  // Equal areas of r = 0.5 mm and r = 1 mm disks: numbers 4 : 1, p2 = 0.2.
  Scene s = scene(2, 50000, {component(1, 0.5, constant(0.5e-3)), component(2, 0.5, constant(1.0e-3))});
  s.grains.fraction_by = GrainsSpec::FractionBy::Volume;
  long n2 = 0;
  for (const auto& d : draw_all(s, 2)) n2 += d.species == 2;
  EXPECT_NEAR(static_cast<double>(n2), 10000.0, 5 * std::sqrt(50000 * 0.2 * 0.8));
}

TEST(Drops, NumberFractionsAreUsedAsGiven) {
  Scene s = scene(3, 40000, {component(1, 0.75, constant(0.5e-3)), component(2, 0.25, constant(1.0e-3))});
  long n2 = 0;
  for (const auto& d : draw_all(s, 2)) n2 += d.species == 2;
  EXPECT_NEAR(static_cast<double>(n2), 10000.0, 5 * std::sqrt(40000 * 0.25 * 0.75));
}

// Checks every drop lies where its grain fits and that the drops reach the edges of that area.
TEST(Drops, RainStaysInsideTheFootprint) {
  const RadiusSpec r = ranged(RadiusSpec::Kind::Uniform, 0.5e-3, 1.0e-3);
  for (auto kind : {ContainerKind::Box, ContainerKind::Periodic, ContainerKind::HeleShaw, ContainerKind::Cylinder,
                    ContainerKind::Drum}) {
    for (int dim : {2, 3}) {
      if (dim == 2 && (kind == ContainerKind::HeleShaw || kind == ContainerKind::Cylinder)) continue;
      SCOPED_TRACE(std::string(to_string(kind)) + " " + std::to_string(dim) + "D");
      const Scene s = scene(dim, 20000, {component(1, 1, r)}, kind);
      const Container& c = s.container;
      double x_lo = 1, x_hi = -1, inner = 0;
      for (const auto& d : draw_all(s, 9)) {
        if (dim == 2) {
          ASSERT_EQ(d.y, 0.0);
        }
        switch (kind) {
          case ContainerKind::Box:
            ASSERT_LE(std::abs(d.x), c.size_x / 2 - d.r);
            if (dim == 3) {
              ASSERT_LE(std::abs(d.y), c.size_y / 2 - d.r);
            }
            break;
          case ContainerKind::Periodic:
            ASSERT_GE(d.x, -c.size_x / 2);
            ASSERT_LT(d.x, c.size_x / 2);
            if (dim == 3) {
              ASSERT_GE(d.y, -c.size_y / 2);
              ASSERT_LT(d.y, c.size_y / 2);
            }
            break;
          case ContainerKind::HeleShaw:
            ASSERT_LE(std::abs(d.x), c.size_x / 2 - d.r);
            ASSERT_LE(std::abs(d.y), c.gap / 2 - d.r);
            break;
          case ContainerKind::Cylinder: {
            const double rho = std::hypot(d.x, d.y);
            ASSERT_LE(rho, c.radius - d.r);
            inner += rho < (c.radius - d.r) / 2;  // a quarter of the disk's area
            break;
          }
          case ContainerKind::Drum:  // across the drum's width; in 3D clear of its end walls (length size_y)
            ASSERT_LE(std::abs(d.x), c.radius - d.r);
            if (dim == 3) {
              ASSERT_LE(std::abs(d.y), c.size_y / 2 - d.r);
            }
            break;
          case ContainerKind::Open:
          case ContainerKind::Mesh: break;  // a mesh's drops: tests/btr/test_mesh.cpp
        }
        x_lo = std::min(x_lo, d.x), x_hi = std::max(x_hi, d.x);
      }
      const double reach = kind == ContainerKind::Cylinder || kind == ContainerKind::Drum ? c.radius - 1e-3
                           : kind == ContainerKind::Periodic ? c.size_x / 2
                                                             : c.size_x / 2 - 1e-3;
      EXPECT_LT(x_lo, -0.9 * reach);
      EXPECT_GT(x_hi, 0.9 * reach);
      if (kind == ContainerKind::Cylinder) {
        EXPECT_NEAR(inner / 20000, 0.25, 5 * std::sqrt(0.25 * 0.75 / 20000));
      }
    }
  }
}

TEST(Drops, PointSourceScattersOverADisk) {
  Scene s = scene(3, 20000, {component(1, 1, constant(1e-3))}, ContainerKind::Open);
  s.source.kind = SourceSpec::Kind::Point;
  s.source.x = 0.01, s.source.y = -0.02, s.source.scatter = 2e-3;
  double inner = 0, mx = 0, my = 0;
  for (const auto& d : draw_all(s, 4)) {
    const double rho = std::hypot(d.x - 0.01, d.y + 0.02);
    ASSERT_LE(rho, 2e-3);
    inner += rho < 1e-3;
    mx += d.x, my += d.y;
  }
  EXPECT_NEAR(inner / 20000, 0.25, 5 * std::sqrt(0.25 * 0.75 / 20000));
  EXPECT_NEAR(mx / 20000, 0.01, 5e-5);
  EXPECT_NEAR(my / 20000, -0.02, 5e-5);

  s.dimension = 2;  // a segment of half-length scatter
  for (const auto& d : draw_all(s, 4)) {
    ASSERT_EQ(d.y, 0.0);
    ASSERT_LE(std::abs(d.x - 0.01), 2e-3);
  }
}

TEST(Drops, RegionIsCoveredUniformly) {
  Scene s = scene(3, 20000, {component(1, 1, constant(0.5e-3))}, ContainerKind::HeleShaw);
  s.source.kind = SourceSpec::Kind::Region;
  s.source.x_min = -0.009, s.source.x_max = -0.006, s.source.y_min = -1e-3, s.source.y_max = 1e-3;
  double left = 0;
  for (const auto& d : draw_all(s, 4)) {
    ASSERT_GE(d.x, -0.009);
    ASSERT_LT(d.x, -0.006);
    ASSERT_GE(d.y, -1e-3);
    ASSERT_LT(d.y, 1e-3);
    left += d.x < -0.0075;
  }
  EXPECT_NEAR(left / 20000, 0.5, 5 * std::sqrt(0.25 / 20000));
}

TEST(Drops, ListSourceGivesTheRowsInOrder) {
  const auto dir = std::filesystem::temp_directory_path() / ("btr_test_drops_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string csv = (dir / "d.csv").string();
  std::ofstream(csv) << "x,r,species\n0.001,1e-3,1\n-0.002,2e-3,2\n0.003,1.5e-3,1\n";
  Scene s = scene(2, 2, {component(1, 0, constant(1e-3)), component(2, 0, constant(2e-3))});
  s.source.kind = SourceSpec::Kind::List;
  s.source.file = csv;
  DropSequence q(s, 1);
  EXPECT_EQ(q.count(), 2);
  const Drop a = q.next(), b = q.next();
  EXPECT_EQ(a.x, 0.001);
  EXPECT_EQ(a.r, 1e-3);
  EXPECT_EQ(a.species, 1);
  EXPECT_EQ(b.x, -0.002);
  EXPECT_EQ(b.r, 2e-3);
  EXPECT_EQ(b.species, 2);
  EXPECT_EQ(q.r_max(), 2e-3);  // of the rows used, not of the whole file
  EXPECT_THROW(q.next(), std::out_of_range);
  std::filesystem::remove_all(dir);
}

TEST(Drops, FirstDrawsFollowTheDocumentedOrder) {
  // Uniform radius, then x, then y of a region; doubles are (u64 >> 11) * 2^-53 of mt19937_64(seed).
  Scene s = scene(3, 1, {component(1, 1, ranged(RadiusSpec::Kind::Uniform, 1e-3, 2e-3))});
  s.source.kind = SourceSpec::Kind::Region;
  s.source.x_min = -0.005, s.source.x_max = 0.005, s.source.y_min = 0.0, s.source.y_max = 0.004;
  std::mt19937_64 g(42);
  auto u = [&] { return static_cast<double>(g() >> 11) / 9007199254740992.0; };
  const double r = 1e-3 + u() * 1e-3, x = -0.005 + u() * 0.01, y = u() * 0.004;
  const Drop d = DropSequence(s, 42).next();
  EXPECT_EQ(d.r, r);
  EXPECT_EQ(d.x, x);
  EXPECT_EQ(d.y, y);
}

TEST(Drops, SameSeedSameSequenceOtherSeedOther) {
  Scene s = scene(3, 2000, {component(1, 0.6, ranged(RadiusSpec::Kind::ConstantMass, 0.5e-3, 1e-3)),
                            component(2, 0.4, constant(0.8e-3))},
                  ContainerKind::Cylinder);
  const auto a = draw_all(s, 123), b = draw_all(s, 123), c = draw_all(s, 124);
  ASSERT_EQ(a.size(), b.size());
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(a[i].x == b[i].x && a[i].y == b[i].y && a[i].r == b[i].r && a[i].species == b[i].species)
        << "drop " << i;
    differ += a[i].x != c[i].x || a[i].r != c[i].r;
  }
  EXPECT_GT(differ, 1990);
}

TEST(Drops, RadiusBoundsOfTheSequence) {
  DropSequence q(scene(3, 10, {component(1, 0.5, ranged(RadiusSpec::Kind::Uniform, 0.4e-3, 0.6e-3)),
                               component(2, 0.5, constant(1.2e-3))}),
                 1);
  EXPECT_EQ(q.r_min(), 0.4e-3);
  EXPECT_EQ(q.r_max(), 1.2e-3);
}

}  // namespace
}  // namespace btr
