#pragma once
// Self-check of a packing, written independently of the placement code: overlaps, grains not
// supported (gravity not balanced by non-negative contact forces), grains outside the container.
#include <cstdint>
#include <functional>
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

struct CheckReport {
  std::int64_t overlaps = 0;        // pairs (and grain-wall) overlapping by more than the tolerance
  double max_overlap = 0.0;         // largest overlap / smaller radius
  std::int64_t unsupported = 0;     // grains whose weight the contacts cannot carry
  std::int64_t outside = 0;         // grains not inside the container
  std::vector<std::int64_t> examples;  // ids of a few offending grains, for the message
  bool ok() const { return overlaps == 0 && unsupported == 0 && outside == 0; }
};

// Minimum-image displacement in the container's periodic axes (wraps_x, wraps_y). A periodic axis
// without a positive period (an invalid container) is treated as unbounded. Shared with the cluster
// check (btr/verify/cluster_check.cpp) and the clusters' unwrapping (btr/verify/cluster_unwrap.cpp).
struct MinimumImage {
  MinimumImage(const Container& container, int dimension);
  Vec3 operator()(Vec3 d) const;
  bool px, py;  // x, y wrap
  double lx, ly;  // their periods
};

// Calls f(i, j, d) once for every pair i != j of the points x within `reach` of each other, d = image(x[i] - x[j]):
// a sweep along x over the points sorted by x (wrapped into the cell); pairs across the x boundary lie near
// the two ends of that order. Shared by the cluster check and the clusters' unwrapping (btr/verify/cluster_unwrap.h).
void for_each_pair_within(const std::vector<Vec3>& x, double reach, const MinimumImage& image,
                          const std::function<void(std::size_t, std::size_t, const Vec3&)>& f);

// overlap_tol and contact_tol are relative to the smaller radius of the pair.
CheckReport check_packing(const Grains& grains, int dimension, const Container& container,
                          double overlap_tol = 1e-9, double contact_tol = 1e-7);

}  // namespace btr
