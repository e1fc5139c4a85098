// The drum's mesh for the DEM engines (coupling/dem/drum_mesh.h): panels tangent to the exact cylinder, few
// enough and no fewer than the sagitta bound asks, end discs only with end walls, the 2D slab inside the
// coupling's one.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "coupling/dem/drum_mesh.h"

namespace btr {
namespace {

Grains two_grains(double r_min, double r_max) {
  Grains g(2);
  g[0].r = r_min;
  g[1].r = r_max;
  return g;
}

TEST(DrumMesh, PanelCountMeetsTheSagittaBoundAndNoMore) {
  for (double ratio : {10.0, 37.5, 200.0, 1000.0}) {
    const double R = 0.02, r_min = R / ratio;
    const int n = drum_panels(R, r_min);
    EXPECT_LE(R * (1 - std::cos(M_PI / n)), kDrumSagittaFraction * r_min) << ratio;
    if (n > 64) {
      EXPECT_GT(R * (1 - std::cos(M_PI / (n / 2))), kDrumSagittaFraction * r_min) << ratio;
    }
    EXPECT_EQ(n & (n - 1), 0) << "a power of two";
  }
  EXPECT_EQ(drum_panels(1.0, 2.0), 64);  // the floor (only for grains wider than the drum: never in a scene)
}

TEST(DrumMesh, PanelsAreTangentToTheCylinderAndEndsFollowTheScene) {
  Container c;
  c.kind = ContainerKind::Drum;
  c.radius = 0.01;
  c.size_y = 0.004;
  for (int variant = 0; variant < 3; ++variant) {  // 3D walls, 3D periodic, 2D
    const int dim = variant == 2 ? 2 : 3;
    c.periodic_ends = variant == 1;
    const auto m = drum_mesh(c, dim, two_grains(4e-4, 6e-4));
    const int n = drum_panels(c.radius, 4e-4);
    if (variant == 0) {  // the end discs cover the rim polygon exactly once: their areas sum to its area, twice
      double area = 0.0;
      for (std::size_t t = 2 * n; t < m->triangles.size(); ++t) {
        const auto& tri = m->triangles[t];
        const Vec3 e = (m->vertices[tri[1]] - m->vertices[tri[0]]).cross(m->vertices[tri[2]] - m->vertices[tri[0]]);
        area += 0.5 * e.norm();
        EXPECT_NEAR(std::abs(e.normalized().y()), 1.0, 1e-12);  // flat, in an end plane
        EXPECT_EQ((e.y() > 0) == (m->vertices[tri[0]].y() > 0), true) << "normal points out of the drum";
      }
      const double rv = c.radius / std::cos(M_PI / n);
      EXPECT_NEAR(area, 2.0 * 0.5 * n * rv * rv * std::sin(2.0 * M_PI / n), 1e-9 * area);
    } else {
      ASSERT_EQ(m->triangles.size(), static_cast<std::size_t>(2 * n)) << variant;
    }
    const double half = dim == 2 ? 3e-4 : 0.002;
    for (int t = 0; t < 2 * n; ++t) {  // the cylinder's triangles: their plane touches the cylinder
      const auto& tri = m->triangles[t];
      const Vec3 a = m->vertices[tri[0]], b = m->vertices[tri[1]], d = m->vertices[tri[2]];
      Vec3 normal = (b - a).cross(d - a).normalized();
      const Vec3 axis_point(0.0, a.y(), c.radius);
      EXPECT_NEAR(std::abs(normal.dot(a - axis_point)), c.radius, 1e-12) << "triangle " << t;
      EXPECT_NEAR(std::abs(normal.y()), 0.0, 1e-12);
      for (int v : tri) EXPECT_NEAR(std::abs(m->vertices[v].y()), half, 1e-15);
    }
    EXPECT_NEAR(m->lo.z(), c.radius - c.radius / std::cos(M_PI / n), 1e-15);
    EXPECT_LT(m->lo.z(), 0.0);  // the vertices lie just outside R, below the lowest line
    EXPECT_GT(m->lo.z(), -kDrumSagittaFraction * 4e-4 * 1.01);
  }
}

}  // namespace
}  // namespace btr
