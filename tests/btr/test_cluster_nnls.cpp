// Least-distance programming (the rigid-cluster rest projection): hand cases with known answers.
#include <gtest/gtest.h>

#include "btr/placement/nnls.h"

namespace btr {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

VectorXd vec(std::initializer_list<double> v) {
  VectorXd x(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double a : v) x(i++) = a;
  return x;
}

TEST(ClusterNnls, NonNegativeLeastSquaresClipsAtZero) {
  // min |x - (1, -2)| over x >= 0 is (1, 0); with a column coupling them, the free optimum (2, -1)
  // is not allowed and the best is x2 = 0, x1 = (b . a1) / |a1|^2.
  EXPECT_TRUE(nnls(MatrixXd::Identity(2, 2), vec({1, -2})).isApprox(vec({1, 0})));
  MatrixXd A(2, 2);
  A << 1, 1, 0, 1;
  const VectorXd x = nnls(A, vec({1, -1}));
  EXPECT_NEAR(x(0), 1.0, 1e-14);
  EXPECT_EQ(x(1), 0.0);
}

TEST(ClusterNnls, LeastDistanceFindsTheNearestFeasiblePoint) {
  // x1 >= 1, x2 >= 2: the corner.
  auto x = least_distance(MatrixXd::Identity(2, 2), vec({1, 2}));
  ASSERT_TRUE(x);
  EXPECT_NEAR((*x - vec({1, 2})).norm(), 0.0, 1e-14);
  // x1 + x2 >= 2 and x1 >= -5: the foot of the perpendicular onto the first line, (1, 1).
  MatrixXd G(2, 2);
  G << 1, 1, 1, 0;
  x = least_distance(G, vec({2, -5}));
  ASSERT_TRUE(x);
  EXPECT_NEAR((*x - vec({1, 1})).norm(), 0.0, 1e-14);
  // Right-hand sides of the size of a contact's penetration (1e-13 m) are not lost in tolerances.
  x = least_distance(MatrixXd::Identity(2, 2), vec({3e-13, -1}));
  ASSERT_TRUE(x);
  EXPECT_NEAR((*x)(0), 3e-13, 1e-27);
  EXPECT_EQ((*x)(1), 0.0);
  // ... nor when a far obstacle's constraint (x1 + x2 >= -1e3) is listed with them.
  MatrixXd H(3, 2);
  H << 1, 0, 0, 1, 1, 1;
  x = least_distance(H, vec({2e-12, 1e-12, -1e3}));
  ASSERT_TRUE(x);
  EXPECT_NEAR((*x)(0), 2e-12, 1e-26);
  EXPECT_NEAR((*x)(1), 1e-12, 1e-26);
}

TEST(ClusterNnls, LeastDistanceOfSatisfiedOrIncompatibleConstraints) {
  const auto zero = least_distance(MatrixXd::Identity(3, 3), vec({-1, 0, -2}));
  ASSERT_TRUE(zero);
  EXPECT_EQ(zero->norm(), 0.0);
  MatrixXd G(2, 1);
  G << 1, -1;  // x >= 1 and -x >= 0
  EXPECT_FALSE(least_distance(G, vec({1, 0})));
  // No unknowns left (the loaded contacts fix every motion): feasible only if nothing is violated.
  EXPECT_TRUE(least_distance(MatrixXd(1, 0), vec({-1})));
  EXPECT_FALSE(least_distance(MatrixXd(1, 0), vec({1e-14})));
}

}  // namespace
}  // namespace btr
