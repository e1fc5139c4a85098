// Pre-loaded start (coupling/dem/preload.h): overlaps from the contact law against closed forms, columns
// of spheres lowered by hand-computed amounts, the overlap check allowing the intended overlaps and
// still catching a real one, real BTR packings, and both engines starting a pre-loaded column at rest.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <filesystem>

#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/preload.h"
#include "coupling/dem/relax.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/engines.h"
#include "coupling/yade/yade_script.h"
#include "relax_fixtures.h"

namespace {

using btr::ContainerKind;

constexpr double kR = 1e-3;

double weight(double r) { return 4.0 / 3.0 * M_PI * r * r * r * 2500.0 * 9.81; }

// Y* of two grains of soft_material (E 5e7, nu 0.3): E / (2 (1 - nu^2)); a grain on a wall of the same
// material has the same Y*.
double y_star() { return 5e7 / (2.0 * (1.0 - 0.09)); }

// Hertz by hand: F = 4/3 Y* sqrt(R*) delta^(3/2).
double hertz_overlap(double force, double r_star) {
  return std::pow(3.0 * force / (4.0 * y_star() * std::sqrt(r_star)), 2.0 / 3.0);
}

btr::Scene column_scene() {
  btr::Scene s = btr_test::make_scene("columns", 3, btr_test::container(ContainerKind::Periodic, 0.012, 0.012));
  s.grains.components[0].radius.min = s.grains.components[0].radius.max = kR;
  return s;
}

// `columns` vertical columns of `height` equal touching spheres standing on the floor.
btr::Grains columns(int n_columns, int height) {
  btr::Grains g;
  for (int c = 0; c < n_columns; ++c)
    for (int k = 0; k < height; ++k) {
      btr::Grain q;
      q.r = kR;
      q.x = btr::Vec3(-0.004 + 0.004 * c, 0.001 * c, kR + 2 * kR * k);
      g.push_back(q);
    }
  // deposition order: layer by layer
  std::stable_sort(g.begin(), g.end(), [](const btr::Grain& a, const btr::Grain& b) { return a.x.z() < b.x.z(); });
  return g;
}

TEST(Preload, LawOverlapIsHertzOrHookeByHand) {
  btr::Scene s = column_scene();
  const btr::Grains g = columns(1, 2);
  const double f = 1e-3;
  EXPECT_NEAR(btr::law_overlap(g, s, 2, 1, f), hertz_overlap(f, kR / 2), 1e-12 * kR);  // R* = r/2
  EXPECT_NEAR(btr::law_overlap(g, s, 1, 0, f), hertz_overlap(f, kR), 1e-12 * kR);      // floor: R* = r
  EXPECT_NEAR(btr::law_overlap(g, s, 2, 1, 8 * f), 4 * btr::law_overlap(g, s, 2, 1, f), 1e-12 * kR);
  EXPECT_EQ(btr::law_overlap(g, s, 2, 1, 0.0), 0.0);
  s.relax.model = "hooke";
  EXPECT_NEAR(btr::law_overlap(g, s, 2, 1, 2 * f), 2 * btr::law_overlap(g, s, 2, 1, f), 1e-15);
  EXPECT_NE(btr::law_overlap(g, s, 2, 1, f), hertz_overlap(f, kR / 2));
}

// `btr relax --predict-overlap`: one grain on the floor, by hand: delta = (3 m g / (4 E* sqrt(R)))^(2/3) with
// 1/E* = (1 - nu_grain^2)/E_grain + (1 - nu_wall^2)/E_wall, the wall of the first component's material.
TEST(Preload, PredictedStaticOverlapIsHertzByHand) {
  btr::Scene s = column_scene();
  const double young = 5e7, poisson = 0.3, m = 2500.0 * 4.0 / 3.0 * M_PI * kR * kR * kR;
  ASSERT_EQ(s.grains.components[0].material.young, young);
  ASSERT_EQ(s.grains.components[0].material.poisson, poisson);
  const double e_star = 1.0 / ((1 - poisson * poisson) / young + (1 - poisson * poisson) / young);
  const double delta = std::pow(3.0 * m * 9.81 / (4.0 * e_star * std::sqrt(kR)), 2.0 / 3.0);
  const btr::StaticOverlap one = btr::predict_static_overlap(columns(1, 1), s);
  EXPECT_EQ(one.law, "hertz");
  EXPECT_EQ(one.floor_grains, 1);
  EXPECT_NEAR(one.single.mean_relative, delta / kR, 1e-12 * delta / kR);
  EXPECT_NEAR(one.single.mean_depth, delta, 1e-12 * delta);
  EXPECT_EQ(one.single.largest_relative, one.single.mean_relative);
  EXPECT_EQ(one.column.mean_relative, one.single.mean_relative);  // alone, its column is itself

  // Two columns of three: two grains on the floor share 6 weights, 3 m g each: delta grows by 3^(2/3).
  const btr::StaticOverlap cols = btr::predict_static_overlap(columns(2, 3), s);
  EXPECT_EQ(cols.floor_grains, 2);
  EXPECT_NEAR(cols.column_force, 3.0 * m * 9.81, 1e-12 * m * 9.81);
  EXPECT_NEAR(cols.column.mean_relative, std::pow(3.0, 2.0 / 3.0) * delta / kR, 1e-12 * delta / kR);
  EXPECT_NEAR(cols.single.mean_relative, delta / kR, 1e-12 * delta / kR);

  // The walls take the first component's material (materials.h, wall_component): a grain of a stiffer second
  // species meets a floor of the first's.
  btr::Scene two = s;
  btr::Component hard = two.grains.components[0];
  hard.species = 2;
  hard.material.young = 2e11;
  hard.material.poisson = 0.2;
  two.grains.components.push_back(hard);
  EXPECT_EQ(&btr::wall_material(two), &two.grains.components[0].material);
  btr::Grains g = columns(1, 1);
  g[0].species = 2;
  const double e_mixed = 1.0 / ((1 - 0.2 * 0.2) / 2e11 + (1 - poisson * poisson) / young);
  EXPECT_NEAR(btr::predict_static_overlap(g, two).single.mean_depth,
              std::pow(3.0 * m * 9.81 / (4.0 * e_mixed * std::sqrt(kR)), 2.0 / 3.0), 1e-12 * delta);

  // Explicit stiffness: F = kn delta (a wall contact takes the grain's kn).
  s.relax.model = "hooke-stiffness";
  s.grains.components[0].material.kn = 2e3;
  EXPECT_NEAR(btr::predict_static_overlap(columns(1, 1), s).single.mean_depth, m * 9.81 / 2e3, 1e-15);

  // Nothing touches the floor (a bed lifted by 10 radii): the lowest grains are taken.
  btr::Grains lifted = columns(2, 3);
  for (btr::Grain& q : lifted) q.x.z() += 10 * kR;
  s.relax.model = "hertz";
  EXPECT_EQ(btr::predict_static_overlap(lifted, s).floor_grains, 2);
}

// A column of 4 spheres: contact k (from the floor, k = 0..3) carries (4 - k) W, so grain k sits
// lower by sum_{m <= k} delta_m.
TEST(Preload, ColumnIsLoweredByTheAccumulatedOverlaps) {
  const btr::Scene s = column_scene();
  const btr::Grains g = columns(2, 4);
  const btr::Preloaded p = btr::preload_packing(g, s);
  const double W = weight(kR);
  for (std::size_t i = 0; i < g.size(); ++i) {
    const int k = static_cast<int>(i) / 2;  // layer
    double sink = hertz_overlap(4 * W, kR);
    for (int m = 1; m <= k; ++m) sink += hertz_overlap((4 - m) * W, kR / 2);
    EXPECT_NEAR(g[i].x.z() - p.grains[i].x.z(), sink, 1e-9 * sink) << "grain " << i + 1;
    EXPECT_EQ(p.grains[i].x.x(), g[i].x.x());  // never moved sideways
  }
  EXPECT_LT(p.rms_misfit, 1e-12 * kR);
  // The check allows exactly these overlaps, and the plain check sees them.
  const btr::OverlapReport plain = btr::largest_overlap(p.grains, 3, s.container);
  const btr::OverlapReport beyond = btr::largest_overlap(p.grains, 3, s.container, p.intended);
  // the largest relative overlap: the first grain-grain contact (3 W, R* = r/2), not the floor (4 W, R* = r)
  EXPECT_NEAR(plain.largest, hertz_overlap(3 * W, kR / 2) / kR, 1e-6 * plain.largest);
  EXPECT_LT(std::abs(beyond.largest), 1e-9);
}

// A real overlap on top of the intended ones is caught and the relaxation refused before any engine.
TEST(Preload, RealOverlapBeyondTheIntendedIsCaught) {
  const btr::Scene s = column_scene();
  const btr::Grains g = columns(2, 4);
  btr::Preloaded p = btr::preload_packing(g, s);
  btr::Packing pk;
  pk.grains = p.grains;
  pk.grains[5].x.z() -= 0.1 * kR;  // grain 6 pushed 0.1 r into grain 4
  pk.meta = {{"scene", btr::scene_to_json(s)}, {"dimension", 3}};
  const btr::OverlapReport rep = btr::largest_overlap(pk.grains, 3, s.container, p.intended);
  EXPECT_NEAR(rep.largest, 0.1, 1e-6);
  EXPECT_EQ(rep.id_a, 4);
  EXPECT_EQ(rep.id_b, 6);
  btr::RelaxSettings settings;
  EXPECT_THROW(btr::make_plan(pk, s, settings, "liggghts", &p.intended), btr::RelaxRefused);
  pk.grains = p.grains;
  EXPECT_NO_THROW(btr::make_plan(pk, s, settings, "liggghts", &p.intended));
}

TEST(Preload, FloatingGrainIsRefusedByName) {
  const btr::Scene s = column_scene();
  btr::Grains g = columns(1, 2);
  g[1].x.z() += 0.5 * kR;  // grain 2 floats above grain 1
  try {
    btr::preload_packing(g, s);
    FAIL() << "a floating grain was pre-loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("grain 2 "), std::string::npos) << e.what();
  }
}

// A real BTR packing (bed3d's scene, 400 grains): the loaded contacts' overlaps, measured on the
// moved grains, match the law (most within a quarter of it: a vertical move per grain is a fit,
// preload.cpp), no grain rises, and the overlap check accepts it.
TEST(Preload, RealBtrPackingMatchesTheLaw) {
  btr::Scene s = btr::load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/bed3d.toml");
  s.container.size_x = s.container.size_y = 0.01;
  const btr::Grains g = btr::run_scene(s, 3, 400, {}).grains;
  const btr::Preloaded p = btr::preload_packing(g, s);
  std::vector<double> rel;
  for (const btr::ContactForce& c : p.forces.contacts) {
    if (!(c.f.norm() > 0)) continue;
    const btr::Grain& a = p.grains[c.i - 1];
    double overlap = a.r - a.x.z();  // the floor
    if (c.j > 0) {
      const btr::Grain& b = p.grains[c.j - 1];
      overlap = a.r + b.r - (a.x - b.x - c.shift).norm();
    } else {
      ASSERT_EQ(c.j, 0);  // periodic: no side walls
    }
    rel.push_back(std::abs(overlap / btr::law_overlap(g, s, c.i, c.j, c.f.norm()) - 1));
  }
  std::sort(rel.begin(), rel.end());
  const double median = rel[rel.size() / 2], p60 = rel[rel.size() * 3 / 5];
  EXPECT_LT(median, 0.1);
  EXPECT_LT(p60, 0.25);
  for (std::size_t i = 0; i < g.size(); ++i) EXPECT_LE(p.grains[i].x.z(), g[i].x.z()) << i + 1;
  const btr::OverlapReport beyond = btr::largest_overlap(p.grains, 3, s.container, p.intended);
  EXPECT_LT(beyond.largest, 0.05) << beyond.describe();
  EXPECT_GT(btr::largest_overlap(p.grains, 3, s.container).largest, 0.1 * beyond.largest);
  std::printf("loaded contacts %zu: |overlap / law - 1| median %.3g, 60th percentile %.3g, 75th %.3g; %lld "
              "column fallbacks; largest beyond intended %s\n", rel.size(), median, p60, rel[rel.size() * 3 / 4],
              static_cast<long long>(p.column_fallbacks), beyond.describe().c_str());
}

bool have_liggghts() { return std::system("command -v liggghts >/dev/null 2>&1") == 0; }

double peak(const btr::RelaxResult& r) {
  double e = 0.0;
  for (const auto& [t, k] : r.kinetic_history) e = std::max(e, k);
  return e;
}

// The same column relaxed plainly falls into its own compression and rings; pre-loaded it starts at
// rest: its peak kinetic energy is far below the plain run's.
void column_starts_at_rest(const std::string& engine) {
  btr::Scene s = column_scene();
  s.relax.max_time = 0.03;
  btr::Packing pk;
  pk.grains = columns(3, 5);
  pk.meta = {{"scene", btr::scene_to_json(s)}, {"dimension", 3}};
  btr::RelaxSettings plain, pre;
  pre.preload = true;
  const btr::RelaxResult a = btr::relax(pk, s, engine, plain, btr_test::fresh_dir(engine + "_column_plain"));
  const btr::RelaxResult b = btr::relax(pk, s, engine, pre, btr_test::fresh_dir(engine + "_column_pre"));
  EXPECT_GT(peak(a), 0.0);
  EXPECT_LT(peak(b), 1e-3 * peak(a)) << engine << ": plain peak " << peak(a) << " J, pre-loaded " << peak(b) << " J";
}

TEST(Preload, LiggghtsColumnStartsAtRest) {
  if (!have_liggghts()) FAIL() << "scripts/setup.sh installs it: " << "liggghts not on PATH";
  column_starts_at_rest("liggghts");
}

TEST(Preload, YadeColumnStartsAtRest) {
  if (!std::filesystem::exists(std::string(btr::kYadePythonPath) + "/yade/__init__.py"))
    FAIL() << "scripts/setup.sh installs it: " << "yade Python module not installed";
  column_starts_at_rest("yade");
}

}  // namespace
