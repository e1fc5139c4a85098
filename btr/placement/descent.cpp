#include "btr/placement/descent.h"

#include <Eigen/Dense>
#include <stdexcept>

namespace btr {
namespace {

constexpr double kForceEps = 1e-12;
constexpr double kFeasibleEps = 1e-12;

// The dot products the subsets share, computed once per descent (the same products, so the same bits).
// Only the first count rows are set (and read).
struct Products {
  double gram[kMaxContacts][kMaxContacts];
  double rhs[kMaxContacts];  // -n_i . g
  Products(const Vec3* n, std::size_t count) {
    const Vec3 g(0.0, 0.0, -1.0);
    for (std::size_t i = 0; i < count; ++i) {
      rhs[i] = -n[i].dot(g);
      for (std::size_t j = 0; j <= i; ++j) gram[i][j] = gram[j][i] = n[i].dot(n[j]);
    }
  }
};

// Tries one active subset: d = g + sum lambda_i n_i with n_i . d = 0 on the subset. Writes `out`, which
// holds a fresh Descent, only when the subset is the answer. Inlined into each of descend's loops: a call
// per subset (about four a descent) cost about a quarter of the descent's instructions in a bed. No result
// changes: the same operations in the same order.
[[gnu::always_inline]] inline bool try_subset(const Vec3* n, const Products& p, std::size_t count, unsigned mask,
                                              Descent& out) {
  const Vec3 g(0.0, 0.0, -1.0);
  int idx[3];
  int k = 0;
  for (unsigned m = mask; m != 0; m &= m - 1) idx[k++] = __builtin_ctz(m);  // the set bits, lowest first
  Vec3 d = g;
  double lambda[3] = {0, 0, 0};
  if (k == 1) {  // the usual case, without the matrices (the same operations as below)
    const double l = p.rhs[idx[0]] / p.gram[idx[0]][idx[0]];
    if (l < -kForceEps) return false;
    lambda[0] = l;
    d += l * n[idx[0]];
  } else if (k > 1) {
    Eigen::Matrix3d gram = Eigen::Matrix3d::Identity();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int a = 0; a < k; ++a) {
      for (int b = 0; b < k; ++b) gram(a, b) = p.gram[idx[a]][idx[b]];
      rhs(a) = p.rhs[idx[a]];
    }
    // Reject dependent normals (supports on one line, a repeated contact): another subset covers them.
    Eigen::Vector3d l = Eigen::Vector3d::Zero();
    if (k == 2) {
      const Eigen::Matrix2d sub = gram.topLeftCorner<2, 2>();
      if (sub.determinant() < 1e-10) return false;
      l.head<2>() = sub.inverse() * rhs.head<2>();
    } else {
      if (gram.determinant() < 1e-10) return false;
      l = gram.inverse() * rhs;
    }
    for (int a = 0; a < k; ++a) {
      if (l(a) < -kForceEps) return false;
      lambda[a] = l(a);
      d += l(a) * n[idx[a]];
    }
  }
  for (std::size_t i = 0; i < count; ++i)
    if (!(mask & (1u << i)) && n[i].dot(d) < -kFeasibleEps) return false;
  out.direction = d.norm() < 1e-12 ? Vec3::Zero() : d;
  for (int a = 0; a < k; ++a) out.loaded[idx[a]] = lambda[a] > kForceEps;
  return true;
}

}  // namespace

Descent descend(const Vec3* normals, std::size_t count) {
  if (count > static_cast<std::size_t>(kMaxContacts)) throw std::length_error("descend: more than kMaxContacts contacts");
  // Subsets in order of size, then of index (as bit masks: the largest index first, then the next), so
  // the first feasible one is the answer and degenerate cases (several subsets giving the same
  // direction) are deterministic.
  const int n = static_cast<int>(count);
  const Products p(normals, count);
  // Every path returns `out` itself, so it is built in the caller's Descent (no copy).
  Descent out;
  auto search = [&] {  // stops at the first feasible subset
    if (try_subset(normals, p, count, 0u, out)) return;
    for (int a = 0; a < n; ++a)
      if (try_subset(normals, p, count, 1u << a, out)) return;
    for (int b = 1; b < n; ++b)
      for (int a = 0; a < b; ++a)
        if (try_subset(normals, p, count, (1u << a) | (1u << b), out)) return;
    for (int c = 2; c < n; ++c)
      for (int b = 1; b < c; ++b)
        for (int a = 0; a < b; ++a)
          if (try_subset(normals, p, count, (1u << a) | (1u << b) | (1u << c), out)) return;
  };
  // Unsolved only through round-off with more than three nearly dependent contacts: carried (`out` is
  // then still fresh, as try_subset writes it only for its answer).
  search();
  return out;
}

}  // namespace btr
