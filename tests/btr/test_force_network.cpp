// The static force network (btr/measures/force_network.h): hand cases with closed-form forces, global and
// per-grain balance on real BTR packings (recomputed from the contact list alone), and broken
// packings (a floating grain, a removed support) that must be reported.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <random>

#include "btr/measures/force_network.h"
#include "btr/placement/deposition.h"
#include "containers.h"

namespace btr {
namespace {

using test::box;
using test::periodic;

Grain grain(double x, double y, double z, double r) {
  Grain g;
  g.x = Vec3(x, y, z);
  g.r = r;
  return g;
}



// Weights proportional to r^3 (one density), in newtons of order 1e-5.
std::vector<double> weights_of(const Grains& g) {
  std::vector<double> w;
  for (const Grain& q : g) w.push_back(4.0 / 3.0 * M_PI * q.r * q.r * q.r * 2500.0 * 9.81);
  return w;
}

const ContactForce& find(const ForceNetwork& net, std::int64_t i, std::int64_t j) {
  for (const ContactForce& c : net.contacts)
    if (c.i == i && c.j == j) return c;
  ADD_FAILURE() << "no contact " << i << "-" << j;
  static ContactForce none;
  return none;
}

TEST(ForceNetwork, GrainOnTheFloorCarriesItsWeight) {
  const Grains g = {grain(0, 0, 1e-3, 1e-3)};
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, 3, Container{}, w);
  ASSERT_EQ(net.contacts.size(), 1u);
  EXPECT_EQ(net.contacts[0].i, 1);
  EXPECT_EQ(net.contacts[0].j, 0);
  EXPECT_NEAR((net.contacts[0].f - Vec3(0, 0, w[0])).norm(), 0.0, 1e-15);
  EXPECT_TRUE(net.unbalanced.empty());
}

// A sphere on three touching spheres in a triangle on the floor: by symmetry each support carries
// W/(3 n_z) along its normal, n_z = sqrt(2/3); each lower sphere presses on the floor with W_low + W/3.
TEST(ForceNetwork, TetrahedronByHand) {
  const double r = 1e-3, R = 2 * r / std::sqrt(3.0), h = 2 * r * std::sqrt(2.0 / 3.0);
  Grains g;
  for (int k = 0; k < 3; ++k) g.push_back(grain(R * std::cos(2 * M_PI * k / 3), R * std::sin(2 * M_PI * k / 3), r, r));
  g.push_back(grain(0, 0, r + h, r));
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, 3, Container{}, w);
  const double lambda = w[3] / (3 * std::sqrt(2.0 / 3.0));
  for (int k = 1; k <= 3; ++k) {
    const ContactForce& c = find(net, 4, k);
    const Vec3 n = (g[3].x - g[k - 1].x).normalized();
    EXPECT_NEAR((c.f - lambda * n).norm(), 0.0, 1e-12 * w[3]) << "support " << k;
    EXPECT_NEAR(find(net, k, 0).f.z(), w[k - 1] + w[3] / 3, 1e-12 * w[3]);
  }
  EXPECT_EQ(net.contacts.size(), 9u);  // 3 on the floor, 3 side by side (no force), 3 under the top
  EXPECT_EQ(find(net, 2, 1).f.norm(), 0.0);
  EXPECT_NEAR(net.container_force.z(), net.total_weight, 1e-12 * net.total_weight);
  EXPECT_EQ(net.lifted_grains, 0);
  EXPECT_EQ(net.singular_grains, 0);
  EXPECT_TRUE(net.unbalanced.empty());
}

// 2D: a disc on two touching discs: lambda = W / (2 cos 30 deg) = W / sqrt(3).
TEST(ForceNetwork, TwoDimensionalArchByHand) {
  const double r = 1e-3;
  const Grains g = {grain(-r, 0, r, r), grain(r, 0, r, r), grain(0, 0, r + std::sqrt(3.0) * r, r)};
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, 2, Container{}, w);
  EXPECT_NEAR(find(net, 3, 1).f.norm(), w[2] / std::sqrt(3.0), 1e-12 * w[2]);
  EXPECT_NEAR(find(net, 3, 2).f.norm(), w[2] / std::sqrt(3.0), 1e-12 * w[2]);
  EXPECT_NEAR(find(net, 3, 1).f.x(), w[2] / 2 / std::sqrt(3.0), 1e-12 * w[2]);  // pushes 3 to +x
  EXPECT_NEAR(find(net, 1, 0).f.z(), w[0] + w[2] / 2, 1e-12 * w[2]);
  EXPECT_NEAR(net.container_force.z(), net.total_weight, 1e-12 * net.total_weight);
}

// 2D box: a disc leaning on the x- wall (partner -1) and on a disc one radius from the wall,
// 60 degrees below it. Wall force W / sqrt(3) (horizontal), grain force 2W / sqrt(3).
TEST(ForceNetwork, WallCarriesTheLateralPartByHand) {
  const double r = 1e-3, L = 0.02, wall = -L / 2;
  const Grains g = {grain(wall + 2 * r, 0, r, r), grain(wall + r, 0, r + std::sqrt(3.0) * r, r)};
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, 2, box(L, 0), w);
  const ContactForce& fw = find(net, 2, -1);
  EXPECT_NEAR((fw.f - Vec3(w[1] / std::sqrt(3.0), 0, 0)).norm(), 0.0, 1e-12 * w[1]);
  EXPECT_NEAR(find(net, 2, 1).f.norm(), 2 * w[1] / std::sqrt(3.0), 1e-12 * w[1]);
  EXPECT_NEAR(find(net, 1, 0).f.z(), w[0] + w[1], 1e-12 * w[1]);
  EXPECT_NEAR(net.container_force.z(), net.total_weight, 1e-12 * net.total_weight);
  EXPECT_NEAR(net.container_force.x(), w[1] / std::sqrt(3.0), 1e-12 * w[1]);
}

// Singular support set: a 3D grain touching two grains whose normals and the vertical are coplanar
// (a row): the pair carries the load exactly (rule: smallest subset); nothing is left unbalanced.
TEST(ForceNetwork, CollinearSupportsInThreeDimensionsAreCarriedByThePair) {
  const double r = 1e-3;
  const Grains g = {grain(-r, 0, r, r), grain(r, 0, r, r), grain(0, 0, r + std::sqrt(3.0) * r, r)};
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, 3, Container{}, w);
  EXPECT_TRUE(net.unbalanced.empty());
  EXPECT_NEAR(find(net, 3, 1).f.norm(), w[2] / std::sqrt(3.0), 1e-12 * w[2]);
}

TEST(ForceNetwork, FloatingGrainIsReported) {
  const Grains g = {grain(0, 0, 1e-3, 1e-3), grain(0, 0, 5e-3, 1e-3)};  // the second touches nothing
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, 3, Container{}, w);
  ASSERT_EQ(net.unbalanced.size(), 1u);
  EXPECT_EQ(net.unbalanced[0].id, 2);
  EXPECT_NEAR(net.unbalanced[0].residual.z(), -w[1], 1e-15);
  EXPECT_NEAR(net.container_force.z(), w[0], 1e-15);  // the floating weight reaches no floor
}

TEST(ForceNetwork, BadWeightsAreRefused) {
  const Grains g = {grain(0, 0, 1e-3, 1e-3)};
  EXPECT_THROW(static_forces(g, 3, Container{}, {}), ForceNetworkError);
  EXPECT_THROW(static_forces(g, 3, Container{}, {-1.0}), ForceNetworkError);
  EXPECT_THROW(static_forces(g, 4, Container{}, {1.0}), ForceNetworkError);
}

// Real BTR packings. Balance is recomputed from the contact list alone: for every grain not
// "lifted", sum of f_z on it from its supports minus sum of f_z it exerts on the grains above
// equals its weight; every force is along the centre line and compressive.
Grains btr_packing(int dim, const Container& k, int count, std::uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double rmax = 1e-3;
  Deposition dep(dim, k, rmax);
  for (int n = 0; n < count; ++n) {
    Drop d;
    d.r = rmax * (0.5 + 0.5 * u(gen));
    const double mx = k.kind == ContainerKind::Box ? d.r : 0.0;
    d.x = (u(gen) - 0.5) * (k.size_x - 2 * mx);
    d.y = dim == 3 ? (u(gen) - 0.5) * (k.size_y - 2 * mx) : 0.0;
    dep.place(d);
  }
  return dep.grains();
}

void expect_balanced(const Grains& g, int dim, const Container& k) {
  const auto w = weights_of(g);
  const ForceNetwork net = static_forces(g, dim, k, w);
  EXPECT_TRUE(net.unbalanced.empty()) << net.unbalanced.size() << " unbalanced, first " << net.unbalanced[0].id;
  std::vector<double> below(g.size(), 0.0), above(g.size(), 0.0);  // vertical forces on each grain
  Vec3 container = Vec3::Zero();
  for (const ContactForce& c : net.contacts) {
    ASSERT_LT(c.j, c.i);
    below[c.i - 1] += c.f.z();
    if (c.j > 0) {
      above[c.j - 1] -= c.f.z();
      const Vec3 d = g[c.i - 1].x - (g[c.j - 1].x + c.shift);
      EXPECT_NEAR(d.norm(), g[c.i - 1].r + g[c.j - 1].r, 1e-9 * g[c.i - 1].r) << c.i << "-" << c.j;
      EXPECT_GE(c.f.dot(d), 0.0);
      EXPECT_LE(c.f.cross(d).norm(), 1e-9 * c.f.norm() * d.norm());
    } else {
      container += c.f;
    }
  }
  std::int64_t lifted = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (above[i] - w[i] >= 0.0) {  // pushed up by the grains above more than its weight
      ++lifted;
      EXPECT_EQ(below[i], 0.0) << "grain " << i + 1;
      continue;
    }
    EXPECT_NEAR(below[i] + above[i], w[i], 1e-9 * net.total_weight) << "grain " << i + 1;
  }
  EXPECT_EQ(lifted, net.lifted_grains);
  EXPECT_NEAR(container.z(), net.total_weight + net.lifted_force, 1e-9 * net.total_weight);
  EXPECT_NEAR((container - net.container_force).norm(), 0.0, 1e-12 * net.total_weight);
  EXPECT_LT(net.lifted_force, 0.1 * net.total_weight);
}

TEST(ForceNetwork, GlobalAndGrainBalanceOnBtrPackings3DPeriodic) {
  const Container k = periodic(0.012, 0.012);
  expect_balanced(btr_packing(3, k, 400, 7), 3, k);
}

TEST(ForceNetwork, GlobalAndGrainBalanceOnBtrPackings2DBox) {
  const Container k = box(0.03, 0);
  expect_balanced(btr_packing(2, k, 300, 8), 2, k);
}

TEST(ForceNetwork, GlobalAndGrainBalanceOnBtrPackings3DBox) {
  const Container k = box(0.01, 0.01);
  expect_balanced(btr_packing(3, k, 300, 9), 3, k);
}

// Removing a grain that carries others breaks the packing: the grains that rested on it are reported.
TEST(ForceNetwork, RemovedSupportIsCaught) {
  const Container k = periodic(0.012, 0.012);
  Grains g = btr_packing(3, k, 400, 7);
  const ForceNetwork whole = static_forces(g, 3, k, weights_of(g));
  std::map<std::int64_t, int> carried;  // grain id -> number of grains resting on it with a force
  for (const ContactForce& c : whole.contacts)
    if (c.j > 0 && c.f.norm() > 0) ++carried[c.j];
  std::int64_t victim = 0;
  for (const auto& [id, n] : carried)
    if (n >= 2) victim = id;
  ASSERT_GT(victim, 0);
  g.erase(g.begin() + (victim - 1));
  const ForceNetwork broken = static_forces(g, 3, k, weights_of(g));
  EXPECT_FALSE(broken.unbalanced.empty());
  for (const UnbalancedGrain& u : broken.unbalanced) EXPECT_GE(u.id, victim);
}

}  // namespace
}  // namespace btr
