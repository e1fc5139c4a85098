#pragma once
// Small dense non-negative least squares (Lawson and Hanson, "Solving Least Squares Problems", ch. 23)
// for the rigid-cluster placement: the descent direction and the rest projection.
#include <Eigen/Dense>
#include <optional>

namespace btr {

// argmin |A x - b| over x >= 0 (Lawson-Hanson active set).
Eigen::VectorXd nnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b);

// Least distance programming: argmin |x| subject to G x >= h, or nothing when the constraints are
// incompatible. Solved through nnls on [G^T; h^T] (Lawson-Hanson's LDP), with h scaled to unit size
// and each constraint to unit length first, so that nnls's absolute tolerance neither swallows tiny
// right-hand sides nor grows with far, irrelevant constraints.
std::optional<Eigen::VectorXd> least_distance(const Eigen::MatrixXd& G, const Eigen::VectorXd& h);

}  // namespace btr
