#pragma once
// The region a relaxation or a pour on an open floor keeps its grains in: grains whose centre leaves it are
// removed (and counted), so that a grain rolling away on the endless floor does not hold the run open.
#include "btr/model/grain.h"

namespace btr {

struct FloorRegion {
  double lo[2], hi[2];  // x and y bounds [m]
};

// The grains' footprint (their extents) grown by `margin` [m], widened to hold the heap their volume makes at
// `heap_angle_deg` centred under the footprint's middle: a cone of packing fraction kHeapRegionPhi (2D: a
// triangle of kHeapRegionPhi2D). A heap flattens as it is poured or relaxed (a BTR heap at 60 deg relaxes to
// 10-25 deg), so the footprint alone loses the heap's rim.
FloorRegion open_floor_region(const Grains& grains, int dimension, double margin, double heap_angle_deg);

// Looser than any random packing a heap holds, so the heap's base is overestimated, not cut.
constexpr double kHeapRegionPhi = 0.5, kHeapRegionPhi2D = 0.75;

}  // namespace btr
