#pragma once
// How precisely one packing gives a periodic bed's bulk packing fraction: the bulk window split into equal
// blocks, whose packing fractions scatter about the window's; their standard deviation / sqrt(blocks) estimates
// the standard error of the window's value, as if the blocks were independent samples (blocks a few grain
// diameters across nearly are; their correlation makes the estimate somewhat low).
#include <string>
#include <vector>

#include "btr/measures/metrics.h"

namespace btr {

struct BlockError {
  bool valid = false;
  std::string note;               // the blocks, or why there are none
  std::vector<double> block_phi;  // packing fraction of each block (equal volumes: their mean is the window's)
  double standard_error = 0.0;
};

// Periodic beds with a slab window (bulk_measures of the same grains and container): 2 x 2 columns x 2 layers in
// 3D, 4 columns x 2 layers in 2D; periodic images counted, volumes exact as in grain_volume_in_box.
BlockError bulk_phi_block_error(const Grains& grains, int dimension, const Container& container,
                                const BulkMeasures& bulk);

}  // namespace btr
