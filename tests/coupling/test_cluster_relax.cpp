// Rigid clusters in the DEM coupling: YADE relaxes them as clumps, LIGGGHTS as rigid bodies (fix rigid
// molecule), both run for real; members keep their ids, cluster numbers and relative positions; what
// cannot keep a cluster rigid is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>

#include "btr/dynamics/redeposition.h"
#include "coupling/dem/relax.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/engines.h"
#include "coupling/yade/yade_script.h"
#include "relax_fixtures.h"
#include "relaxation_checks.h"

namespace {

// A BTR deposit of random compact clusters of three grains (btr::Redeposition's first deposit) in a box.
btr::Packing cluster_packing(btr::Scene& scene, int dimension, int count,
                             btr::ContainerKind kind = btr::ContainerKind::Box) {
  scene = btr_test::make_scene("clumps" + std::to_string(dimension) + "d", dimension, btr_test::container(kind, 0.012, 0.012));
  scene.grains.count = count;
  scene.grains.components[0].material.young = 1e7;  // a longer stable step: a short test
  scene.clusters = btr::ClustersSpec{3, 10.0, 0, ""};
  btr::Redeposition redeposition(scene, 5);
  btr::Packing p;
  p.grains = redeposition.initial();
  p.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", dimension}};
  return p;
}

std::map<std::int32_t, std::vector<std::size_t>> members_of(const btr::Grains& g) {
  std::map<std::int32_t, std::vector<std::size_t>> m;
  for (std::size_t i = 0; i < g.size(); ++i)
    if (g[i].cluster != 0) m[g[i].cluster].push_back(i);
  return m;
}

}  // namespace

class ClusterRelax : public ::testing::TestWithParam<std::string> {};

TEST_P(ClusterRelax, ClustersRelaxAsRigidBodies) {
  const std::string engine = GetParam();
  if (!btr_test::have_engine(engine)) FAIL() << "scripts/setup.sh installs it: " << engine << " not installed";
  // A periodic bed too: members wrapped into the cell one by one must come together in their clump.
  for (const auto& [dimension, kind] : {std::pair{3, btr::ContainerKind::Box}, std::pair{2, btr::ContainerKind::Box},
                                        std::pair{3, btr::ContainerKind::Periodic}}) {
    const std::string name = std::to_string(dimension) + "d_" + btr::to_string(kind);
    SCOPED_TRACE(name);
    btr::Scene scene;
    const btr::Packing in = cluster_packing(scene, dimension, dimension == 3 ? 90 : 60, kind);
    const auto clusters = members_of(in.grains);
    ASSERT_GE(clusters.size(), 10u);
    const std::string dir = btr_test::fresh_dir(engine + "_clusters_" + name);
    const btr::RelaxResult r = btr::relax(in, scene, engine, {}, dir);

    EXPECT_EQ(r.stop_reason, "kinetic-energy");
    if (engine == "yade") {
      const auto status = nlohmann::json::parse(btr_test::read_text(dir + "/" + btr::yade_files::kStatus));
      EXPECT_EQ(status["clumps"], clusters.size());
    }
    const btr::Grains& out = r.relaxed.grains;
    ASSERT_EQ(out.size(), in.grains.size());
    double largest_move = 0.0, r_min = INFINITY;
    for (std::size_t i = 0; i < out.size(); ++i) {
      EXPECT_EQ(out[i].cluster, in.grains[i].cluster) << "grain " << i + 1;
      EXPECT_EQ(out[i].r, in.grains[i].r) << "grain " << i + 1;
      if (dimension == 2) {
        EXPECT_EQ(out[i].x.y(), 0.0) << "grain " << i + 1;
      }
      largest_move = std::max(largest_move, (out[i].x - in.grains[i].x).norm());
      r_min = std::min(r_min, out[i].r);
    }
    // The clumps moved (settled onto each other and the floor) ...
    EXPECT_GT(largest_move, 1e-4 * r_min);
    // ... as rigid bodies: every distance between two members of one cluster is unchanged.
    auto distance = [&](const btr::Grains& g, std::size_t a, std::size_t b) {
      btr::Vec3 d = g[a].x - g[b].x;  // nearest periodic image
      if (kind == btr::ContainerKind::Periodic) {
        d.x() -= scene.container.size_x * std::round(d.x() / scene.container.size_x);
        d.y() -= scene.container.size_y * std::round(d.y() / scene.container.size_y);
      }
      return d.norm();
    };
    double worst = 0.0;
    std::size_t straddling = 0;  // clusters with members on both sides of a periodic boundary
    for (const auto& [id, m] : clusters) {
      bool straddles = false;
      for (std::size_t a = 0; a < m.size(); ++a)
        for (std::size_t b = a + 1; b < m.size(); ++b) {
          worst = std::max(worst, std::abs(distance(out, m[a], m[b]) - distance(in.grains, m[a], m[b])));
          straddles |= (in.grains[m[a]].x - in.grains[m[b]].x).norm() > 2.0 * distance(in.grains, m[a], m[b]);
        }
      straddling += straddles;
    }
    EXPECT_LT(worst, 1e-9 * r_min);
    if (kind == btr::ContainerKind::Periodic) {
      EXPECT_GT(straddling, 0u) << "no cluster crosses the boundary: the case is not tested";
    }
    // No contact inside a clump; contacts between clumps and with the walls carry the weight.
    std::size_t between = 0;
    for (const auto& c : r.contacts) {
      if (c.j == 0) continue;
      const auto ci = out[c.i - 1].cluster, cj = out[c.j - 1].cluster;
      EXPECT_FALSE(ci != 0 && ci == cj) << "contact " << c.i << "-" << c.j << " inside cluster " << ci;
      between += ci != cj;
    }
    EXPECT_GT(between, 0u);
    EXPECT_LT(btr_test::largest_pair_overlap(out, scene.container, dimension), 0.05);
  }
}

// A cluster wider than half a periodic cell: a zig-zag chain of 7 touching grains (r = 1 mm, bonds at 120
// degrees, ends 10.4 r apart) across the corner of a 3D cell 14 r x 14 r, listed from its low end, its
// plane tilted by 15 degrees about y so that it falls and turns to lie flat on the floor; three free grains
// rest on the floor away from it. The packing wraps each member into the cell on its own: the last two
// members lie more than half a period (in x) from the first, so putting every member at the image nearest
// the first member breaks the body, and its members' distances change as it turns.
TEST_P(ClusterRelax, AClusterWiderThanHalfThePeriodicCellStaysInOnePiece) {
  const std::string engine = GetParam();
  if (!btr_test::have_engine(engine)) FAIL() << "scripts/setup.sh installs it: " << engine << " not installed";
  const double r = 1e-3, L = 14 * r, tilt = M_PI / 12, bond = 2 * r * std::cos(M_PI / 6);
  btr::Scene scene = btr_test::make_scene("wide_cluster", 3, btr_test::container(btr::ContainerKind::Periodic, L, L));
  scene.grains.components[0].material.young = 1e7;  // a longer stable step: a short test
  btr::Packing in;
  auto wrap = [&](double v) { return v - L * std::floor(v / L + 0.5); };
  for (int k = 0; k < 7; ++k) {
    const double along = (k - 3) * bond;  // the middle member at the corner
    btr::Grain g{btr::Vec3(wrap(0.5 * L + along * std::cos(tilt)), wrap(0.5 * L + (k % 2 - 0.5) * r),
                           1.05 * r + (along + 3 * bond) * std::sin(tilt)),
                 r, 1};
    g.cluster = 1;
    in.grains.push_back(g);
  }
  for (int k = 0; k < 3; ++k) {
    const double rk = (0.9 + 0.1 * k) * r;
    in.grains.push_back(btr::Grain{btr::Vec3((k - 1) * 4 * r, 0, rk), rk, 1});
  }
  in.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", 3}};
  ASSERT_GT(6 * bond * std::cos(tilt), 0.5 * L);  // the ends' x distance: wider than half the cell
  ASSERT_GT(std::abs(in.grains[1].x.y() - in.grains[0].x.y()), 0.5 * L);  // wrapped apart in y too

  const std::string dir = btr_test::fresh_dir(engine + "_wide_cluster");
  const btr::RelaxResult result = btr::relax(in, scene, engine, {}, dir);
  EXPECT_EQ(result.stop_reason, "kinetic-energy");
  const btr::Grains& out = result.relaxed.grains;
  ASSERT_EQ(out.size(), in.grains.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].cluster, in.grains[i].cluster) << "grain " << i + 1;
    EXPECT_LE(std::max(std::abs(out[i].x.x()), std::abs(out[i].x.y())), 0.5 * L) << "grain " << i + 1 << " outside";
  }
  // Every distance between two members, the members unwrapped along the chain (consecutive members touch,
  // their nearest images are their own; the chain's ends are not, and their minimum-image distance changes
  // as the chain turns).
  auto unwrapped = [&](const btr::Grains& g) {
    std::vector<btr::Vec3> u{g[0].x};
    for (std::size_t k = 1; k < 7; ++k) {
      btr::Vec3 d = g[k].x - g[k - 1].x;
      d.x() -= L * std::round(d.x() / L);
      d.y() -= L * std::round(d.y() / L);
      u.push_back(u.back() + d);
    }
    return u;
  };
  const std::vector<btr::Vec3> before = unwrapped(in.grains), after = unwrapped(out);
  double worst = 0.0;
  for (std::size_t a = 0; a < 7; ++a)
    for (std::size_t b = a + 1; b < 7; ++b)
      worst = std::max(worst, std::abs((after[a] - after[b]).norm() - (before[a] - before[b]).norm()));
  EXPECT_LT(worst, 1e-9 * 0.9 * r);
  // The chain turned (its high end fell by more than 2 r) and lies flat on the floor in one piece.
  EXPECT_GT(in.grains[6].x.z() - out[6].x.z(), 2 * r);
  for (std::size_t k = 0; k < 7; ++k) EXPECT_NEAR(out[k].x.z(), r, 0.01 * r) << "member " << k + 1;
  for (const auto& c : result.contacts)
    EXPECT_FALSE(c.j != 0 && c.i <= 7 && c.j <= 7) << "contact " << c.i << "-" << c.j << " inside the cluster";
  if (engine == "yade") {
    const auto status = nlohmann::json::parse(btr_test::read_text(dir + "/" + btr::yade_files::kStatus));
    EXPECT_EQ(status["clumps"], 1);
  }
}

INSTANTIATE_TEST_SUITE_P(Engines, ClusterRelax, ::testing::Values("liggghts", "yade"));

TEST(ClusterRelax, WhatCannotKeepAClusterRigidIsRefused) {
  btr::Scene scene;
  const btr::Packing in = cluster_packing(scene, 3, 30);
  const std::string dir = btr_test::fresh_dir("clumps_refused");
  auto refusal = [&](const btr::Scene& s, const std::string& engine, const btr::RelaxSettings& settings) {
    try {
      btr::export_inputs(in, s, engine, settings, dir);
    } catch (const btr::RelaxRefused& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  btr::Scene unbalanced = scene;
  unbalanced.relax.stop_rule = "unbalanced-force";
  EXPECT_NE(refusal(unbalanced, "liggghts", {}).find("unbalanced force"), std::string::npos);
  EXPECT_EQ(refusal(unbalanced, "yade", {}), "(accepted)");  // YADE's is per clump
  btr::RelaxSettings preload;
  preload.preload = true;
  EXPECT_NE(refusal(scene, "yade", preload).find("pre-loaded start"), std::string::npos);
  btr::Scene open = scene;
  open.container = btr_test::container(btr::ContainerKind::Open);
  EXPECT_NE(refusal(open, "yade", {}).find("open floor"), std::string::npos);
  EXPECT_EQ(refusal(scene, "yade", {}), "(accepted)");
  EXPECT_EQ(refusal(scene, "liggghts", {}), "(accepted)");
}
