// Stratification measure on heaps built by hand: sites on a jittered square lattice under a 30-degree
// line leaning on an end wall, each holding a small (r = 0.25 mm) or a large (0.5 mm) grain. The species
// are placed at random (mixed), in bands parallel to the slope of a known period (striped), or small
// near the top and large at the toe (segregated).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "btr/measures/metrics.h"
#include "btr/measures/stratification.h"

namespace btr {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTheta = 30.0, kApex = 0.04, kSite = 1e-3, kSmall = 0.25e-3, kLarge = 0.5e-3;

// rule(x, z, depth below the built line, u / foot) -> true for a small grain. 2D: disks in x-z; 3D: a
// Hele-Shaw cell three sites wide.
Grains build_heap(int dimension, std::uint64_t seed, const std::function<bool(double, double, double, double)>& rule) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.1 * kSite, 0.1 * kSite);
  const double t = std::tan(kTheta * kPi / 180.0), c = std::cos(kTheta * kPi / 180.0), foot = kApex / t;
  Grains g;
  const int ny = dimension == 3 ? 3 : 1;
  for (double x = 0.5 * kSite; x < foot; x += kSite)
    for (double z = 0.5 * kSite; z < kApex - x * t - 0.5 * kSite; z += kSite)
      for (int j = 0; j < ny; ++j) {
        Grain q;
        q.x = Vec3(x + jitter(rng), dimension == 3 ? (j - 1) * kSite : 0.0, z + jitter(rng));
        const bool small = rule(x, z, c * (kApex - x * t - z), x / foot);
        q.r = small ? kSmall : kLarge;
        q.species = small ? 1 : 2;
        g.push_back(q);
      }
  return g;
}

Stratification measure(const Grains& g, int dimension) {
  const HeapMeasures h = heap_measures(g, dimension, 0.0, 0.0, true);
  EXPECT_TRUE(h.valid) << h.note;
  return stratification_measures(g, dimension, h, 0.0, 0.0);
}

double mean_diameter(const Grains& g) {
  double s = 0.0;
  for (const Grain& q : g) s += 2.0 * q.r;
  return s / double(g.size());
}

TEST(Stratification, MixedHeapHasNoWavelengthAndNoContrast) {
  for (int dimension : {2, 3})
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      std::mt19937_64 coin(100 + seed);
      const Grains g = build_heap(dimension, seed, [&](double, double, double, double) { return coin() % 2 == 0; });
      const Stratification s = measure(g, dimension);
      ASSERT_TRUE(s.valid) << s.note;
      EXPECT_EQ(s.small_species, 1);
      EXPECT_EQ(s.large_species, 2);
      EXPECT_FALSE(s.has_wavelength) << "dim " << dimension << " seed " << seed << ": " << s.wavelength_d;
      EXPECT_EQ(s.contrast, 0.0) << "sigma " << s.sigma << " threshold " << s.sigma_threshold;
      EXPECT_LT(s.fluctuation_ratio, 1.5);
      ASSERT_TRUE(s.top_toe_valid);
      EXPECT_LT(std::abs(s.top_toe_index), 4.0 * s.top_toe_noise + 1e-12);
      // both species see the built 30-degree flank
      ASSERT_EQ(s.species_angles.size(), 2u);
      for (const SpeciesAngle& a : s.species_angles) {
        EXPECT_TRUE(a.valid);
        EXPECT_NEAR(a.angle_deg, kTheta, 3.0) << "species " << a.species;
      }
    }
}

TEST(Stratification, StripedHeapGivesItsPeriod) {
  for (int dimension : {2, 3})
    for (double period : {6e-3, 4e-3}) {
      const Grains g = build_heap(dimension, 7, [&](double, double, double depth, double) {
        return static_cast<long>(std::floor(depth / (0.5 * period))) % 2 == 0;
      });
      const Stratification s = measure(g, dimension);
      ASSERT_TRUE(s.valid) << s.note;
      const double expected_d = period / mean_diameter(g);
      ASSERT_TRUE(s.has_wavelength) << "peak " << s.peak_autocorrelation << " threshold " << s.peak_threshold;
      EXPECT_NEAR(s.wavelength_d, expected_d, s.options.layer_d) << "dim " << dimension;
      EXPECT_GT(s.contrast, 0.5);
      EXPECT_GT(s.fluctuation_ratio, 3.0);
    }
}

// A conical heap on an open floor (3D, measured against the distance from the axis) striped in depth.
TEST(Stratification, StripedConicalHeapGivesItsPeriod) {
  const double apex = 0.02, t = std::tan(kTheta * kPi / 180.0), c = std::cos(kTheta * kPi / 180.0);
  const double period = 2.5e-3, foot = apex / t;  // a cone keeps fewer layers: its deep layers lie nearer the axis
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-0.1 * kSite, 0.1 * kSite);
  Grains g;
  for (double x = -foot; x < foot; x += kSite)
    for (double y = -foot; y < foot; y += kSite)
      for (double z = 0.5 * kSite; z < apex - std::hypot(x, y) * t - 0.5 * kSite; z += kSite) {
        Grain q;
        q.x = Vec3(x + jitter(rng), y + jitter(rng), z + jitter(rng));
        const double depth = c * (apex - std::hypot(x, y) * t - z);
        const bool small = static_cast<long>(std::floor(depth / (0.5 * period))) % 2 == 0;
        q.r = small ? kSmall : kLarge;
        q.species = small ? 1 : 2;
        g.push_back(q);
      }
  const HeapMeasures h = heap_measures(g, 3, 0.0, 0.0, false);
  ASSERT_TRUE(h.valid) << h.note;
  ASSERT_TRUE(h.line_radial.valid);
  const Stratification s = stratification_measures(g, 3, h, 0.0, 0.0);
  ASSERT_TRUE(s.valid) << s.note;
  ASSERT_EQ(s.flanks, std::vector<std::string>{"radial"});
  ASSERT_TRUE(s.has_wavelength) << "peak " << s.peak_autocorrelation << " threshold " << s.peak_threshold
                                << " layers " << s.layer_small_fraction.size();
  EXPECT_NEAR(s.wavelength_d, period / mean_diameter(g), s.options.layer_d);
  EXPECT_GT(s.contrast, 0.5);
}

TEST(Stratification, SmallGrainsAtTheTopGivePositiveTopToeIndex) {
  const Grains g = build_heap(2, 5, [](double, double, double, double u) { return u < 0.5; });
  const Stratification s = measure(g, 2);
  ASSERT_TRUE(s.valid) << s.note;
  ASSERT_TRUE(s.top_toe_valid);
  EXPECT_GT(s.small_fraction_top, 0.95);
  EXPECT_LT(s.small_fraction_toe, 0.05);
  EXPECT_GT(s.top_toe_index, 10.0 * s.top_toe_noise);
  // the layers follow the slope, so this heap is not striped across them
  EXPECT_FALSE(s.has_wavelength);
}

TEST(Stratification, SameHeapSameNumbers) {
  const Grains g = build_heap(2, 9, [](double x, double, double, double) { return std::fmod(x, 3e-3) < 1.5e-3; });
  const Stratification a = measure(g, 2), b = measure(g, 2);
  ASSERT_TRUE(a.valid);
  EXPECT_EQ(a.sigma_threshold, b.sigma_threshold);
  EXPECT_EQ(a.peak_threshold, b.peak_threshold);
  EXPECT_EQ(a.top_toe_noise, b.top_toe_noise);
}

TEST(Stratification, OneSpeciesOrNoFlankIsNotMeasured) {
  Grains g = build_heap(2, 3, [](double, double, double, double) { return false; });
  const Stratification one = measure(g, 2);
  EXPECT_FALSE(one.valid);
  EXPECT_NE(one.note.find("one species"), std::string::npos) << one.note;
  HeapMeasures flat;  // no fitted flank
  g.front().species = 1, g.front().r = kSmall;
  const Stratification none = stratification_measures(g, 2, flat, 0.0, 0.0);
  EXPECT_FALSE(none.valid);
  EXPECT_NE(none.note.find("no fitted flank"), std::string::npos) << none.note;
}

}  // namespace
}  // namespace btr
