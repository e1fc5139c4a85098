#pragma once
// Summary measures of a packing (DESIGN.md section 5): packing fraction and mean coordination number
// in a bulk window away from the floor, the walls and the free surface, and for heaps the height and
// the angle of repose.
#include <cstdint>
#include <string>
#include <vector>

#include "btr/container.h"
#include "btr/grain.h"

namespace btr {

// An axis-aligned box; in 2D only x and z are used (disks lie in the x-z plane).
struct Box {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
};

struct MetricsOptions {
  double margin_diameters = 3.0;  // the bulk window keeps this many largest diameters from floor, walls, surface
  double contact_tol = 1e-7;      // a contact: gap < contact_tol * smaller radius (overlaps count too)
};

struct BulkMeasures {
  bool valid = false;
  std::string note;           // how the window was chosen, or why there is none
  bool slab = false;          // periodic beds: the window is a z-slab over the whole footprint
  Box window;                 // slab: x (and y) span the period
  double window_volume = 0.0;  // m^3 (3D) or m^2 (2D)
  double packing_fraction = 0.0;
  double mean_coordination = 0.0;           // over grains whose centre is in the window
  std::int64_t grains_in_window = 0;
  std::vector<std::int64_t> coordination_histogram;  // [k] = grains in the window with k contacts
};

struct HeapMeasures {
  bool valid = false;
  std::string note;
  double height = 0.0;           // highest grain top above the floor
  double angle_deg = 0.0;        // 3D: from the radial profile; 2D: mean of both sides
  double angle_left_deg = 0.0;   // 2D only
  double angle_right_deg = 0.0;  // 2D only
  int profile_points = 0;        // profile points inside the fitted 20%..80% height band
};

// Contacts per grain with other grains (walls and floor are not counted). Periodic containers wrap.
std::vector<int> coordination_numbers(const Grains& grains, int dimension, const Container& container,
                                      double contact_tol = 1e-7);

// Volume (3D) or area (2D) of one grain inside a box; exact, except spheres cut by a vertical box side
// (Gauss-Legendre quadrature over exact disk-rectangle areas, relative error below 1e-9).
double grain_volume_in_box(const Grain& g, int dimension, const Box& box);
// Volume (3D) or area (2D) of one grain between the planes z = z_lo and z = z_hi; exact.
double grain_volume_in_slab(const Grain& g, int dimension, double z_lo, double z_hi);

// Solid fraction of a box (no periodic images).
double packing_fraction_in_box(const Grains& grains, int dimension, const Box& box);

// The bulk window keeps `margin` = margin_diameters largest diameters from the floor, the walls and the
// free surface. The free surface is sampled in columns one largest diameter wide (highest grain top of
// the grains centred in each column). Periodic beds: a z-slab over the whole footprint, up to the lowest
// column top less the margin; volumes of cut grains are exact caps / segments. Other containers: the
// lateral bounds are the walls less the margin (cylinder: the inscribed square; Hele-Shaw: the whole gap
// in y; open floor: the extent of the grains less the margin), and the window is the column-aligned box
// of largest volume under (column top - margin), so heaps get a box under their slopes.
// Drums get no window (invalid, with a note). `coordination` (optional): coordination_numbers() already
// computed with options.contact_tol.
BulkMeasures bulk_measures(const Grains& grains, int dimension, const Container& container,
                           const MetricsOptions& options = {}, const std::vector<int>* coordination = nullptr);

// Mean height of the free surface: the container's footprint (cylinder: its inscribed square; open
// floor: the grains' extent) cut into columns `width` wide, each with the highest grain top among the
// grains centred in it; the mean over the columns that hold a grain. 0 without grains.
double mean_surface_height(const Grains& grains, int dimension, const Container& container, double width);

// For a heap poured from a point source at (source_x, source_y): free-surface profile = highest grain
// top per radial bin (3D) or per x bin on each side (2D), bins one largest diameter wide; linear fit
// of the profile points whose height lies between 20% and 80% of the heap height.
HeapMeasures heap_measures(const Grains& grains, int dimension, double source_x, double source_y);

}  // namespace btr
