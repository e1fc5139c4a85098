#pragma once
// Self-check of a packing of rigid clusters, written apart from the placement code: contacts are
// found by brute force over sorted grains, and support is decided by enumerating the contact subsets
// (Caratheodory: a wrench in the cone of k wrenches is in the cone of at most 6 independent ones),
// (more than 14 contacts: an accelerated projected gradient), not by the placement's non-negative
// least squares.
#include <cstdint>
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

struct ClusterCheckReport {
  std::int64_t bodies = 0;
  std::int64_t overlaps = 0;       // pairs of grains of different bodies (or grain and wall) overlapping
  double max_overlap = 0.0;        // relative to the smaller radius
  std::int64_t unsupported = 0;    // bodies whose weight no non-negative normal forces balance
  std::vector<std::int64_t> examples;  // ids of a grain of some offending bodies
  bool ok() const { return overlaps == 0 && unsupported == 0; }
};

// Box, Hele-Shaw, periodic, cylinder and open containers. Tolerances relative to the smaller radius.
ClusterCheckReport check_clusters(const Grains& grains, int dimension, const Container& container,
                                  double overlap_tol = 1e-9, double contact_tol = 1e-7);

}  // namespace btr
