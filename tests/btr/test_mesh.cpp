// Mesh containers: grains against triangles in hand geometry (fall onto a face, an edge, a vertex;
// roll off an edge; slide into a groove and a corner), refusals of open meshes, the STL reader's errors,
// and the self-check on filled meshes.
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include "btr/placement/deposition.h"
#include "btr/placement/drops.h"
#include "btr/placement/mesh_index.h"
#include "btr/placement/mesh_line_reach.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/mesh_file.h"
#include "btr/scene/scene_toml.h"
#include "btr/verify/check.h"

namespace fs = std::filesystem;
using namespace btr;

namespace {

// A mesh container from triangles given in a frame of the test's own; `shift` is what the container
// adds to them (its box centred on the z axis, its lowest point at z = 0), as the STL reader does.
struct HandMesh {
  Container container;
  Vec3 shift;
};

HandMesh hand_mesh(const std::vector<Vec3>& v, const std::vector<std::array<int, 3>>& t) {
  auto m = std::make_shared<TriangleMesh>();
  m->file = "hand.stl";
  Vec3 lo = v[0], hi = v[0];
  for (const Vec3& p : v) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  m->shift = Vec3(-0.5 * (lo.x() + hi.x()), -0.5 * (lo.y() + hi.y()), -lo.z());
  for (const Vec3& p : v) m->vertices.push_back(p + m->shift);
  m->triangles = t;
  m->lo = lo + m->shift, m->hi = hi + m->shift;
  HandMesh h;
  h.container.kind = ContainerKind::Mesh;
  h.container.size_x = hi.x() - lo.x(), h.container.size_y = hi.y() - lo.y();
  h.container.mesh = m;
  h.shift = m->shift;
  return h;
}

// Two triangles of the quadrilateral a b c d.
void quad(std::vector<std::array<int, 3>>& t, int a, int b, int c, int d) {
  t.push_back({a, b, c});
  t.push_back({a, c, d});
}

Drop drop_at(const Vec3& p, double r) {
  Drop d;
  d.x = p.x(), d.y = p.y(), d.r = r;
  return d;
}

constexpr double kTol = 1e-9;

// A flat floor z = 0 over [-10, 10]^2 (lowest at 0 already, centred).
HandMesh floor_mesh() {
  std::vector<Vec3> v = {{-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}};
  std::vector<std::array<int, 3>> t;
  quad(t, 0, 1, 2, 3);
  return hand_mesh(v, t);
}

}  // namespace

// The rounding of the file's coordinates: half an ulp of a float32 is at most 2^-24 of the number, so the bound
// is 2^-24 times the largest file coordinate (12.5 here), scaled; the shift the placement adds is not rounded.
TEST(MeshIndex, VertexRoundoffIsHalfAFloatUlpOfTheLargestFileCoordinateScaled) {
  TriangleMesh m;
  m.scale = 1e-3;
  m.shift = Vec3(0.5, -0.25, 2.0);
  for (const Vec3& p : {Vec3(1.0, 2.0, 0.0), Vec3(-12.5, 3.0, 0.0), Vec3(4.0, 4.0, 7.0)}) m.vertices.push_back(m.scale * p + m.shift);
  m.triangles = {{0, 1, 2}};
  m.lo = m.vertices[0].cwiseMin(m.vertices[1]).cwiseMin(m.vertices[2]);
  m.hi = m.vertices[0].cwiseMax(m.vertices[1]).cwiseMax(m.vertices[2]);
  const MeshIndex idx(m, 1e-3);
  EXPECT_NEAR(idx.vertex_roundoff(), std::ldexp(12.5e-3, -24), 1e-12 * std::ldexp(12.5e-3, -24));
}

TEST(MeshIndex, ClosestPointOfFaceEdgeAndVertex) {
  std::vector<Vec3> v = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};
  TriangleMesh m;
  m.vertices = v;
  m.triangles = {{0, 1, 2}};
  m.lo = Vec3(0, 0, 0), m.hi = Vec3(4, 4, 0);
  const MeshIndex idx(m, 1.0);
  EXPECT_LT((idx.closest(0, Vec3(1, 1, 3)) - Vec3(1, 1, 0)).norm(), 1e-15);   // face
  EXPECT_LT((idx.closest(0, Vec3(2, -3, 1)) - Vec3(2, 0, 0)).norm(), 1e-15);  // edge a-b
  EXPECT_LT((idx.closest(0, Vec3(3, 3, 0)) - Vec3(2, 2, 0)).norm(), 1e-15);   // hypotenuse
  EXPECT_LT((idx.closest(0, Vec3(-1, -2, 5)) - Vec3(0, 0, 0)).norm(), 1e-15); // vertex a
  EXPECT_NEAR(idx.distance(0, Vec3(6, -1, 2)), std::sqrt(4.0 + 1.0 + 4.0), 1e-14);
}

TEST(MeshIndex, FallContactOnFaceEdgeAndVertex) {
  // A triangle tilted about the x axis: z = y tan(a) over x in [0, 4], y in [0, 4] (right angle at 0).
  const double a = 0.3, r = 1.0;
  std::vector<Vec3> v = {{0, 0, 0}, {4, 0, 0}, {0, 4, 4 * std::tan(a)}};
  TriangleMesh m;
  m.vertices = v;
  m.triangles = {{0, 1, 2}};
  m.lo = Vec3(0, 0, 0), m.hi = Vec3(4, 4, 4 * std::tan(a));
  const MeshIndex idx(m, 1.0);
  // Face: the centre rests on the plane offset by r, z = y tan(a) + r / cos(a) (where its foot is inside).
  EXPECT_NEAR(idx.fall_contact(0, Vec3(1, 1.5, 50), r), 1.5 * std::tan(a) + r / std::cos(a), kTol);
  // Edge a-b (y = 0, z = 0), met from the side y < 0: distance sqrt(y^2 + z^2) = r.
  EXPECT_NEAR(idx.fall_contact(0, Vec3(2, -0.6, 50), r), std::sqrt(1.0 - 0.36), kTol);
  // Vertex b = (4, 0, 0), met from outside both its edges: |x - b| = r.
  EXPECT_NEAR(idx.fall_contact(0, Vec3(4.3, -0.4, 50), r), std::sqrt(1.0 - 0.09 - 0.16), kTol);
  // Beside it: no contact.
  EXPECT_TRUE(std::isnan(idx.fall_contact(0, Vec3(6, 2, 50), r)));
  // Below it, moving away: no contact.
  EXPECT_TRUE(std::isnan(idx.fall_contact(0, Vec3(1, 1, -5), r)));
}

TEST(MeshLineReach, HeightsWithinADistanceOfFaceEdgeVertexAndTheirUnion) {
  // The triangle (0,0,0), (4,0,0), (0,4,0), d = 1, lines from height 10 (offsets from there).
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0), n(0, 0, 1);
  auto at = [&](double x, double y) { return line_within(a, b, c, n, Vec3(x, y, 10.0), 1.0); };
  HeightInterval s = at(1, 1);  // over the face: the slab |z| <= 1
  EXPECT_NEAR(s.lo, -11.0, 1e-12);
  EXPECT_NEAR(s.hi, -9.0, 1e-12);
  s = at(2, -0.6);  // beside the edge a-b: 0.36 + z^2 <= 1
  EXPECT_NEAR(s.lo, -10.8, 1e-12);
  EXPECT_NEAR(s.hi, -9.2, 1e-12);
  s = at(4.3, -0.4);  // beyond the vertex b: 0.09 + 0.16 + z^2 <= 1
  EXPECT_NEAR(s.hi, -10.0 + std::sqrt(0.75), 1e-12);
  EXPECT_NEAR(s.lo, -10.0 - std::sqrt(0.75), 1e-12);
  EXPECT_TRUE(at(6, 2).empty());
  // A vertical triangle in the plane x = 0, the line at x = 0.6 over y = 1: from the cylinder about the
  // edge z = 0 (0.36 + z^2 <= 1) up through the slab to the cylinder about y + z = 4 (0.36 + (z - 3)^2 / 2 <= 1).
  const HeightInterval v = line_within(Vec3(0, 0, 0), Vec3(0, 4, 0), Vec3(0, 0, 4), Vec3(1, 0, 0), Vec3(0.6, 1, 0), 1.0);
  EXPECT_NEAR(v.lo, -0.8, 1e-12);
  EXPECT_NEAR(v.hi, 3.0 + std::sqrt(1.28), 1e-12);
}

TEST(MeshIndex, FallContactBesideAVerticalTriangle) {
  // The triangle (0,0,0), (0,4,0), (0,0,4) in the plane x = 0; a grain of radius 1 falling from z = 50.
  const double r = 1.0;
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {0, 4, 0}, {0, 0, 4}};
  m.triangles = {{0, 1, 2}};
  m.lo = Vec3(0, 0, 0), m.hi = Vec3(0, 4, 4);
  const MeshIndex idx(m, 1.0);
  // Farther than r from the plane on either side: never within r of the triangle.
  EXPECT_TRUE(std::isnan(idx.fall_contact(0, Vec3(1.5, 1, 50), r)));
  EXPECT_TRUE(std::isnan(idx.fall_contact(0, Vec3(-1.2, 1, 50), r)));
  // At x = 0.6 over y = 1 the line enters the cylinder about the edge y + z = 4 first:
  // 0.6^2 + (1 + z - 4)^2 / 2 = 1.
  EXPECT_NEAR(idx.fall_contact(0, Vec3(0.6, 1, 50), r), 3.0 + std::sqrt(1.28), kTol);
  EXPECT_NEAR(idx.fall_contact(0, Vec3(-0.6, 1, 50), r), 3.0 + std::sqrt(1.28), kTol);
}

TEST(MeshIndex, FootprintOfAnOpenCupByItsCrossingsAndItsRim) {
  // A cup: the floor [-5, 5]^2 at z = 0 and four walls up to z = 5, open at the top (the walls' top edges
  // are edges of one triangle only: the rim).
  std::vector<Vec3> v = {{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}, {-5, -5, 5}, {5, -5, 5}, {5, 5, 5}, {-5, 5, 5}};
  TriangleMesh m;
  m.vertices = v;
  quad(m.triangles, 0, 1, 2, 3);
  for (int k = 0; k < 4; ++k) quad(m.triangles, k, (k + 1) % 4, 4 + (k + 1) % 4, 4 + k);
  m.lo = Vec3(-5, -5, 0), m.hi = Vec3(5, 5, 5);
  m.file = "cup.stl";
  const MeshIndex idx(m, 0.5);  // columns much narrower than a rim edge
  EXPECT_TRUE(idx.in_footprint(0.0, 0.0, 1.0));
  EXPECT_TRUE(idx.in_footprint(4.5, 0.3, 0.4));   // 0.5 from the rim x = 5
  EXPECT_FALSE(idx.in_footprint(4.5, 0.3, 0.6));  // within r of it
  EXPECT_FALSE(idx.in_footprint(-4.2, 4.3, 0.8)); // within r of the rim y = 5 only
  EXPECT_FALSE(idx.in_footprint(6.0, 0.0, 0.1));  // outside: the line misses the cup
  EXPECT_NE(idx.footprint_misfit(4.5, 0.3, 0.6).find("from (5, -5, 5) to (5, 5, 5)"), std::string::npos)
      << idx.footprint_misfit(4.5, 0.3, 0.6);
  // The reason is given exactly where the test fails, on a grid over and around the cup.
  for (double x = -6.05; x < 6.1; x += 0.37)
    for (double y = -6.05; y < 6.1; y += 0.41)
      EXPECT_EQ(idx.in_footprint(x, y, 0.7), idx.footprint_misfit(x, y, 0.7).empty()) << x << " " << y;
}

TEST(MeshPlacement, FallsOntoAFlatFaceAndRests) {
  const HandMesh h = floor_mesh();
  Deposition dep(3, h.container, 1.0);
  const Grain& g = dep.place(drop_at(Vec3(0.3, -0.2, 0), 1.0));
  EXPECT_NEAR(g.x.x(), 0.3, kTol);
  EXPECT_NEAR(g.x.y(), -0.2, kTol);
  EXPECT_NEAR(g.x.z(), 1.0, kTol);
  // A second grain dropped half a diameter beside it rolls down its meridian to the floor: it rests at
  // distance 2 r from the first, on the floor, in the vertical plane of the drop.
  const Grain g2 = dep.place(drop_at(Vec3(1.3, -0.2, 0), 1.0));
  EXPECT_NEAR(g2.x.x(), 2.3, 1e-7);
  EXPECT_NEAR(g2.x.y(), -0.2, 1e-7);
  EXPECT_NEAR(g2.x.z(), 1.0, 1e-9);
}

// A horizontal V groove along y: faces z = |x| tan(a) for |x| <= L, |y| <= L.
HandMesh groove(double a, double L) {
  const double zt = L * std::tan(a);
  std::vector<Vec3> v = {{-L, -L, zt}, {0, -L, 0}, {0, L, 0}, {-L, L, zt}, {L, -L, zt}, {L, L, zt}};
  std::vector<std::array<int, 3>> t;
  quad(t, 0, 1, 2, 3);
  quad(t, 1, 4, 5, 2);
  return hand_mesh(v, t);
}

TEST(MeshPlacement, SlidesDownAFaceIntoAGroove) {
  const double a = 0.4, L = 10, r = 1.0;
  const HandMesh h = groove(a, L);
  Deposition dep(3, h.container, r);
  const Vec3 at = Vec3(-3.0, 0.7, 0) + h.shift;
  const Grain& g = dep.place(drop_at(at, r));
  // Touching both faces: on the groove's line of symmetry, r / cos(a) above its bottom; no motion along y.
  const Vec3 expect = Vec3(0.0, 0.7, r / std::cos(a)) + h.shift;
  EXPECT_LT((g.x - expect).norm(), 1e-8) << g.x.transpose() << " vs " << expect.transpose();
}

// The groove with one corner of the left face's panel raised or lowered by 1e-6 (its two triangles coplanar only
// to the rounding of float32 coordinates, as a flat CAD panel read from STL): a grain sliding down that face
// crosses the panel's diagonal, goes on onto the other triangle (at most 4 ulps of a float32 coordinate off
// its plane, kept to that plane) and comes to rest in the groove as on the flat face, touching nothing.
TEST(MeshPlacement, SlidesOverThePanelDiagonalThatIsFlatOnlyToRoundOff) {
  const double a = 0.4, L = 10, r = 1.0;
  for (const double lift : {1e-6, -1e-6}) {
    const double zt = L * std::tan(a);
    std::vector<Vec3> v = {{-L, -L, zt}, {0, -L, 0}, {0, L, 0}, {-L, L, zt + lift}, {L, -L, zt}, {L, L, zt}};
    std::vector<std::array<int, 3>> t;
    quad(t, 0, 1, 2, 3);  // the diagonal from (-L, -L) to (0, L): a drop at x = -6, y = 0.7 starts beyond it
    quad(t, 1, 4, 5, 2);
    const HandMesh h = hand_mesh(v, t);
    Deposition dep(3, h.container, r);
    const Grain& g = dep.place(drop_at(Vec3(-6.0, 0.7, 0) + h.shift, r));
    const Vec3 expect = Vec3(0.0, 0.7, r / std::cos(a)) + h.shift;
    EXPECT_LT((g.x - expect).norm(), 1e-5) << "lift " << lift << ": " << g.x.transpose() << " vs " << expect.transpose();
    const CheckReport rep = check_packing(dep.grains(), 3, h.container);
    EXPECT_TRUE(rep.ok()) << "lift " << lift << ": " << rep.overlaps << " overlaps, " << rep.unsupported
                          << " unsupported, " << rep.outside << " outside";
  }
}

TEST(MeshPlacement, SlidesOntoAGrainRollsOffItsTopAndRestsBesideItInTheGroove) {
  // The groove above; a first grain rests in it. A second, dropped upslope in the same plane y = 0.7,
  // slides straight down the face onto it (an exact slide), is then at the top of the circle where its
  // contact sphere meets the face's offset plane, rolls off sideways along that circle (an exact arc on a
  // grain and a face) and down the groove, and rests touching both faces and the first grain.
  const double a = 0.4, L = 10, r = 1.0;
  const HandMesh h = groove(a, L);
  Deposition dep(3, h.container, r);
  const Grain g1 = dep.place(drop_at(Vec3(-3.0, 0.7, 0) + h.shift, r));
  const Grain g2 = dep.place(drop_at(Vec3(-6.0, 0.7, 0) + h.shift, r));
  EXPECT_NEAR((g2.x - g1.x).norm(), 2.0 * r, 1e-9);
  const double bottom = r / std::cos(a);
  EXPECT_NEAR(g2.x.x(), h.shift.x(), 1e-8);
  EXPECT_NEAR(g2.x.z(), bottom + h.shift.z(), 1e-8);
  EXPECT_NEAR(std::abs(g2.x.y() - g1.x.y()), 2.0 * r, 1e-8);
  const CheckReport report = check_packing(dep.grains(), 3, h.container);
  EXPECT_TRUE(report.ok()) << report.overlaps << " overlaps, " << report.unsupported << " unsupported";
}

TEST(MeshPlacement, FallsOntoAnEdgeRollsOffItAndFallsToTheFloor) {
  // A block of height H over x <= 0 beside a floor over x >= 0: top face, vertical side at x = 0, floor.
  const double H = 2.0, L = 10, r = 1.0;
  std::vector<Vec3> v = {{-L, -L, H}, {0, -L, H}, {0, L, H}, {-L, L, H},   // top 0-3
                         {0, -L, 0}, {L, -L, 0}, {L, L, 0}, {0, L, 0}};    // floor 4-7
  std::vector<std::array<int, 3>> t;
  quad(t, 0, 1, 2, 3);
  quad(t, 1, 4, 7, 2);  // the side x = 0
  quad(t, 4, 5, 6, 7);
  const HandMesh h = hand_mesh(v, t);
  const MeshIndex idx(*h.container.mesh, 2.0);
  // Dropped half a radius beyond the edge: it first touches the edge (the cylinder of radius r about it).
  const Vec3 drop = Vec3(0.5, 0.3, 0) + h.shift;
  double first = -1e300;
  for (int k = 0; k < idx.size(); ++k) {
    const double z = idx.fall_contact(k, Vec3(drop.x(), drop.y(), 50), r);
    if (!std::isnan(z)) first = std::max(first, z);
  }
  EXPECT_NEAR(first, H + std::sqrt(1.0 - 0.25), kTol);
  // It rolls off the edge about it, leaves it level with the edge at x = r, and falls along the side.
  Deposition dep(3, h.container, r);
  const Grain& g = dep.place(drop_at(drop, r));
  const Vec3 expect = Vec3(r, 0.3, r) + h.shift;
  EXPECT_LT((g.x - expect).norm(), 1e-7) << g.x.transpose() << " vs " << expect.transpose();
}

TEST(MeshPlacement, AGrainGrazedRollingOffAnEdgeIsMetBetweenTwoSteps) {
  // The block and edge above. A grain o of radius 3 rests on the floor at (3.2, y_o) beside the block, its
  // contact sphere (radius 4) reaching over the edge. The dropped grain rolls off the edge on the circle
  // P(a) = (sin a, 0.3, H + cos a), a from 30 to 90 degrees, in steps of r/10 (samples 5.7 degrees apart),
  // and comes nearest o at a* = atan2(3.2, 1) = 72.6 degrees, between the samples at 70.0 and 75.7, where its
  // distance from o in the x-z plane is rho = |(3.2, 1)| - 1. o is set across (y) so that the path enters
  // its sphere there by `depth` and both samples are 9e-4 clear. Met, o pushes the grain along the edge
  // (-y) until a*, where o's constraint stops holding it (the distance grows past a*): the grain leaves o at
  // y = y_o - sqrt(16 - rho^2) and falls to the floor beside the side there. Passed through, it would keep
  // y = 0.3.
  const double H = 2.0, L = 10, r = 1.0, ro = 3.0, xo = 3.2;
  std::vector<Vec3> v = {{-L, -L, H}, {0, -L, H}, {0, L, H}, {-L, L, H}, {0, -L, 0}, {L, -L, 0}, {L, L, 0}, {0, L, 0}};
  std::vector<std::array<int, 3>> t;
  quad(t, 0, 1, 2, 3);
  quad(t, 1, 4, 7, 2);
  quad(t, 4, 5, 6, 7);
  const HandMesh h = hand_mesh(v, t);
  const double rho = std::hypot(xo, ro - H) - r;
  for (const double depth : {1e-5, -1e-5}) {  // entered by 1e-5, or passed 1e-5 clear
    const double yo = 0.3 + std::sqrt((r + ro - depth) * (r + ro - depth) - rho * rho);
    Deposition dep(3, h.container, ro);
    const Grain o = dep.place(drop_at(Vec3(xo, yo, 0) + h.shift, ro));
    ASSERT_LT((o.x - (Vec3(xo, yo, ro) + h.shift)).norm(), 1e-12);
    const Grain g = dep.place(drop_at(Vec3(0.5, 0.3, 0) + h.shift, r));
    const double y = depth > 0.0 ? yo - std::sqrt((r + ro) * (r + ro) - rho * rho) : 0.3;
    const Vec3 expect = Vec3(r, y, r) + h.shift;
    EXPECT_LT((g.x - expect).norm(), 1e-9) << "depth " << depth << ": " << (g.x - h.shift).transpose();
    const CheckReport rep = check_packing(dep.grains(), 3, h.container);
    EXPECT_TRUE(rep.ok()) << rep.overlaps << " " << rep.unsupported << " " << rep.outside;
  }
}

TEST(MeshPlacement, FallsOntoAVertexAndRollsOffIt) {
  // A square pyramid (apex 0 at height P) standing on a floor; a grain dropped a little off the apex
  // first touches the apex alone (|x - apex| = r), rolls off and comes to rest on the floor beside it.
  const double P = 3.0, B = 2.0, L = 10, r = 1.0;
  std::vector<Vec3> v = {{0, 0, P}, {-B, -B, 0}, {B, -B, 0}, {B, B, 0}, {-B, B, 0},
                         {-L, -L, 0}, {L, -L, 0}, {L, L, 0}, {-L, L, 0}};
  std::vector<std::array<int, 3>> t = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}};
  quad(t, 5, 6, 2, 1);
  quad(t, 6, 7, 3, 2);
  quad(t, 7, 8, 4, 3);
  quad(t, 8, 5, 1, 4);
  const HandMesh h = hand_mesh(v, t);
  const MeshIndex idx(*h.container.mesh, 2.0);
  const Vec3 drop = Vec3(0.05, 0.02, 0) + h.shift;
  double first = -1e300;
  for (int k = 0; k < idx.size(); ++k) {
    const double z = idx.fall_contact(k, Vec3(drop.x(), drop.y(), 50), r);
    if (!std::isnan(z)) first = std::max(first, z);
  }
  // Within the vertex's region (the apex's normal cone holds directions this steep), the contact is the
  // sphere about the apex.
  EXPECT_NEAR(first, P + std::sqrt(1.0 - 0.05 * 0.05 - 0.02 * 0.02), kTol);
  Deposition dep(3, h.container, r);
  const Grain& g = dep.place(drop_at(drop, r));
  EXPECT_LT(g.x.z(), P);  // it left the apex
  const CheckReport rep = check_packing(dep.grains(), 3, h.container);
  EXPECT_TRUE(rep.ok()) << rep.overlaps << " " << rep.unsupported << " " << rep.outside;
}

TEST(MeshPlacement, SlidesIntoACornerAndRestsOnThreeFaces) {
  // Three mutually perpendicular faces meeting at the origin with their diagonal vertical: the grain
  // slides down a face, along a groove, into the corner, and rests touching all three, its centre
  // r sqrt(3) above the corner.
  const double L = 20, r = 1.0;
  const Vec3 k = Vec3(1, 1, 1).normalized();
  const Vec3 i0 = Vec3(1, -1, 0).normalized(), j0 = k.cross(i0);
  Eigen::Matrix3d rot;  // maps the corner's axes: (1,1,1)/sqrt3 -> z
  rot.row(0) = i0.transpose(), rot.row(1) = j0.transpose(), rot.row(2) = k.transpose();
  std::vector<Vec3> v = {Vec3::Zero(), rot * Vec3(L, 0, 0), rot * Vec3(0, L, 0), rot * Vec3(0, 0, L)};
  std::vector<std::array<int, 3>> t = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}};
  const HandMesh h = hand_mesh(v, t);
  Deposition dep(3, h.container, r);
  const Vec3 corner = h.shift;
  const Grain& g = dep.place(drop_at(corner + Vec3(1.5, 2.0, 0), r));
  const Vec3 expect = corner + Vec3(0, 0, r * std::sqrt(3.0));
  EXPECT_LT((g.x - expect).norm(), 1e-8) << g.x.transpose() << " vs " << expect.transpose();
  const CheckReport rep = check_packing(dep.grains(), 3, h.container);
  EXPECT_TRUE(rep.ok());
}

TEST(MeshPlacement, OpenOutletRefusesGrainsThatWouldFallOut) {
  const std::string stl = std::string(BTR_SOURCE_DIR) + "/tests/data/open_hopper.stl";
  Container c;
  c.kind = ContainerKind::Mesh;
  c.mesh = read_mesh(stl, 1e-3);
  c.size_x = c.mesh->hi.x() - c.mesh->lo.x(), c.size_y = c.mesh->hi.y() - c.mesh->lo.y();
  Deposition dep(3, c, 1e-3);
  // Over the open outlet (radius 4 mm): refused before it falls, naming the file.
  try {
    dep.place(drop_at(Vec3(0.5e-3, 0.0, 0), 1e-3));
    FAIL() << "a drop over the open outlet was placed";
  } catch (const PlacementError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the footprint of the mesh " + stl), std::string::npos) << e.what();
    EXPECT_EQ(e.grain_id(), 1);
  }
  // Outside the rim (radius 20 mm): refused.
  EXPECT_THROW(dep.place(drop_at(Vec3(19.5e-3, 19.5e-3, 0), 1e-3)), PlacementError);
  // On the cone: it slides down to the outlet and through it: refused with the reason, never placed.
  try {
    dep.place(drop_at(Vec3(12e-3, 0.0, 0), 1e-3));
    FAIL() << "a grain that falls through the outlet was placed";
  } catch (const PlacementError& e) {
    EXPECT_NE(std::string(e.what()).find("falls out of the mesh"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(dep.grains().empty());
}

TEST(MeshPlacement, FilledHopperPassesTheSelfCheckAndIsDeterministic) {
  const Scene s = load_scene(std::string(BTR_SOURCE_DIR) + "/inputs/hopper.toml");
  const RunResult a = run_scene(s, 7, 400, {});
  const RunResult b = run_scene(s, 7, 400, {});
  ASSERT_EQ(a.grains.size(), 400u);
  for (std::size_t i = 0; i < a.grains.size(); ++i) {
    ASSERT_EQ(a.grains[i].x, b.grains[i].x) << i;
    ASSERT_EQ(a.grains[i].r, b.grains[i].r) << i;
  }
  const CheckReport rep = check_packing(a.grains, 3, s.container);
  EXPECT_TRUE(rep.ok()) << "overlaps " << rep.overlaps << " (max " << rep.max_overlap << "), unsupported "
                        << rep.unsupported << ", outside " << rep.outside;
  // Every grain inside the cone: its distance from the axis at most the cone's radius at its height less r
  // (radius 4 + 16 z / 25 mm, wall sloping at atan(25/16) from the horizontal: the centre is r / sin of
  // that slope's angle with the vertical inside the wall, measured horizontally), within round-off.
  const double slope = std::atan2(16.0, 25.0);
  for (const Grain& g : a.grains) {
    const double wall = 4e-3 + 16.0 / 25.0 * g.x.z();
    EXPECT_LE(std::hypot(g.x.x(), g.x.y()), wall - g.r / std::cos(slope) * 0.999) << g.x.transpose();
  }
}

TEST(MeshPlacement, SelfCheckFindsPenetrationFloatingAndOutside) {
  const HandMesh h = floor_mesh();
  Grains ok = {Grain{Vec3(0, 0, 1.0), 1.0, 1}};
  EXPECT_TRUE(check_packing(ok, 3, h.container).ok());
  Grains in = {Grain{Vec3(0, 0, 0.9), 1.0, 1}};
  EXPECT_GT(check_packing(in, 3, h.container).overlaps, 0);
  Grains floating = {Grain{Vec3(0, 0, 1.5), 1.0, 1}};
  EXPECT_GT(check_packing(floating, 3, h.container).unsupported, 0);
  Grains below = {Grain{Vec3(0, 0, -1.5), 1.0, 1}};
  EXPECT_GT(check_packing(below, 3, h.container).outside, 0);
  Grains beside = {Grain{Vec3(12, 0, 1.0), 1.0, 1}};
  EXPECT_GT(check_packing(beside, 3, h.container).outside, 0);
}

class MeshFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("btr_test_mesh_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::string error_of(const std::string& path, double scale = 1.0) {
    try {
      read_mesh(path, scale);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  }
  static std::string facet(const Vec3& a, const Vec3& b, const Vec3& c) {
    std::ostringstream s;
    s << "facet normal 0 0 1\nouter loop\n";
    for (const Vec3& p : {a, b, c}) s << "vertex " << p.x() << " " << p.y() << " " << p.z() << "\n";
    s << "endloop\nendfacet\n";
    return s.str();
  }
  fs::path dir_;
};

TEST_F(MeshFile, ReadsAsciiAndBinaryAlikeScaledAndPlaced) {
  const std::string ascii = write("a.stl", "solid a\n" + facet({10, 20, 5}, {30, 20, 5}, {10, 40, 9}) + "endsolid a\n");
  // The same triangle in binary STL: 80-byte header, count, then normal, 3 vertices (float32), attribute.
  std::string bin(80, ' ');
  auto put_u32 = [&](std::uint32_t v) { bin.append(reinterpret_cast<const char*>(&v), 4); };
  auto put_f = [&](float v) { bin.append(reinterpret_cast<const char*>(&v), 4); };
  put_u32(1);
  for (float v : {0.f, 0.f, 1.f, 10.f, 20.f, 5.f, 30.f, 20.f, 5.f, 10.f, 40.f, 9.f}) put_f(v);
  bin.append(2, '\0');
  const std::string binary = write("b.stl", bin);
  for (const std::string& p : {ascii, binary}) {
    SCOPED_TRACE(p);
    const auto m = read_mesh(p, 1e-3);
    ASSERT_EQ(m->triangles.size(), 1u);
    // Scaled to metres, then its box centred on the z axis with its lowest point at z = 0.
    EXPECT_NEAR(m->hi.x() - m->lo.x(), 0.020, 1e-12);
    EXPECT_NEAR(m->hi.y() - m->lo.y(), 0.020, 1e-12);
    EXPECT_NEAR(m->lo.x(), -0.010, 1e-12);
    EXPECT_NEAR(m->lo.z(), 0.0, 1e-15);
    EXPECT_NEAR(m->hi.z(), 0.004, 1e-12);
    EXPECT_NEAR(m->shift.x(), -0.020, 1e-12);
    EXPECT_NEAR(m->shift.z(), -0.005, 1e-12);
  }
}

TEST_F(MeshFile, BadMeshesAreRefusedNamingTheFile) {
  const std::string missing = (dir_ / "none.stl").string();
  EXPECT_NE(error_of(missing).find(missing + ": cannot open the mesh file"), std::string::npos) << error_of(missing);
  const std::string empty = write("empty.stl", "");
  EXPECT_NE(error_of(empty).find(empty + ":"), std::string::npos) << error_of(empty);
  const std::string junk = write("junk.stl", "solid x\nthis is not a facet\nendsolid x\n");
  EXPECT_NE(error_of(junk).find(junk + ":"), std::string::npos) << error_of(junk);
  // Triangle 1 of 3 is degenerate (its vertices on one line): reported by its index.
  const std::string degenerate =
      write("deg.stl", "solid d\n" + facet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}) + facet({0, 0, 1}, {1, 0, 1}, {2, 0, 1}) +
                           facet({0, 0, 2}, {1, 0, 2}, {0, 1, 2}) + "endsolid d\n");
  const std::string e = error_of(degenerate);
  EXPECT_NE(e.find(degenerate + ": 1 degenerate triangle"), std::string::npos) << e;
  EXPECT_NE(e.find(": 1"), std::string::npos) << e;
}

TEST_F(MeshFile, SceneRefusesAMeshSmallerThanOneGrainAndSizesOnNonMesh) {
  write("tiny.stl", "solid t\n" + facet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}) + facet({0, 0, 0}, {1, 0, 1}, {0, 1, 1}) + "endsolid t\n");
  const std::string scene = write("s.toml", R"([scene]
dimension = 3
[grains]
count = 10
radius = { distribution = "constant", value = 1e-3 }
[container]
kind = "mesh"
file = "tiny.stl"
scale = 1e-3
[source]
kind = "rain"
)");
  try {
    load_scene(scene);
    FAIL() << "a mesh smaller than one grain was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("smaller than one grain"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tiny.stl"), std::string::npos) << e.what();
  }
  const std::string box = write("b.toml", R"([scene]
dimension = 3
[grains]
count = 10
radius = { distribution = "constant", value = 1e-3 }
[container]
kind = "box"
size = [0.1, 0.1]
file = "x.stl"
[source]
kind = "rain"
)");
  EXPECT_THROW(load_scene(box), SceneError);
}

TEST_F(MeshFile, ASourceThatCannotReachTheFootprintIsRefusedBeforePlacing) {
  const std::string scene = write("p.toml", R"([scene]
dimension = 3
[grains]
count = 10
radius = { distribution = "constant", value = 1e-3 }
[container]
kind = "mesh"
file = ")" + std::string(BTR_SOURCE_DIR) + R"(/tests/data/open_hopper.stl"
scale = 1e-3
[source]
kind = "point"
position = [0.0, 0.0]
)");
  const Scene s = load_scene(scene);
  try {
    DropSequence drops(s, 1);
    FAIL() << "a point source over the open outlet was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("source.position"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("open_hopper.stl"), std::string::npos) << e.what();
  }
}
