// The periodic wrap of btr/model/container.h: coordinates into [-L/2, L/2), separations to their nearest image.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "btr/model/container.h"
#include "containers.h"

namespace btr {
namespace {

TEST(PeriodicWrap, CoordinatesLandInTheHalfOpenDomain) {
  const double L = 0.03;
  const double below_half = std::nextafter(0.5 * L, 0.0);
  for (double x : {0.0, 0.01, -0.01, 0.5 * L, -0.5 * L, below_half, -below_half, 1.5 * L, -1.5 * L,
                   7.25 * L, -7.25 * L, 1e6 * L + 0.3 * L, std::nextafter(-0.5 * L, -1.0)}) {
    const double w = wrap_coordinate(x, L);
    EXPECT_GE(w, -0.5 * L) << x;
    EXPECT_LT(w, 0.5 * L) << x;
    const double k = (x - w) / L;  // a whole number of periods moved
    EXPECT_NEAR(k, std::round(k), 1e-6) << x;
  }
  EXPECT_EQ(wrap_coordinate(0.01, L), 0.01);  // inside: unchanged, to the bit
  EXPECT_EQ(wrap_coordinate(0.5 * L, L), -0.5 * L);
  // a hair below L/2 may come out at -L/2: the same point of the cell, to round-off
  EXPECT_NEAR(std::abs(wrap_coordinate(below_half, L)), 0.5 * L, 1e-17);
}

TEST(PeriodicWrap, SeparationsTakeTheNearestImage) {
  const double L = 2.0;
  EXPECT_EQ(minimum_image(0.7, L), 0.7);
  EXPECT_EQ(minimum_image(-1.0, L), -1.0);  // half a period: kept as it is
  EXPECT_DOUBLE_EQ(minimum_image(1.5, L), -0.5);
  EXPECT_DOUBLE_EQ(minimum_image(-1.5, L), 0.5);
  EXPECT_NEAR(minimum_image(6.1, L), 0.1, 1e-14);
  EXPECT_NEAR(minimum_image(-6.1, L), -0.1, 1e-14);
}

TEST(PeriodicWrap, OnlyTheContainersPeriodicAxesWrap) {
  const Vec3 x(0.8, -0.9, 5.0);
  const Vec3 p = wrap_into_cell(test::periodic(1.0, 1.0), 3, x);
  EXPECT_DOUBLE_EQ(p.x(), -0.2);
  EXPECT_DOUBLE_EQ(p.y(), 0.1);
  EXPECT_EQ(p.z(), 5.0);
  EXPECT_EQ(wrap_into_cell(test::box(1.0, 1.0), 3, x), x);
  EXPECT_EQ(wrap_into_cell(test::periodic(1.0, 1.0), 2, x).y(), -0.9);  // 2D: only x wraps
  Container drum;
  drum.kind = ContainerKind::Drum;
  drum.size_y = 1.0;
  drum.periodic_ends = true;
  const Vec3 q = wrap_into_cell(drum, 3, x);
  EXPECT_EQ(q.x(), 0.8);
  EXPECT_DOUBLE_EQ(q.y(), 0.1);
  EXPECT_EQ(period_along(drum, 3, 0), 0.0);
  EXPECT_EQ(period_along(drum, 3, 1), 1.0);
  EXPECT_EQ(period_along(test::periodic(2.0, 3.0), 2, 1), 0.0);
}

}  // namespace
}  // namespace btr
