// A mesh container in both engines, for real: a small BTR fill of inputs/hopper.toml relaxed in LIGGGHTS
// (fix mesh/surface + wall/gran mesh) and in YADE (ymport.stl facets). The cone holds the grains: after
// the run every grain is still inside it (the hopper's wall, from hand geometry) and none was lost; with
// no mesh in the engine the grains on the cone's wall would slide outwards to the floor.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "coupling/engines.h"
#include "coupling/io/scene_json.h"
#include "relax_fixtures.h"

namespace {

// The hopper of inputs/hopper.stl: radius 4 + 16 z / 25 mm at height z (mm), lowest point z = 0.
double cone_radius(double z) { return 4e-3 + 16.0 / 25.0 * z; }

int facets_in(const std::string& stl) {
  std::ifstream in(stl);
  std::string word;
  int n = 0;
  while (in >> word) n += word == "facet";
  return n;
}

void relax_in(const std::string& engine) {
  if (!btr_test::have_engine(engine)) FAIL() << engine << " is not installed (scripts/setup.sh installs it)";
  btr::Scene scene = btr::load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/hopper.toml");
  scene.relax.engine = engine;
  scene.relax.max_time = 0.05;
  btr::Packing bed;
  bed.grains = btr::run_scene(scene, 3, 120, {}).grains;
  bed.meta = {{"scene", btr::scene_to_json(scene)}, {"dimension", 3}};
  const std::string dir = btr_test::fresh_dir("mesh_" + engine);
  const btr::RelaxResult res = btr::relax(bed, scene, engine, {}, dir);
  EXPECT_TRUE(res.removed.empty());
  ASSERT_EQ(res.relaxed.grains.size(), bed.grains.size());
  EXPECT_EQ(facets_in(dir + "/btr_mesh.stl"), 144);  // the mesh beside the engine's input, every facet
  const double slope = std::atan2(16.0, 25.0);
  double moved = 0.0;
  for (std::size_t i = 0; i < bed.grains.size(); ++i) {
    const btr::Grain& g = res.relaxed.grains[i];
    // Inside the cone, up to an overlap of a tenth of the radius with its wall.
    EXPECT_LE(std::hypot(g.x.x(), g.x.y()), cone_radius(g.x.z()) - 0.9 * g.r / std::cos(slope))
        << engine << ": grain " << i + 1 << " at " << g.x.transpose();
    EXPECT_GT(g.x.z(), 0.9 * g.r);
    moved = std::max(moved, (g.x - bed.grains[i].x).norm() / g.r);
  }
  std::printf("%s: %zu grains relaxed in the hopper mesh, stop %s at t = %.3g s, largest displacement %.3g r\n",
              engine.c_str(), res.relaxed.grains.size(), res.stop_reason.c_str(), res.simulated_time, moved);
  EXPECT_LT(moved, 2.0);  // a settled BTR fill stays about where it was put (measured: 0.8 r at most)
}

}  // namespace

TEST(MeshRelax, LiggghtsHoldsTheGrainsInTheHopperMesh) { relax_in("liggghts"); }
TEST(MeshRelax, YadeHoldsTheGrainsInTheHopperMesh) { relax_in("yade"); }
