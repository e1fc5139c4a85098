// The block estimate of the bulk packing fraction's standard error, on configurations worked out by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "btr/measures/block_error.h"
#include "containers.h"

namespace btr {
namespace {

constexpr double kPi = 3.14159265358979323846;

Grain grain(double x, double y, double z, double r) {
  Grain g;
  g.x = Vec3(x, y, z);
  g.r = r;
  return g;
}

// The slab window bulk_measures gives a periodic bed: the whole period, z in [z0, z1].
BulkMeasures slab(double lx, double ly, double z0, double z1) {
  BulkMeasures m;
  m.valid = true;
  m.slab = true;
  m.window.lo = Vec3(-0.5 * lx, -0.5 * ly, z0);
  m.window.hi = Vec3(0.5 * lx, 0.5 * ly, z1);
  return m;
}

TEST(BlockError, OneGrainInOneOfEightBlocksGivesAnEighthOfItsBlocksPackingFraction) {
  // blocks 1 x 1 x 1: one sphere of radius 0.3 inside the block x, y in [-1, 0], z in [0, 1]
  const double r = 0.3, p = 4.0 / 3.0 * kPi * r * r * r;
  const BlockError e = bulk_phi_block_error({grain(-0.5, -0.5, 0.5, r)}, 3, test::periodic(2.0, 2.0), slab(2, 2, 0, 2));
  ASSERT_TRUE(e.valid) << e.note;
  ASSERT_EQ(e.block_phi.size(), 8u);
  int occupied = 0;
  for (double b : e.block_phi) occupied += b > 0.0;
  EXPECT_EQ(occupied, 1);
  // values p, 0 x 7: mean p/8, sample sd p sqrt(((7/8)^2 + 7 (1/8)^2) / 7) = p / sqrt(8), over sqrt(8): p / 8
  EXPECT_NEAR(e.standard_error, p / 8.0, 1e-12);
}

TEST(BlockError, AGrainAcrossThePeriodCountsWhollyThroughItsImage) {
  const double r = 0.4;
  for (const Grain& g : {grain(-0.9, 0.2, 0.5, r), grain(0.95, -0.97, 1.0, r)}) {  // across x; across x, y, a layer
    const BlockError e = bulk_phi_block_error({g}, 3, test::periodic(2.0, 2.0), slab(2, 2, 0, 2));
    ASSERT_TRUE(e.valid);
    double solid = 0.0;
    for (double b : e.block_phi) solid += b * 1.0;  // blocks of unit volume
    EXPECT_NEAR(solid, 4.0 / 3.0 * kPi * r * r * r, 1e-9) << g.x.transpose();
  }
}

TEST(BlockError, ALatticeWhoseBlocksAreAlikeHasNoScatter) {
  // simple cubic lattice of touching spheres, spacing a: every 2a x 2a x 2a block holds 8 whole spheres, pi/6
  const double a = 1.0, r = 0.5;
  Grains g;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) g.push_back(grain(-2.0 + (i + 0.5) * a, -2.0 + (j + 0.5) * a, (k + 0.5) * a, r));
  const BlockError e = bulk_phi_block_error(g, 3, test::periodic(4.0, 4.0), slab(4, 4, 0, 4));
  ASSERT_TRUE(e.valid);
  for (double b : e.block_phi) EXPECT_NEAR(b, kPi / 6.0, 1e-12);
  EXPECT_LT(e.standard_error, 1e-12);
}

TEST(BlockError, TwoDimensionsSplitTheLineInFourColumns) {
  // disks of radius 0.2, one per column of width 1 but two in the first: areas pi r^2 over blocks 1 x 1
  const double r = 0.2, a = kPi * r * r;
  Grains g = {grain(-1.5, 0, 0.5, r), grain(-1.5, 0, 1.5, r), grain(-0.5, 0, 0.5, r), grain(0.5, 0, 0.5, r),
              grain(1.5, 0, 0.5, r)};
  const BlockError e = bulk_phi_block_error(g, 2, test::periodic(4.0), slab(4, 0, 0, 2));
  ASSERT_TRUE(e.valid);
  ASSERT_EQ(e.block_phi.size(), 8u);
  // values a x 5, 0 x 3: mean 5a/8, squares 5 (3a/8)^2 + 3 (5a/8)^2 = 120 a^2 / 64, sd sqrt(120/64/7) a
  EXPECT_NEAR(e.standard_error, std::sqrt(120.0 / 64.0 / 7.0) * a / std::sqrt(8.0), 1e-12);
}

TEST(BlockError, OnlyAPeriodicBedsSlabHasBlocks) {
  const Grains g = {grain(0, 0, 0.5, 0.3)};
  EXPECT_FALSE(bulk_phi_block_error(g, 3, test::box(2.0, 2.0), slab(2, 2, 0, 2)).valid);
  BulkMeasures none = slab(2, 2, 0, 2);
  none.valid = false;
  EXPECT_FALSE(bulk_phi_block_error(g, 3, test::periodic(2.0, 2.0), none).valid);
}

}  // namespace
}  // namespace btr
