#include "btr/placement/nnls.h"

#include <algorithm>
#include <vector>

namespace btr {

using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

VecX nnls(const MatX& A, const VecX& b) {
  const int k = static_cast<int>(A.cols());
  VecX x = VecX::Zero(k);
  std::vector<char> passive(k, 0);
  const double tol = 1e-13 * std::max(1.0, A.norm()) * std::max(1.0, b.norm());
  for (int outer = 0; outer < 3 * k + 10; ++outer) {
    const VecX w = A.transpose() * (b - A * x);
    int j = -1;
    double best = tol;
    for (int i = 0; i < k; ++i)
      if (!passive[i] && w(i) > best) { best = w(i); j = i; }
    if (j < 0) break;
    passive[j] = 1;
    for (int inner = 0; inner < 3 * k + 10; ++inner) {
      std::vector<int> idx;
      for (int i = 0; i < k; ++i)
        if (passive[i]) idx.push_back(i);
      MatX sub(A.rows(), static_cast<Eigen::Index>(idx.size()));
      for (std::size_t a = 0; a < idx.size(); ++a) sub.col(a) = A.col(idx[a]);
      const VecX z = sub.completeOrthogonalDecomposition().solve(b);
      bool positive = true;
      for (Eigen::Index a = 0; a < z.size(); ++a) positive &= z(a) > 0.0;
      if (positive) {
        x.setZero();
        for (std::size_t a = 0; a < idx.size(); ++a) x(idx[a]) = z(a);
        break;
      }
      double alpha = 1.0;
      for (std::size_t a = 0; a < idx.size(); ++a)
        if (z(a) <= 0.0) alpha = std::min(alpha, x(idx[a]) / (x(idx[a]) - z(a)));
      for (std::size_t a = 0; a < idx.size(); ++a) x(idx[a]) += alpha * (z(a) - x(idx[a]));
      for (int i = 0; i < k; ++i)
        if (passive[i] && x(i) <= 1e-15) { passive[i] = 0; x(i) = 0.0; }
    }
  }
  return x;
}

std::optional<VecX> least_distance(const MatX& G, const VecX& h) {
  const Eigen::Index n = G.cols(), m = G.rows();
  const double scale = m == 0 ? 0.0 : h.maxCoeff();
  if (!(scale > 0.0)) return VecX::Zero(n);  // x = 0 satisfies every constraint
  // Each constraint row may be scaled by a positive factor: columns of unit length keep a far,
  // irrelevant constraint (h very negative) from inflating nnls's tolerance.
  MatX E(n + 1, m);
  E.topRows(n) = G.transpose();
  E.bottomRows(1) = (h / scale).transpose();
  for (Eigen::Index i = 0; i < m; ++i)
    if (E.col(i).norm() > 0.0) E.col(i).normalize();
  VecX f = VecX::Zero(n + 1);
  f(n) = 1.0;
  const VecX r = E * nnls(E, f) - f;
  if (!(r(n) < -1e-12)) return std::nullopt;  // |r| ~ 0: no x meets the constraints
  return VecX(-r.head(n) / r(n) * scale);
}

}  // namespace btr
