#pragma once
// Rigid clusters of touching grains (seed 000 section 5: cohesive nano-powder agglomerates).
// A cluster's shape is its members' positions relative to its centre of mass; placement moves the
// shape as one rigid body, so the members never change their relative positions.
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "btr/model/grain.h"

namespace btr {

struct ClusterShape {
  std::vector<Vec3> offsets;  // member centres relative to the centre of mass (2D: y == 0)
  std::vector<double> radii;
  std::vector<int> species;   // one per member

  std::size_t size() const { return offsets.size(); }
  void add(const Vec3& x, double r, int s = 1) { offsets.push_back(x); radii.push_back(r); species.push_back(s); }
  // Moves the offsets so that the centre of mass (member masses ~ r^3 in 3D, r^2 in 2D) is the origin.
  void centre(int dimension);
  // Largest distance of a member's surface from the centre of mass.
  double extent() const;
};

// One cluster to place: where its centre of mass is dropped (x, y; y is ignored in 2D) and its
// orientation (in 2D a rotation about the y axis).
struct ClusterDrop {
  double x = 0.0, y = 0.0;
  ClusterShape shape;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

// A random compact cluster of n grains: each new grain touches a randomly chosen member and, of a few
// random candidate positions free of overlap, takes the one nearest the centre of mass so far.
// Radii come from `radius(rng)`. Deterministic for a given rng state.
ClusterShape random_compact_cluster(int dimension, int n, std::mt19937_64& rng,
                                    const std::function<double(std::mt19937_64&)>& radius, int species = 1);

// A uniformly random orientation (3D) or a rotation about y by a uniform angle (2D).
Eigen::Quaterniond random_orientation(int dimension, std::mt19937_64& rng);

// The clusters of a packing: the grains' indices per cluster number; free grains (cluster 0) are
// each their own one-grain body. Bodies are ordered by their first member's index.
std::vector<std::vector<std::size_t>> rigid_bodies(const Grains& grains);

}  // namespace btr
