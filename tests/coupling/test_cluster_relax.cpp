// Rigid clusters in the DEM coupling: YADE relaxes them as clumps, LIGGGHTS as rigid bodies (fix rigid
// molecule), both run for real; members keep their ids, cluster numbers and relative positions; what
// cannot keep a cluster rigid is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>

#include "btr/redeposition.h"
#include "coupling/relax.h"
#include "coupling/relax_plan.h"
#include "coupling/yade_script.h"
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
  if (!btr_test::have_engine(engine)) GTEST_SKIP() << engine << " not installed";
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
