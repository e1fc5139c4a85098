#pragma once
// Shared by the LIGGGHTS and YADE tests: the container cases every engine must relax, and checks of
// a relaxed packing computed independently of the coupling (brute force, by hand).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <ostream>
#include <string>
#include <vector>

#include "coupling/dem/relax.h"
#include "relax_fixtures.h"

namespace btr_test {

// The whole of a text file (empty if it is missing).
inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::string line_starting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(prefix, 0) == 0) return line;
  return "";
}

struct Case {
  std::string name;
  int dimension;
  btr::Container container;
  int grains;
};
// ctest shows the case by its name instead of a hex dump of the struct.
inline void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

inline std::vector<Case> all_cases() {
  using btr::ContainerKind;
  return {
      {"open3d", 3, container(ContainerKind::Open), 300},
      {"box3d", 3, container(ContainerKind::Box, 0.02, 0.016), 300},
      {"periodic3d", 3, container(ContainerKind::Periodic, 0.02, 0.02), 300},
      {"heleshaw3d", 3, container(ContainerKind::HeleShaw, 0.06, 0.005), 200},
      {"cylinder3d", 3, container(ContainerKind::Cylinder, 0.011), 300},
      {"open2d", 2, container(ContainerKind::Open), 200},
      {"box2d", 2, container(ContainerKind::Box, 0.05), 200},
      {"periodic2d", 2, container(ContainerKind::Periodic, 0.05), 200},
  };
}

// Largest pair overlap / smaller radius, brute force over all pairs (nearest periodic image).
inline double largest_pair_overlap(const btr::Grains& g, const btr::Container& c, int dim) {
  double worst = 0;
  for (std::size_t i = 0; i < g.size(); ++i)
    for (std::size_t j = i + 1; j < g.size(); ++j) {
      btr::Vec3 d = g[j].x - g[i].x;
      if (c.kind == btr::ContainerKind::Periodic) {
        d.x() -= c.size_x * std::round(d.x() / c.size_x);
        if (dim == 3) d.y() -= c.size_y * std::round(d.y() / c.size_y);
      }
      worst = std::max(worst, (g[i].r + g[j].r - d.norm()) / std::min(g[i].r, g[j].r));
    }
  return worst;
}

// Largest (r - distance to the wall) / r over grains and the container's true walls (the true
// cylinder, not an engine's facets); periodic grains must lie in the primary cell.
inline double largest_wall_overlap(const btr::Grains& g, const btr::Container& c, int dim) {
  double worst = 0;
  for (const btr::Grain& q : g) {
    std::vector<double> dist{q.x.z()};
    if (c.kind == btr::ContainerKind::Box) {
      dist.push_back(c.size_x / 2 - std::abs(q.x.x()));
      if (dim == 3) dist.push_back(c.size_y / 2 - std::abs(q.x.y()));
    } else if (c.kind == btr::ContainerKind::HeleShaw) {
      dist.push_back(c.size_x / 2 - std::abs(q.x.x()));
      dist.push_back(c.gap / 2 - std::abs(q.x.y()));
    } else if (c.kind == btr::ContainerKind::Cylinder) {
      dist.push_back(c.radius - std::hypot(q.x.x(), q.x.y()));
    } else if (c.kind == btr::ContainerKind::Periodic) {
      EXPECT_TRUE(q.x.x() >= -c.size_x / 2 && q.x.x() < c.size_x / 2) << q.x.x();
      if (dim == 3) {
        EXPECT_TRUE(q.x.y() >= -c.size_y / 2 && q.x.y() < c.size_y / 2) << q.x.y();
      }
    }
    for (double d : dist) worst = std::max(worst, (q.r - d) / q.r);
  }
  return worst;
}

// The stop threshold stop_kinetic_ratio * sum m g d, by hand.
inline double threshold_by_hand(const btr::Grains& g, const btr::Scene& s) {
  double sum = 0;
  for (const btr::Grain& q : g) {
    const double m = 4.0 / 3.0 * M_PI * q.r * q.r * q.r * s.grains.components[q.species - 1].density;
    sum += m * 9.81 * 2 * q.r;
  }
  return s.relax.stop_kinetic_ratio * sum;
}

// velocities.csv (id,vx,vy,vz) as written by relax(): one row per grain, ids 1..N in order, the values of
// RelaxResult::velocities; returns their translational kinetic energy sum m v^2 / 2 (sphere masses).
inline double check_velocities_file(const btr::Scene& scene, const btr::Packing& in, const btr::RelaxResult& r,
                                    const std::string& dir) {
  EXPECT_EQ(r.velocities.size(), in.grains.size());
  std::ifstream f(dir + "/velocities.csv");
  std::string line;
  EXPECT_TRUE(std::getline(f, line) && line == "id,vx,vy,vz") << line;
  double energy = 0;
  std::size_t rows = 0;
  while (std::getline(f, line)) {
    long id = 0;
    double v[3];
    EXPECT_EQ(std::sscanf(line.c_str(), "%ld,%lf,%lf,%lf", &id, &v[0], &v[1], &v[2]), 4) << line;
    ++rows;
    EXPECT_EQ(id, static_cast<long>(rows));
    if (rows > in.grains.size() || rows > r.velocities.size()) break;
    const btr::Vec3 vel(v[0], v[1], v[2]);
    EXPECT_TRUE(vel.allFinite()) << line;
    EXPECT_EQ(vel, r.velocities[rows - 1]) << "%.17g round trip, row " << rows;
    if (scene.dimension == 2) {
      EXPECT_EQ(vel.y(), 0.0) << "2D grains do not move along y";
    }
    const btr::Grain& g = in.grains[rows - 1];
    const double m = 4.0 / 3.0 * M_PI * g.r * g.r * g.r * scene.grains.components[g.species - 1].density;
    energy += 0.5 * m * vel.squaredNorm();
  }
  EXPECT_EQ(rows, in.grains.size());
  return energy;
}

// Checks every engine's relaxation must pass; `out` receives the relaxed packing read back from dir.
inline void check_relaxed_packing(const Case& c, const btr::Scene& scene, const btr::Packing& in,
                                  const btr::RelaxResult& r, const std::string& dir, btr::Packing& out) {
  EXPECT_EQ(r.stop_reason, "kinetic-energy") << "it should settle before max_time";
  EXPECT_GT(r.simulated_time, 0.0);
  EXPECT_LT(r.simulated_time, scene.relax.max_time);
  out = btr::read_packing(dir + "/relaxed.csv");  // ids 1..N in order, checked there
  ASSERT_EQ(out.grains.size(), in.grains.size());
  double moved = 0, z_in = 0, z_out = 0;
  for (std::size_t i = 0; i < in.grains.size(); ++i) {
    EXPECT_EQ(out.grains[i].r, in.grains[i].r);
    EXPECT_EQ(out.grains[i].species, in.grains[i].species);
    if (c.dimension == 2) {
      EXPECT_EQ(out.grains[i].x.y(), 0.0) << "2D grains stay in y = 0";
    }
    moved = std::max(moved, (out.grains[i].x - in.grains[i].x).norm());
    z_in += in.grains[i].x.z();
    z_out += out.grains[i].x.z();
  }
  EXPECT_GT(moved, 0.05e-3) << "the grains started above their supports and must have fallen";
  EXPECT_LT(z_out, z_in) << "the bed settles";
  EXPECT_LT(largest_pair_overlap(out.grains, c.container, c.dimension), 0.01);
  EXPECT_LT(largest_wall_overlap(out.grains, c.container, c.dimension), 0.01);
  ASSERT_FALSE(r.kinetic_history.empty());
  EXPECT_EQ(r.kinetic_history.front().first, 0.0);
  EXPECT_LT(r.kinetic_history.back().second, threshold_by_hand(in.grains, scene));
  EXPECT_EQ(out.meta["relax"]["stop_reason"], "kinetic-energy");
  EXPECT_GT(static_cast<long>(r.contacts.size()), static_cast<long>(in.grains.size()) / 2);
  // The floor carries the weight where there are no side walls to share it (static balance).
  if (c.container.kind == btr::ContainerKind::Open || c.container.kind == btr::ContainerKind::Periodic) {
    double floor = 0, weight = 0;
    for (const auto& k : r.contacts)
      if (k.j == 0) floor += k.fn;
    for (const btr::Grain& q : in.grains)
      weight += 4.0 / 3.0 * M_PI * std::pow(q.r, 3) * scene.grains.components[q.species - 1].density * 9.81;
    EXPECT_NEAR(floor / weight, 1.0, 0.02) << "floor force " << floor << " N, weight " << weight << " N";
  }
}

}  // namespace btr_test
