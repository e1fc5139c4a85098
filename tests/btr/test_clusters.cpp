// Rigid clusters: hand geometry, invariants of random cluster packings, the independent check.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "btr/model/cluster.h"
#include "btr/placement/cluster_placement.h"
#include "btr/placement/deposition.h"
#include "btr/placement/neighbour_grid.h"
#include "btr/verify/cluster_check.h"
#include "btr/verify/cluster_unwrap.h"
#include "containers.h"

namespace btr {
namespace {

using test::box;
using test::periodic;


ClusterShape dimer(double r) {
  ClusterShape s;
  s.add(Vec3(-r, 0, 0), r);
  s.add(Vec3(r, 0, 0), r);
  return s;
}

Eigen::Quaterniond about_y(double angle) { return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Vec3::UnitY())); }

Vec3 centre_of_mass(const Grains& g, int dim) {
  Vec3 G = Vec3::Zero();
  double m = 0;
  for (const Grain& x : g) { G += std::pow(x.r, dim) * x.x; m += std::pow(x.r, dim); }
  return G / m;
}

// A tilted dimer on a frictionless floor: only vertical forces act, so its centre of mass falls
// straight down and it ends flat, both members on the floor, its axis in the plane it started in.
TEST(Clusters, DimerLiesFlatOnTheFloor) {
  for (int dim : {2, 3}) {
    Deposition dep(dim, box(10, 10), 0.5);
    ClusterDrop drop;
    drop.x = 0.3;
    drop.y = 0.2;
    drop.shape = dimer(0.5);
    drop.orientation = about_y(0.6);
    EXPECT_EQ(dep.place_cluster(drop), 1);
    const Grains& g = dep.grains();
    ASSERT_EQ(g.size(), 2u);
    const double y = dim == 3 ? 0.2 : 0.0;
    for (const Grain& x : g) {
      EXPECT_NEAR(x.x.z(), 0.5, 1e-9) << dim;
      EXPECT_NEAR(x.x.y(), y, 1e-12) << dim;
      EXPECT_EQ(x.cluster, 1);
    }
    EXPECT_NEAR(std::min(g[0].x.x(), g[1].x.x()), -0.2, 1e-9) << dim;
    EXPECT_NEAR(std::max(g[0].x.x(), g[1].x.x()), 0.8, 1e-9) << dim;
    EXPECT_NEAR((g[0].x - g[1].x).norm(), 1.0, 1e-12);
    EXPECT_TRUE(check_clusters(g, dim, box(10, 10)).ok());
  }
}

// A tilted dimer whose upper member touches the wall x = +2 at the drop: the wall only pushes it
// towards -x, so it ends flat on the floor against the wall: members at x = 1.5 and 0.5.
TEST(Clusters, DimerSlidesDownAWall) {
  for (int dim : {2, 3}) {
    Deposition dep(dim, box(4, 4), 0.5);
    ClusterDrop drop;
    const double tilt = M_PI / 4;  // upper member towards +x
    drop.shape = dimer(0.5);
    drop.orientation = about_y(-tilt);
    drop.x = 1.5 - 0.5 * std::cos(tilt);
    dep.place_cluster(drop);
    const Grains& g = dep.grains();
    const Grain& right = g[0].x.x() > g[1].x.x() ? g[0] : g[1];
    const Grain& left = g[0].x.x() > g[1].x.x() ? g[1] : g[0];
    EXPECT_NEAR(right.x.x(), 1.5, 1e-9) << dim;
    EXPECT_NEAR(left.x.x(), 0.5, 1e-9) << dim;
    EXPECT_NEAR(right.x.z(), 0.5, 1e-9) << dim;
    EXPECT_NEAR(left.x.z(), 0.5, 1e-9) << dim;
    EXPECT_TRUE(check_clusters(g, dim, box(4, 4)).ok());
  }
}

// A flat equilateral trimer (side 2r) over three fixed grains at the corners of a triangle of side
// 1.2 (2r = 1), turned by 60 degrees so each member nests between two supports. Dropped off centre,
// it slides into the nest: centre of mass on the axis, members at the height closed form below.
TEST(Clusters, TrimerNestsOnThreeGrains) {
  const double r = 0.5, a = 1.2 / std::sqrt(3.0), b = 1.0 / std::sqrt(3.0);
  Deposition dep(3, box(10, 10), r);
  for (int k = 0; k < 3; ++k) {
    Drop d;
    d.x = a * std::cos(2 * M_PI * k / 3);
    d.y = a * std::sin(2 * M_PI * k / 3);
    d.r = r;
    dep.place(d);
  }
  ClusterShape tri;
  for (int k = 0; k < 3; ++k)
    tri.add(Vec3(b * std::cos(2 * M_PI * k / 3 + M_PI / 3), b * std::sin(2 * M_PI * k / 3 + M_PI / 3), 0), r);
  ClusterDrop drop;
  drop.shape = tri;
  drop.x = 0.04;
  drop.y = -0.03;
  dep.place_cluster(drop);
  const Grains& g = dep.grains();
  ASSERT_EQ(g.size(), 6u);
  // Horizontal distance member-support: law of cosines with the 60 degree offset.
  const double dxy2 = a * a + b * b - 2 * a * b * std::cos(M_PI / 3);
  const double z = r + std::sqrt(4 * r * r - dxy2);
  const Grains members(g.begin() + 3, g.end());
  const Vec3 G = centre_of_mass(members, 3);
  EXPECT_NEAR(G.x(), 0.0, 1e-7);
  EXPECT_NEAR(G.y(), 0.0, 1e-7);
  for (const Grain& m : members) EXPECT_NEAR(m.x.z(), z, 1e-7);
  EXPECT_TRUE(check_clusters(g, 3, box(10, 10)).ok());
}

struct Pile {
  Grains grains;
  std::vector<ClusterShape> shapes;
};

Pile random_pile(int dim, const Container& c, int clusters, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Deposition dep(dim, c, 0.55);
  Pile p;
  auto radius = [](std::mt19937_64& g) { return std::uniform_real_distribution<double>(0.45, 0.55)(g); };
  for (int i = 0; i < clusters; ++i) {
    const int n = 1 + static_cast<int>(rng() % 5);
    ClusterDrop d;
    d.shape = random_compact_cluster(dim, n, rng, radius);
    d.orientation = random_orientation(dim, rng);
    const double half = 0.5 * c.size_x - d.shape.extent();
    d.x = std::uniform_real_distribution<double>(-half, half)(rng);
    d.y = dim == 3 ? std::uniform_real_distribution<double>(-half, half)(rng) : 0.0;
    dep.place_cluster(d);
    p.shapes.push_back(d.shape);
  }
  p.grains = dep.release();
  return p;
}

// Largest change of a distance between two members of one cluster, placed against its shape (in a
// periodic container the members are wrapped one by one: the nearest images are compared).
double worst_shape_change(const Pile& p, const Container& c) {
  const auto bodies = rigid_bodies(p.grains);
  if (bodies.size() != p.shapes.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (std::size_t b = 0; b < bodies.size(); ++b)
    for (std::size_t i = 0; i < bodies[b].size(); ++i)
      for (std::size_t j = i + 1; j < bodies[b].size(); ++j) {
        Vec3 dx = p.grains[bodies[b][i]].x - p.grains[bodies[b][j]].x;
        if (c.kind == ContainerKind::Periodic) {
          dx.x() -= c.size_x * std::round(dx.x() / c.size_x);
          if (c.size_y > 0.0) dx.y() -= c.size_y * std::round(dx.y() / c.size_y);
        }
        const double placed = dx.norm();
        const double shape = (p.shapes[b].offsets[i] - p.shapes[b].offsets[j]).norm();
        worst = std::max(worst, std::abs(placed - shape));
      }
  return worst;
}

// Random cluster packings: no overlap between clusters, every cluster supported (independent check),
// members' relative positions as in the shape to 1e-12, and the same seed gives the same packing.
TEST(Clusters, RandomPackingsKeepTheirInvariants) {
  for (int dim : {2, 3}) {
    const Container c = box(dim == 3 ? 6 : 16, 6);
    const Pile p = random_pile(dim, c, dim == 3 ? 40 : 50, 7);
    const ClusterCheckReport rep = check_clusters(p.grains, dim, c);
    EXPECT_TRUE(rep.ok()) << "dim " << dim << ": overlaps " << rep.overlaps << " (max " << rep.max_overlap
                          << "), unsupported " << rep.unsupported;
    EXPECT_EQ(rep.bodies, static_cast<std::int64_t>(p.shapes.size()));
    EXPECT_LT(worst_shape_change(p, c), 1e-12) << dim;
    const Pile again = random_pile(dim, c, dim == 3 ? 40 : 50, 7);
    ASSERT_EQ(again.grains.size(), p.grains.size());
    for (std::size_t i = 0; i < p.grains.size(); ++i) EXPECT_EQ(again.grains[i].x, p.grains[i].x);
  }
}

// 3D rest positions where a member touches two obstacles that the rest projection closed in turn (a
// wall and a neighbour, two neighbours) used to keep a member inside one of them by up to ~6e-8 r (2
// of these 20 piles; the check's tolerance is 1e-9 r). Every pile now passes the independent check, and
// the rest positions repeat exactly.
TEST(Clusters, RestPositionsIn3DLeaveNoMemberInsideAnObstacle) {
  const Container c = box(6, 6);
  int failed = 0;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const Pile p = random_pile(3, c, 40, seed);
    const ClusterCheckReport rep = check_clusters(p.grains, 3, c);
    if (!rep.ok() && failed++ < 3)
      ADD_FAILURE() << "seed " << seed << ": overlaps " << rep.overlaps << " (max " << rep.max_overlap
                    << " r), unsupported " << rep.unsupported;
    EXPECT_LT(worst_shape_change(p, c), 1e-12) << "seed " << seed;
  }
  EXPECT_EQ(failed, 0);
  const Pile once = random_pile(3, c, 40, 15), again = random_pile(3, c, 40, 15);
  for (std::size_t i = 0; i < once.grains.size(); ++i) EXPECT_EQ(once.grains[i].x, again.grains[i].x);
}

// A step whose Newton projection diverged used to be accepted when the overlap test, which sees only
// the obstacles gathered near the members, found nothing: in this periodic pile a cluster of three
// jumped about 1 r into three others (overlap 1.2 r). Such steps are now refused.
TEST(Clusters, StepsWhoseProjectionDivergesAreRefused) {
  const Container c = periodic(6, 6);
  const Pile p = random_pile(3, c, 40, 133);
  const ClusterCheckReport rep = check_clusters(p.grains, 3, c);
  EXPECT_EQ(rep.overlaps, 0) << "max " << rep.max_overlap << " r";
  EXPECT_LT(worst_shape_change(p, c), 1e-12);
}

// A descent that ended by the halving rule short of balance: at each step one of four loaded contacts
// unloaded within 2e-9 r, the step cut short there did not lower the centre of mass measurably (the
// descent over it is below the resolution of z) and was refused, until the step was negligible.
// Replayed through the engine's interface from the 3D nano-powder workflow (the cluster and the fixed
// grains near its path, tests/btr/data/cluster_rest_by_rule.txt); the independent check must find the
// cluster supported.
TEST(Clusters, DescentDoesNotStopShortOfBalanceWhereASupportUnloads) {
  const std::string path = std::string(BTR_SOURCE_DIR) + "/tests/btr/data/cluster_rest_by_rule.txt";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  Container c = box(0, 0);
  double r_max = 0.0, top = 0.0;
  ClusterDrop drop;
  Grains grains;
  for (std::string line; std::getline(in, line);) {
    std::istringstream f(line);
    std::string tag;
    f >> tag;
    if (tag == "box") {
      f >> c.size_x;
      c.size_y = c.size_x;
    } else if (tag == "engine") {
      f >> r_max >> top;
    } else if (tag == "drop") {
      double w, x, y, z;
      f >> drop.x >> drop.y >> w >> x >> y >> z;
      drop.orientation = Eigen::Quaterniond(w, x, y, z);
    } else if (tag == "member" || tag == "grain") {
      Vec3 x;
      double r;
      f >> x.x() >> x.y() >> x.z() >> r;
      if (tag == "member") {
        drop.shape.add(x, r);
      } else {
        grains.push_back(Grain{x, r, 1});
        grains.back().cluster = 2;  // the fixed grains as one body: only the placed cluster is in question
      }
    }
    ASSERT_FALSE(f.fail()) << path << ": " << line;
  }
  ASSERT_EQ(drop.shape.size(), 3u);
  ASSERT_EQ(grains.size(), 112u);
  NeighbourGrid grid(3, c, r_max);
  for (std::size_t i = 0; i < grains.size(); ++i) grid.insert(static_cast<std::int32_t>(i), grains[i].x, grains[i].r);
  std::int32_t clusters = 0;
  ClusterEngine engine{3, c, r_max, 10000, grains, grid, top, clusters};
  ASSERT_EQ(place_rigid_cluster(engine, drop), 1);
  const ClusterCheckReport rep = check_clusters(grains, 3, c);
  EXPECT_EQ(rep.overlaps, 0) << rep.max_overlap;
  for (std::int64_t id : rep.examples) EXPECT_NE(grains[id - 1].cluster, 1) << "the placed cluster is unsupported";
}

// A grain at (x, 0, z): in the x-z plane, so in 2D too.
Grain grain_at(double x, double z, double r, std::int32_t cluster) {
  Grain g{Vec3(x, 0.0, z), r, 1};
  g.cluster = cluster;
  return g;
}

// Each grain wrapped into the periodic cell [-L/2, L/2) on its own, as in a packing.
Grains wrapped(Grains g, double L) {
  for (Grain& x : g) x.x.x() -= L * std::floor(x.x.x() / L + 0.5);
  return g;
}

bool flagged(const ClusterCheckReport& rep, std::int64_t id) {
  return std::find(rep.examples.begin(), rep.examples.end(), id) != rep.examples.end();
}

// A dimer (radius 0.5) across the boundary x = 3 of a periodic cell 6 wide, in the x-z plane (2D, and
// 3D at y = 0). Props are single grains on the floor. (1) Flat on the floor: supported. (2) Leaning at
// 60 degrees, its foot A on the floor against T, its top B against the side of S: the horizontal pushes
// of T and S balance each other and their torque about A, f s = c / 2 (c, s: cosine and sine of the
// tilt), is that of the weight, so f = 1 / (2 sqrt 3) >= 0: supported. (3) The same dimer tilted over
// T (B up-left of A, resting on T with the normal (1/2, sqrt 3 / 2)): every contact except the floor
// under A pushes towards +x, so only the floor can carry it, and the centre of mass is not above A:
// unsupported.
TEST(Clusters, CheckUnwrapsADimerAcrossThePeriodicBoundary) {
  const double L = 6.0, r = 0.5, c = 0.5, s = std::sqrt(3.0) / 2.0, rS = r + s;
  const double a = 0.5 * L - 0.25;  // the foot; the centre of mass of (1) and (2) is on the boundary
  const Grains flat = wrapped({grain_at(a, r, r, 1), grain_at(a + 2 * r, r, r, 1)}, L);
  const Grains leaning = wrapped({grain_at(a, r, r, 1), grain_at(a + c, r + s, r, 1), grain_at(a - 2 * r, r, r, 0),
                                  grain_at(a + c + r + rS, rS, rS, 0)},
                                 L);
  const double b = -a;  // (3) on the other side of the boundary: A and T touch across it
  const Grains tilted =
      wrapped({grain_at(b, r, r, 1), grain_at(b - c, r + s, r, 1), grain_at(b - 2 * r, r, r, 0)}, L);
  ASSERT_LT(flat[1].x.x(), 0.0);
  ASSERT_LT(leaning[1].x.x(), 0.0);
  ASSERT_GT(tilted[1].x.x(), 0.0);
  ASSERT_GT(tilted[2].x.x(), 0.0);
  for (int dim : {2, 3}) {
    const Container cell = dim == 3 ? periodic(L, L) : periodic(L);
    const ClusterCheckReport one = check_clusters(flat, dim, cell);
    EXPECT_TRUE(one.ok()) << dim << ": overlaps " << one.overlaps << ", unsupported " << one.unsupported;
    EXPECT_EQ(one.bodies, 1);
    const ClusterCheckReport two = check_clusters(leaning, dim, cell);
    EXPECT_TRUE(two.ok()) << dim << ": overlaps " << two.overlaps << ", unsupported " << two.unsupported;
    EXPECT_EQ(two.bodies, 3);
    const ClusterCheckReport three = check_clusters(tilted, dim, cell);
    EXPECT_EQ(three.overlaps, 0) << dim << ": max " << three.max_overlap;
    EXPECT_EQ(three.unsupported, 1) << dim;
    EXPECT_TRUE(flagged(three, 1)) << dim;
  }
}

// A rigid chain of 7 touching grains (radius 0.5, 6 diameters long) leaning at 30 degrees in a periodic
// cell 10 wide, listed from the top: its ends are 5.2 apart in x, more than half a period, so the image
// of the foot nearest the first member is the wrong one. Foot on the floor against T, top against the
// top member of a column of 4 grains (one cluster) standing on the floor: supported as the leaning dimer
// above (f = c / (2 s)), lying inside the cell or across its boundary.
TEST(Clusters, CheckUnwrapsAClusterWiderThanHalfTheCell) {
  const double L = 10.0, r = 0.5, c = std::cos(M_PI / 6), s = 0.5;
  for (double a : {-4.9, 1.0}) {  // the foot: the chain inside the cell, then across x = 5
    Grains g;
    for (int k = 6; k >= 0; --k) g.push_back(grain_at(a + 2 * r * k * c, r + 2 * r * k * s, r, 1));
    for (int k = 0; k < 4; ++k) g.push_back(grain_at(a + 12 * r * c + 2 * r, r + 2 * r * k, r, 2));
    g.push_back(grain_at(a - 2 * r, r, r, 0));
    g = wrapped(g, L);
    EXPECT_EQ(g[0].x.x() < g[6].x.x(), a > 0) << a;  // the top wrapped to the other side
    for (int dim : {2, 3}) {
      const ClusterCheckReport rep = check_clusters(g, dim, dim == 3 ? periodic(L, L) : periodic(L));
      EXPECT_TRUE(rep.ok()) << a << ", " << dim << ": overlaps " << rep.overlaps << ", unsupported "
                            << rep.unsupported;
      EXPECT_EQ(rep.bodies, 3);
    }
  }
}

// The unwrapping the check and the DEM export share: the chain above across x = 5 (wider than half the cell,
// listed from the top) and a free grain, wrapped. Every member comes back where it was before wrapping,
// give or take one shift by a whole period for the whole cluster; the first member and the free grain keep
// their wrapped positions; a box changes nothing.
TEST(Clusters, UnwrapBringsAClusterWiderThanHalfTheCellTogether) {
  const double L = 10.0, r = 0.5, c = std::cos(M_PI / 6), s = 0.5, a = 1.0;
  Grains g;
  for (int k = 6; k >= 0; --k) g.push_back(grain_at(a + 2 * r * k * c, r + 2 * r * k * s, r, 1));
  g.push_back(grain_at(a - 2 * r, r, r, 0));
  const Grains w = wrapped(g, L);
  for (int dim : {2, 3}) {
    const std::vector<Vec3> at = unwrap_clusters(w, dim, dim == 3 ? periodic(L, L) : periodic(L));
    ASSERT_EQ(at.size(), g.size());
    EXPECT_EQ(at[0], w[0].x) << dim;
    EXPECT_EQ(at[7], w[7].x) << dim;
    const Vec3 shift = at[0] - g[0].x;
    EXPECT_NEAR(std::abs(shift.x()), L, 1e-12) << dim;  // the top member wrapped to the other side
    for (int k = 1; k < 7; ++k) EXPECT_LT((at[k] - g[k].x - shift).norm(), 1e-12) << dim << ", member " << k;
    const std::vector<Vec3> in_box = unwrap_clusters(w, dim, dim == 3 ? box(L, L) : box(L));
    for (std::size_t i = 0; i < w.size(); ++i) EXPECT_EQ(in_box[i], w[i].x) << dim << ", grain " << i;
  }
}

// Random 3D piles in a periodic cell: clusters come to rest across the boundary (members wrapped to
// opposite sides), and every pile passes the check; such a cluster lifted off its supports does not.
TEST(Clusters, PeriodicPilesAcrossTheBoundaryPassTheCheck) {
  const Container c = periodic(6, 6);
  int failed = 0, across = 0, lifted = 0;
  for (std::uint64_t seed = 0; seed < 30; ++seed) {
    const Pile p = random_pile(3, c, 40, seed);
    for (const auto& body : rigid_bodies(p.grains)) {
      bool split = false;
      for (std::size_t i : body) {
        const Vec3 d = p.grains[i].x - p.grains[body.front()].x;
        split = split || std::abs(d.x()) > 0.5 * c.size_x || std::abs(d.y()) > 0.5 * c.size_y;
      }
      across += split;
      if (split && lifted++ < 5) {
        Grains up = p.grains;
        for (std::size_t i : body) up[i].x.z() += 0.01;
        EXPECT_TRUE(flagged(check_clusters(up, 3, c), static_cast<std::int64_t>(body.front()) + 1)) << "seed " << seed;
      }
    }
    const ClusterCheckReport rep = check_clusters(p.grains, 3, c);
    EXPECT_EQ(rep.bodies, 40) << "seed " << seed;
    if (!rep.ok() && failed++ < 3)
      ADD_FAILURE() << "seed " << seed << ": overlaps " << rep.overlaps << " (max " << rep.max_overlap
                    << " r), unsupported " << rep.unsupported;
  }
  EXPECT_EQ(failed, 0);
  EXPECT_GE(across, 100);  // 168 when written: the test does exercise clusters across the boundary
}

// The independent check catches a cluster lifted off its supports and one pushed into another.
TEST(Clusters, CheckCatchesBrokenPackings) {
  const Container c = box(6, 6);
  Pile p = random_pile(3, c, 20, 3);
  ASSERT_TRUE(check_clusters(p.grains, 3, c).ok());
  Grains lifted = p.grains, sunk = p.grains;
  const std::int32_t last = p.grains.back().cluster;
  for (Grain& g : lifted)
    if (g.cluster == last) g.x.z() += 0.01;
  EXPECT_EQ(check_clusters(lifted, 3, c).unsupported, 1);
  for (Grain& g : sunk)
    if (g.cluster == last) g.x.z() -= 0.05;
  EXPECT_GT(check_clusters(sunk, 3, c).overlaps, 0);
}

// More than 14 contacts (the check's projected-gradient branch): a vertical column of 16 disks, one
// cluster, each member touching the wall x = -2: supported when it stands on the floor, not when lifted.
TEST(Clusters, CheckWithManyContacts) {
  const Container c = box(4, 4);
  Grains column;
  for (int k = 0; k < 16; ++k) {
    Grain g;
    g.x = Vec3(-1.5, 0.0, 0.5 + k);
    g.r = 0.5;
    g.cluster = 1;
    column.push_back(g);
  }
  EXPECT_TRUE(check_clusters(column, 2, c).ok());
  for (Grain& g : column) g.x.z() += 0.01;
  const ClusterCheckReport lifted = check_clusters(column, 2, c);
  EXPECT_EQ(lifted.unsupported, 1);
  EXPECT_EQ(lifted.overlaps, 0);
}

// A one-grain cluster follows the same physics as a grain: both engines give the same packing.
TEST(Clusters, SingleGrainClustersMatchTheGrainEngine) {
  const Container c = box(5, 5);
  Deposition grains(3, c, 0.5), clusters(3, c, 0.5);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(-2.0, 2.0), rad(0.4, 0.5);
  for (int i = 0; i < 60; ++i) {
    Drop d;
    d.x = pos(rng);
    d.y = pos(rng);
    d.r = rad(rng);
    grains.place(d);
    ClusterDrop cd;
    cd.x = d.x;
    cd.y = d.y;
    cd.shape.add(Vec3::Zero(), d.r);
    clusters.place_cluster(cd);
  }
  int far = 0;
  for (std::size_t i = 0; i < grains.grains().size(); ++i)
    if ((grains.grains()[i].x - clusters.grains()[i].x).norm() > 1e-6 && far++ == 0)
      ADD_FAILURE() << "first difference at grain " << i + 1 << ": " << grains.grains()[i].x.transpose() << " vs "
                    << clusters.grains()[i].x.transpose();
  EXPECT_EQ(far, 0);
}

// An exhausted event budget is an error naming the cluster.
TEST(Clusters, BudgetExceededNamesTheCluster) {
  Deposition dep(3, box(6, 6), 0.5, 1);  // 20 steps per cluster
  std::mt19937_64 rng(5);
  auto radius = [](std::mt19937_64&) { return 0.5; };
  try {
    for (int i = 0; i < 30; ++i) {
      ClusterDrop d;
      d.shape = random_compact_cluster(3, 6, rng, radius);
      d.orientation = random_orientation(3, rng);
      dep.place_cluster(d);
    }
    FAIL() << "no budget error";
  } catch (const PlacementError& e) {
    EXPECT_NE(std::string(e.what()).find("cluster "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("steps"), std::string::npos) << e.what();
  }
}

TEST(Clusters, RandomCompactClustersTouchAndDoNotOverlap) {
  std::mt19937_64 rng(1);
  auto radius = [](std::mt19937_64& g) { return std::uniform_real_distribution<double>(0.9, 1.1)(g); };
  for (int dim : {2, 3}) {
    const ClusterShape s = random_compact_cluster(dim, 12, rng, radius);
    ASSERT_EQ(s.size(), 12u);
    Vec3 G = Vec3::Zero();
    double m = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      G += std::pow(s.radii[i], dim) * s.offsets[i];
      m += std::pow(s.radii[i], dim);
      if (dim == 2) {
        EXPECT_EQ(s.offsets[i].y(), 0.0);
      }
      int touching = 0;
      for (std::size_t j = 0; j < s.size(); ++j) {
        if (i == j) continue;
        const double gap = (s.offsets[i] - s.offsets[j]).norm() - s.radii[i] - s.radii[j];
        EXPECT_GT(gap, -1e-12);
        touching += gap < 1e-12;
      }
      EXPECT_GE(touching, 1);
    }
    EXPECT_LT((G / m).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace btr
