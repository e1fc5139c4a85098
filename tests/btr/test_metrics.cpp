// Metrics on configurations whose answers are known in closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "btr/measures/metrics.h"
#include "containers.h"

namespace btr {
namespace {

using test::box;
using test::periodic;

constexpr double kPi = 3.14159265358979323846;

double sphere_volume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }
double cap_volume(double r, double h) { return kPi * h * h * (3.0 * r - h) / 3.0; }  // cap of height h

Grain grain(double x, double y, double z, double r) {
  Grain g;
  g.x = Vec3(x, y, z);
  g.r = r;
  return g;
}

Box box(double x0, double x1, double y0, double y1, double z0, double z1) {
  Box b;
  b.lo = Vec3(x0, y0, z0);
  b.hi = Vec3(x1, y1, z1);
  return b;
}

// ------------------------------------------------------------ single-grain volumes

TEST(GrainVolume, SymmetricCutsOfASphere) {
  const double r = 0.7;
  const Grain g = grain(0.1, -0.2, 0.3, r);
  const double V = sphere_volume(r), big = 10.0;
  // centre on a box corner / edge / face: 1/8, 1/4, 1/2 of the sphere
  EXPECT_NEAR(grain_volume_in_box(g, 3, box(0.1, big, -0.2, big, 0.3, big)), V / 8, 1e-12 * V);
  EXPECT_NEAR(grain_volume_in_box(g, 3, box(0.1, big, -0.2, big, -big, big)), V / 4, 1e-12 * V);
  EXPECT_NEAR(grain_volume_in_box(g, 3, box(0.1, big, -big, big, -big, big)), V / 2, 1e-12 * V);
  EXPECT_NEAR(grain_volume_in_box(g, 3, box(-big, big, -big, big, -big, big)), V, 1e-12 * V);
  EXPECT_EQ(grain_volume_in_box(g, 3, box(0.81, big, -big, big, -big, big)), 0.0);
}

TEST(GrainVolume, SphereCutByOneVerticalPlaneIsSphereMinusCap) {
  const double r = 1.3;
  const Grain g = grain(0, 0, 0, r);
  for (double h : {0.0, 0.2, 0.77, 1.1, 1.29}) {
    const double expected = sphere_volume(r) - cap_volume(r, r - h);  // the side x <= h
    EXPECT_NEAR(grain_volume_in_box(g, 3, box(-5, h, -5, 5, -5, 5)), expected, 1e-10 * sphere_volume(r)) << h;
    EXPECT_NEAR(grain_volume_in_box(g, 3, box(-5, 5, -h, 5, -5, 5)), expected, 1e-10 * sphere_volume(r)) << h;
  }
}

TEST(GrainVolume, EightOctantsAboutAnyPointAddUpToTheSphere) {
  const double r = 0.9;
  const Grain g = grain(0.05, 0.02, -0.03, r);
  const double big = 10.0;
  for (Vec3 p : {Vec3(0.3, -0.4, 0.1), Vec3(-0.61, 0.52, -0.2), Vec3(0.8, 0.1, 0.85)}) {
    double sum = 0.0;
    for (int i = 0; i < 8; ++i) {
      double x0 = (i & 1) ? p.x() : -big, x1 = (i & 1) ? big : p.x();
      double y0 = (i & 2) ? p.y() : -big, y1 = (i & 2) ? big : p.y();
      double z0 = (i & 4) ? p.z() : -big, z1 = (i & 4) ? big : p.z();
      double v = grain_volume_in_box(g, 3, box(x0, x1, y0, y1, z0, z1));
      EXPECT_GE(v, 0.0);
      sum += v;
    }
    EXPECT_NEAR(sum, sphere_volume(r), 1e-10 * sphere_volume(r));
  }
}

TEST(GrainVolume, SlabIsSphereMinusTwoCaps) {
  const double r = 2.0;
  const Grain g = grain(0, 0, 5.0, r);
  EXPECT_NEAR(grain_volume_in_slab(g, 3, 4.0, 6.0), sphere_volume(r) - 2 * cap_volume(r, 1.0), 1e-12);
  EXPECT_NEAR(grain_volume_in_slab(g, 3, 5.5, 100.0), cap_volume(r, 1.5), 1e-12);
  EXPECT_EQ(grain_volume_in_slab(g, 3, 7.5, 9.0), 0.0);
}

TEST(GrainVolume, DiskSegmentsAndQuadrants) {
  const double r = 0.5;
  const Grain g = grain(1.0, 0.0, 2.0, r);
  const double A = kPi * r * r;
  for (double h : {0.0, 0.1, 0.33, 0.49}) {
    const double segment = r * r * std::acos(h / r) - h * std::sqrt(r * r - h * h);  // beyond a chord at h
    EXPECT_NEAR(grain_volume_in_box(g, 2, box(1.0 + h, 9, 0, 0, -9, 9)), segment, 1e-14);
    EXPECT_NEAR(grain_volume_in_slab(g, 2, 2.0 + h, 9), segment, 1e-14);
  }
  double sum = 0.0;  // four rectangles about an off-centre point
  const double px = 1.21, pz = 1.77;
  sum += grain_volume_in_box(g, 2, box(-9, px, 0, 0, -9, pz));
  sum += grain_volume_in_box(g, 2, box(px, 9, 0, 0, -9, pz));
  sum += grain_volume_in_box(g, 2, box(-9, px, 0, 0, pz, 9));
  sum += grain_volume_in_box(g, 2, box(px, 9, 0, 0, pz, 9));
  EXPECT_NEAR(sum, A, 1e-14);
}

// ------------------------------------------------------------ lattices


// Simple cubic block: n x n columns filling the period / box, nz layers resting on the floor.
Grains simple_cubic(int n, int nz, double r, double shift) {
  Grains g;
  const double L = n * 2 * r;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        g.push_back(grain(-L / 2 + (2 * i + 1) * r + shift, -L / 2 + (2 * j + 1) * r + shift, r + 2 * k * r, r));
  return g;
}

// FCC with cubic cell a = 2 sqrt(2) r: n x n cells laterally, m cells high, lowest layer on the floor.
Grains fcc(int n, int m, double r) {
  const double a = 2 * std::sqrt(2.0) * r, L = n * a;
  const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Grains g;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& b : basis)
          g.push_back(grain(-L / 2 + (i + b[0] + 0.25) * a, -L / 2 + (j + b[1] + 0.25) * a, r + (k + b[2]) * a, r));
  return g;
}

// 2D hexagonal: rows of disks 2r apart, rows sqrt(3) r apart, odd rows shifted by r.
Grains hexagonal(int n, int rows, double r) {
  const double L = n * 2 * r;
  Grains g;
  for (int k = 0; k < rows; ++k)
    for (int i = 0; i < n; ++i)
      g.push_back(grain(-L / 2 + (2 * i + 1 + (k % 2)) * r, 0.0, r + k * std::sqrt(3.0) * r, r));
  return g;
}

TEST(BulkMeasures, SimpleCubicPeriodicBed) {
  const double r = 1e-3;
  const int n = 12, nz = 16;
  const Grains g = simple_cubic(n, nz, r, 0.0);
  const BulkMeasures m = bulk_measures(g, 3, periodic(n * 2 * r, n * 2 * r));
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_TRUE(m.slab);
  // margins of 3 diameters at the floor and below the flat top: the slab is 10 whole lattice periods
  EXPECT_NEAR(m.window.lo.z(), 6 * r, 1e-15);
  EXPECT_NEAR(m.window.hi.z(), (2 * nz - 6) * r, 1e-15);
  EXPECT_NEAR(m.packing_fraction, kPi / 6, 1e-12);
  EXPECT_DOUBLE_EQ(m.mean_coordination, 6.0);
  EXPECT_EQ(m.grains_in_window, n * n * 10);  // layers with centres 7r, 9r, ..., 25r
  ASSERT_EQ(m.coordination_histogram.size(), 7u);
  EXPECT_EQ(m.coordination_histogram[6], m.grains_in_window);
}

// Slabs one diameter thick on a simple-cubic bed: each holds one whole layer, pi/6 exactly; half-thickness slabs
// cut every sphere at its equator and read pi/6 too; a lattice whose upper half is twice as sparse (every other
// grain of each layer removed) reads pi/12 there: the profile sees a gradient the bulk mean averages away.
TEST(HeightProfile, SimpleCubicLayersAndAGradient) {
  const double r = 1e-3;
  const int n = 12, nz = 16;
  const Grains g = simple_cubic(n, nz, r, 0.0);
  const BulkMeasures bulk = bulk_measures(g, 3, periodic(n * 2 * r, n * 2 * r));
  const HeightProfile p = height_profile(g, 3, bulk, 6 * r, 2 * r);
  ASSERT_EQ(p.packing_fraction.size(), static_cast<std::size_t>(nz)) << "up to the top: window top + margin";
  for (std::size_t k = 0; k < p.packing_fraction.size(); ++k) {
    EXPECT_NEAR(p.z_mid[k], (2 * k + 1) * r, 1e-15);
    EXPECT_NEAR(p.packing_fraction[k], kPi / 6, 1e-12) << k;
  }
  const HeightProfile half = height_profile(g, 3, bulk, 6 * r, r);
  ASSERT_EQ(half.packing_fraction.size(), static_cast<std::size_t>(2 * nz));
  for (double phi : half.packing_fraction) EXPECT_NEAR(phi, kPi / 6, 1e-12);
  Grains sparse_top;
  for (std::size_t i = 0; i < g.size(); ++i)
    if (g[i].x.z() < nz * r || i % 2 == 0) sparse_top.push_back(g[i]);
  const HeightProfile grad = height_profile(sparse_top, 3, bulk, 6 * r, 2 * r);
  EXPECT_NEAR(grad.packing_fraction.front(), kPi / 6, 1e-12);
  EXPECT_NEAR(grad.packing_fraction.back(), kPi / 12, 1e-12);
  EXPECT_EQ(height_profile(g, 3, BulkMeasures{}, 6 * r, 2 * r).thickness, 0.0) << "no window, no profile";
}

TEST(BulkMeasures, SimpleCubicInABoxCutByTheWindowSides) {
  const double r = 1e-3;
  const int n = 14, nz = 14;
  // shifted laterally so that the window's side planes cut spheres: exercises the quadrature
  const Grains g = simple_cubic(n, nz, r, 0.37 * r);
  Container c;
  c.kind = ContainerKind::Box;
  c.size_x = c.size_y = n * 2 * r;
  const BulkMeasures m = bulk_measures(g, 3, c);
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_FALSE(m.slab);
  // the flat top lets the full width win; each side is 8 whole periods, the height 8 periods
  EXPECT_NEAR(m.window.hi.x() - m.window.lo.x(), (n - 6) * 2 * r, 1e-15);
  EXPECT_NEAR(m.window.hi.y() - m.window.lo.y(), (n - 6) * 2 * r, 1e-15);
  EXPECT_NEAR(m.window.hi.z() - m.window.lo.z(), (nz - 6) * 2 * r, 1e-15);
  EXPECT_NEAR(m.packing_fraction, kPi / 6, 1e-9);
  EXPECT_DOUBLE_EQ(m.mean_coordination, 6.0);
}

TEST(BulkMeasures, FaceCentredCubic) {
  const double r = 0.5e-3, a = 2 * std::sqrt(2.0) * r;
  const int n = 6, m_cells = 10;
  const Grains g = fcc(n, m_cells, r);
  const Container c = periodic(n * a, n * a);
  const double phi = kPi / (3 * std::sqrt(2.0));
  // a slab of whole cells at an arbitrary height: exactly the lattice's fraction
  double solid = 0.0;
  const double z0 = 3.3 * r;
  for (const Grain& gr : g) solid += grain_volume_in_slab(gr, 3, z0, z0 + 5 * a);
  EXPECT_NEAR(solid / (n * a * n * a * 5 * a), phi, 1e-12);
  // a box of whole cells at an arbitrary offset, cutting spheres on every side
  const Box b = box(-1.7 * a, 1.3 * a, -0.9 * a, 2.1 * a, 2.2 * a, 5.2 * a);
  EXPECT_NEAR(packing_fraction_in_box(g, 3, b), phi, 1e-9);
  // the automatic window is not a whole number of periods high: close, not exact
  const BulkMeasures m = bulk_measures(g, 3, c);
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_NEAR(m.packing_fraction, phi, 0.02);
  EXPECT_DOUBLE_EQ(m.mean_coordination, 12.0);
}

TEST(BulkMeasures, TwoDimensionalHexagonal) {
  const double r = 1e-3, row = std::sqrt(3.0) * r;
  const int n = 20, rows = 30;
  const Grains g = hexagonal(n, rows, r);
  const double phi = kPi / (2 * std::sqrt(3.0));
  // rectangle of whole periods (2r wide, two rows high) at an arbitrary offset
  EXPECT_NEAR(packing_fraction_in_box(g, 2, box(-7.3 * r, 4.7 * r, 0, 0, 5.1 * r, 5.1 * r + 8 * row)), phi, 1e-13);
  const BulkMeasures m = bulk_measures(g, 2, periodic(n * 2 * r, 0.0));
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_NEAR(m.packing_fraction, phi, 0.02);
  EXPECT_DOUBLE_EQ(m.mean_coordination, 6.0);
  // the same block on an open floor: a box window inside the block
  const BulkMeasures open = bulk_measures(g, 2, Container{});
  ASSERT_TRUE(open.valid) << open.note;
  EXPECT_FALSE(open.slab);
  EXPECT_NEAR(open.packing_fraction, phi, 0.03);
  EXPECT_DOUBLE_EQ(open.mean_coordination, 6.0);
}

TEST(BulkMeasures, ShallowBedHasNoWindow) {
  const double r = 1e-3;
  const BulkMeasures m = bulk_measures(simple_cubic(10, 5, r, 0.0), 3, periodic(20 * r, 20 * r));
  EXPECT_FALSE(m.valid);
  EXPECT_NE(m.note.find("shallow"), std::string::npos) << m.note;
}

TEST(Coordination, ContactToleranceIsRelativeToTheSmallerRadius) {
  const double r1 = 1e-3, r2 = 0.4e-3;
  for (double gap_rel : {-1e-3, 0.0, 0.5e-7, 2e-7, 1e-3}) {
    Grains g{grain(0, 0, r1, r1), grain(r1 + r2 + gap_rel * r2, 0, r1, r2)};
    std::vector<int> z = coordination_numbers(g, 3, Container{});
    const int expected = gap_rel < 1e-7 ? 1 : 0;
    EXPECT_EQ(z[0], expected) << gap_rel;
    EXPECT_EQ(z[1], expected) << gap_rel;
  }
}

TEST(Coordination, PeriodicNeighboursAcrossTheSides) {
  const double r = 1e-3;
  const int n = 5, nz = 3;
  const Grains g = simple_cubic(n, nz, r, 0.0);
  const std::vector<int> z = coordination_numbers(g, 3, periodic(n * 2 * r, n * 2 * r));
  for (std::size_t i = 0; i < g.size(); ++i) {
    const int layer = static_cast<int>(i) / (n * n);
    EXPECT_EQ(z[i], layer == 1 ? 6 : 5) << i;  // top and bottom layers miss one neighbour
  }
  // without the periodic sides, a corner grain of the middle layer has 4
  const std::vector<int> open = coordination_numbers(g, 3, Container{});
  EXPECT_EQ(open[n * n], 4);
}

// ------------------------------------------------------------ heaps

// A column of grains at (x, y) whose top grain's top is exactly at height h.
void column(Grains& g, double x, double y, double h, double r) {
  for (double z = r; z + r < h - 2 * r; z += 2 * r) g.push_back(grain(x, y, z, r));
  g.push_back(grain(x, y, h - r, r));
}

TEST(HeapMeasures, TwoDimensionalHeapWithDifferentSides) {
  const double r = 1e-3, H0 = 0.08, cap = 0.9 * H0;
  const double left = 25.0, right = 35.0;
  Grains g;
  for (int k = -120; k < 120; ++k) {
    const double x = (k + 0.5) * 2 * r + 0.01;  // the source is at x = 0.01
    const double t = std::tan((x < 0.01 ? left : right) * kPi / 180);
    const double h = std::max(2 * r, std::min(cap, H0 - t * std::abs(x - 0.01)));  // flat top and foot
    column(g, x, 0.0, h, r);
  }
  const HeapMeasures m = heap_measures(g, 2, 0.01, 0.0);
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_NEAR(m.height, cap, 1e-12);
  EXPECT_NEAR(m.angle_left_deg, left, 1e-9);
  EXPECT_NEAR(m.angle_right_deg, right, 1e-9);
  EXPECT_NEAR(m.angle_deg, 30.0, 1e-9);
  EXPECT_GT(m.profile_points, 20);
}

TEST(HeapMeasures, ConicalHeap) {
  const double r = 1e-3, H0 = 0.05, cap = 0.9 * H0, theta = 32.0;
  const double t = std::tan(theta * kPi / 180);
  Grains g;
  for (int j = -50; j <= 50; ++j)
    for (int i = -50; i <= 50; ++i) {
      const double x = i * 2 * r, y = j * 2 * r;
      column(g, x, y, std::max(2 * r, std::min(cap, H0 - t * std::hypot(x, y))), r);
    }
  const HeapMeasures m = heap_measures(g, 3, 0.0, 0.0);
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_NEAR(m.height, cap, 1e-12);
  EXPECT_NEAR(m.angle_deg, theta, 1e-9);
}

// A Hele-Shaw heap is a 2D pile between the plates: each side is fitted on its own, as in 2D.
TEST(HeapMeasures, HeleShawHeapIsFittedSideBySide) {
  const double r = 1e-3, H0 = 0.05, left = 24.0, right = 34.0;
  Grains g;
  for (int k = -100; k < 100; ++k) {
    const double x = (k + 0.5) * 2 * r, t = std::tan((x < 0 ? left : right) * kPi / 180);
    const double h = std::max(2 * r, H0 - t * std::abs(x));
    column(g, x, (k % 2 ? 0.5 : -0.5) * r, h, r);  // centres staggered across a 3 r gap
  }
  Container cell;
  cell.kind = ContainerKind::HeleShaw;
  cell.size_x = 0.4;
  cell.gap = 3 * r;
  const PackingMeasures m = measure_packing(g, 3, cell, {}, true, 0.0, 0.0);
  ASSERT_TRUE(m.heap.valid) << m.heap.note;
  EXPECT_TRUE(m.heap.by_sides);
  EXPECT_NEAR(m.heap.angle_left_deg, left, 1e-9);
  EXPECT_NEAR(m.heap.angle_right_deg, right, 1e-9);
}

TEST(HeapMeasures, FlatBedHasNoSlope) {
  Grains g;
  for (int i = -30; i < 30; ++i) column(g, i * 2e-3, 0.0, 0.02, 1e-3);
  const HeapMeasures m = heap_measures(g, 2, 0.0, 0.0);
  EXPECT_FALSE(m.valid);
}

// Stray grains that rolled far from the heap: stacks `layers` grains high, spread over distances
// [from, to] from the axis (on a line in 2D, on a ring in 3D), far apart from each other.
void strays(Grains& g, int dimension, double from, double to, int count, int layers, double r) {
  for (int k = 0; k < count; ++k) {
    const double s = from + (to - from) * k / std::max(1, count - 1), a = 2.399963 * k;  // golden-angle ring
    const double x = dimension == 3 ? s * std::cos(a) : (k % 2 ? s : -s), y = dimension == 3 ? s * std::sin(a) : 0.0;
    for (int l = 0; l < layers; ++l) g.push_back(grain(x, y, r + 2 * l * r, r));
  }
}

// The heap angle must ignore grains beyond the pile's foot. Stacks 5 grains high stand above 20 % of the
// heap height, so a fit of every profile point between 20 % and 80 % (the rule before issue 10) took them
// in and reported a much shallower flank.
TEST(HeapMeasures, ConicalHeapWithStrayGrains) {
  const double r = 1e-3, H0 = 0.05, cap = 0.9 * H0, theta = 32.0;
  const double t = std::tan(theta * kPi / 180), foot = (H0 - 2 * r) / t;
  for (int layers : {1, 5}) {
    Grains g;
    for (int j = -30; j <= 30; ++j)
      for (int i = -30; i <= 30; ++i) {
        const double x = i * 2 * r, y = j * 2 * r, s = std::hypot(x, y);
        if (s <= foot) column(g, x, y, std::max(2 * r, std::min(cap, H0 - t * s)), r);
      }
    const std::size_t heap = g.size();
    strays(g, 3, foot + 10 * r, 3 * foot, 40, layers, r);
    const HeapMeasures m = heap_measures(g, 3, 0.0, 0.0);
    ASSERT_TRUE(m.valid) << m.note;
    EXPECT_NEAR(m.height, cap, 1e-12);
    EXPECT_NEAR(m.angle_deg, theta, 1e-9) << layers << " grain(s) per stray stack";
    EXPECT_GE(m.grains_beyond_flank, static_cast<std::int64_t>(g.size() - heap)) << layers;  // strays not fitted
    EXPECT_LT(m.grains_beyond_flank, static_cast<std::int64_t>(heap)) << layers;
  }
}

TEST(HeapMeasures, TwoDimensionalHeapWithStrayGrains) {
  const double r = 1e-3, H0 = 0.06, theta = 27.0, t = std::tan(theta * kPi / 180), foot = (H0 - 2 * r) / t;
  Grains g;
  for (int k = -200; k < 200; ++k) {
    const double x = (k + 0.5) * 2 * r;
    if (std::abs(x) <= foot) column(g, x, 0.0, std::max(2 * r, H0 - t * std::abs(x)), r);
  }
  strays(g, 2, foot + 10 * r, 3 * foot, 12, 7, r);  // tops at 14 r, above 20 % of the height
  const HeapMeasures m = heap_measures(g, 2, 0.0, 0.0);
  ASSERT_TRUE(m.valid) << m.note;
  EXPECT_NEAR(m.angle_left_deg, theta, 1e-9);
  EXPECT_NEAR(m.angle_right_deg, theta, 1e-9);
  EXPECT_GE(m.grains_beyond_flank, 12 * 7);
}

// ------------------------------------------------------------ g(r), segregation, surface depth

TEST(RadialDistribution, SimpleCubicShellsCountTheirNeighbours) {
  const double r = 1e-3;
  const int n = 12, nz = 16;
  const Grains g = simple_cubic(n, nz, r, 0.0);
  const Container c = periodic(n * 2 * r, n * 2 * r);
  const BulkMeasures b = bulk_measures(g, 3, c);
  const RadialDistribution rdf = radial_distribution(g, 3, c, b);
  ASSERT_TRUE(rdf.valid);
  // n(r) = density * g * shell volume: 6 neighbours at d, 12 at sqrt(2) d, 8 at sqrt(3) d, 6 at 2 d.
  const double density = double(b.grains_in_window) / b.window_volume, d = 2 * r, bin = 0.02 * d;
  auto neighbours_near = [&](double at) {
    double n_sum = 0;
    for (std::size_t k = 0; k < rdf.g.size(); ++k) {
      const double a = k * bin, bb = (k + 1) * bin;
      if (std::abs(rdf.r_over_d[k] - at) < 0.05)
        n_sum += density * rdf.g[k] * 4.0 / 3.0 * kPi * (bb * bb * bb - a * a * a);
    }
    return n_sum;
  };
  EXPECT_NEAR(neighbours_near(1.0), 6.0, 1e-9);
  EXPECT_NEAR(neighbours_near(std::sqrt(2.0)), 12.0, 1e-9);
  EXPECT_NEAR(neighbours_near(std::sqrt(3.0)), 8.0, 1e-9);
  EXPECT_NEAR(neighbours_near(2.0), 6.0, 1e-9);
  for (std::size_t k = 0; k < rdf.g.size(); ++k) {
    if (rdf.r_over_d[k] < 0.97) {
      EXPECT_EQ(rdf.g[k], 0.0) << rdf.r_over_d[k];
    }
  }
}

TEST(Segregation, VerticalAndRadialIndicesOfKnownArrangements) {
  // large grains (species 2) in the top two of four layers at heights 0.5, 1.5, 2.5, 3.5
  Grains g;
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < 6; ++i) {
      Grain q = grain(i, 0.0, 0.5 + k, k >= 2 ? 0.5 : 0.25);
      q.species = k >= 2 ? 2 : 1;
      g.push_back(q);
    }
  SegregationIndex s = vertical_segregation(g);
  ASSERT_TRUE(s.valid) << s.basis;
  EXPECT_NEAR(s.index, 2 * (3.0 - 1.0) / (3.0 + 1.0), 1e-14);
  // one polydisperse species: the median radius splits the same grains
  for (Grain& q : g) q.species = 1;
  EXPECT_NEAR(vertical_segregation(g).index, 1.0, 1e-14);
  for (Grain& q : g) q.r = 0.5;
  EXPECT_FALSE(vertical_segregation(g).valid);
  // a drum along y: small grains on a ring of radius 1, large ones on radius 3 -> 2 (3 - 1) / 4 = 1
  Grains drum;
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * kPi * k / 12;
    Grain q = grain(5 + std::cos(a), 7.0 * k, 4 + std::sin(a), 0.1);
    Grain p = grain(5 + 3 * std::cos(a), -2.0, 4 + 3 * std::sin(a), 0.3);
    p.species = 2;
    drum.push_back(q), drum.push_back(p);
  }
  s = radial_segregation(drum, Vec3(5, 0, 4), Vec3(0, 1, 0));
  ASSERT_TRUE(s.valid) << s.basis;
  EXPECT_NEAR(s.index, 1.0, 1e-12);
  EXPECT_NEAR(s.mean_small, 1.0, 1e-12);
}

// Distances from an oblique axis (through (1, 2, 3) along (1, 1, 0)) by hand: a point on the axis, one
// moved 2 along z off it, and one moved along (1, -1, 0) by sqrt(2) off it.
TEST(AxisDistances, HandCases) {
  const Grains g = {grain(4, 5, 3, 0.1), grain(-1, 0, 5, 0.1), grain(2, 1, 3, 0.1)};
  const std::vector<double> d = axis_distances(g, Vec3(1, 2, 3), Vec3(1, 1, 0));
  ASSERT_EQ(d.size(), 3u);
  EXPECT_NEAR(d[0], 0.0, 1e-12);
  EXPECT_NEAR(d[1], 2.0, 1e-12);
  EXPECT_NEAR(d[2], std::sqrt(2.0), 1e-12);
}

TEST(SurfaceDepth, DepthBelowTheTopOfEachColumn) {
  Grains g;
  column(g, 0.0, 0.0, 0.02, 1e-3);  // 10 grains, top at 0.02
  column(g, 0.01, 0.0, 0.006, 1e-3);
  const std::vector<double> depth = surface_depth(g, 2);
  for (std::size_t i = 0; i < g.size(); ++i)
    EXPECT_NEAR(depth[i], (g[i].x.x() < 0.005 ? 0.02 : 0.006) - g[i].x.z(), 1e-15) << i;
}

// A simple cubic bed of nz layers: <h> is its top, 2 r nz, and the height packing fraction is the
// lattice's, pi/6 (2D square: pi/4), whatever the strip width; an open floor has no footprint.
TEST(BedHeightMeasures, SimpleCubicAndSquareLatticesHaveTheirPackingFraction) {
  const double r = 1e-3;
  const int n = 6, nz = 5;
  const Grains sc = simple_cubic(n, nz, r, 0.0);
  for (double width : {2 * r, 3.3 * r}) {
    const BedHeightMeasures m = bed_height_measures(sc, 3, periodic(n * 2 * r, n * 2 * r), width);
    EXPECT_NEAR(m.mean_height, 2 * r * nz, 1e-15) << width;
    EXPECT_NEAR(m.packing_fraction, kPi / 6.0, 1e-12) << width;
  }
  Grains square;
  for (int k = 0; k < nz; ++k)
    for (int i = 0; i < n; ++i) square.push_back(grain(-n * r + (2 * i + 1) * r, 0.0, r + 2 * k * r, r));
  const BedHeightMeasures m2 = bed_height_measures(square, 2, box(n * 2 * r), 2 * r);
  EXPECT_NEAR(m2.mean_height, 2 * r * nz, 1e-15);
  EXPECT_NEAR(m2.packing_fraction, kPi / 4.0, 1e-12);
  Container open;
  open.kind = ContainerKind::Open;
  EXPECT_TRUE(std::isnan(bed_height_measures(sc, 3, open, 2 * r).packing_fraction));
}

// A Hele-Shaw heap poured at a corner leans on the left end wall: one flank only, measured on its own,
// and stray grains rolled far along the floor beyond the foot do not enter the fit.
TEST(HeapMeasures, HeleShawHeapAgainstAnEndWallHasOneFlank) {
  const double r = 1e-3, H0 = 0.04, theta = 26.0, src = -0.099;
  for (bool strays : {false, true}) {
    Grains g;
    for (int k = 0; k < 100; ++k) {
      const double x = src + (k + 0.5) * 2 * r;
      const double h = std::max(2 * r, H0 - std::tan(theta * kPi / 180) * (x - src));
      if (h > 2 * r || !strays) column(g, x, (k % 2 ? 0.5 : -0.5) * r, h, r);
    }
    if (strays)  // isolated grains on the floor every 6 r up to the far end
      for (double x = src + 0.09; x < 0.099; x += 6 * r) g.push_back(grain(x, 0.0, r, r));
    Container cell;
    cell.kind = ContainerKind::HeleShaw;
    cell.size_x = 0.2;
    cell.gap = 3 * r;
    const PackingMeasures m = measure_packing(g, 3, cell, {}, true, src, 0.0);
    ASSERT_TRUE(m.heap.valid) << m.heap.note;
    EXPECT_FALSE(m.heap.left_valid);
    EXPECT_TRUE(m.heap.right_valid);
    EXPECT_NEAR(m.heap.angle_deg, theta, 1e-9) << "strays: " << strays;
    EXPECT_NE(m.heap.note.find("one flank only"), std::string::npos) << m.heap.note;
  }
}

// No flank on either side (a flat bed in a cell) stays invalid.
TEST(HeapMeasures, HeleShawFlatBedHasNoFlank) {
  const double r = 1e-3;
  Grains g;
  for (int k = 0; k < 50; ++k) column(g, -0.05 + (k + 0.5) * 2 * r, 0.0, 6 * r, r);
  Container cell;
  cell.kind = ContainerKind::HeleShaw;
  cell.size_x = 0.2;
  cell.gap = 3 * r;
  EXPECT_FALSE(measure_packing(g, 3, cell, {}, true, -0.03, 0.0).heap.valid);
}

}  // namespace
}  // namespace btr
