#pragma once
// The structural measures of a packing (docs/design.md section 5), the one place each is defined: the bulk
// window, packing fraction, coordination and its histogram, g(r), the free-surface profile and the heap
// angle, segregation indices, heights, and the rotating drum's per-step measures. `btr deposit`, `btr
// relax`, `btr measure` (which the Python workflows call) and `btr drum` all take their numbers from
// here; measure_packing() gathers them.
#include <cstdint>
#include <string>
#include <vector>

#include "btr/measures/stratification.h"
#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

// An axis-aligned box; in 2D only x and z are used (disks lie in the x-z plane).
struct Box {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
};

struct MetricsOptions {
  double margin_diameters = 3.0;  // the bulk window keeps this many largest diameters from floor, walls, surface
  double contact_tol = 1e-7;      // a contact: gap < contact_tol * smaller radius (overlaps count too)
  double rdf_max_d = 3.0;         // g(r) up to this many mean diameters
  double rdf_bin_d = 0.02;        // g(r) bins, in mean diameters
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

// The free surface seen from the side: the highest grain top per bin of a lateral coordinate (bins one
// largest diameter wide); each point is that grain's own coordinate and top. Empty bins are left out.
struct ProfilePoint {
  double distance = 0.0, top = 0.0;
};

// The least-squares line of one fitted flank: top = intercept - tan(angle) * distance, fitted over the
// profile bins at distances [start, end] (the same fit that gives the angle).
struct FlankLine {
  bool valid = false;
  double angle_deg = 0.0, intercept = 0.0, start = 0.0, end = 0.0;
};

struct HeapMeasures {
  static constexpr double kLowFraction = 0.2, kHighFraction = 0.8;  // the fitted flank, in heap heights
  bool valid = false;
  std::string note;
  double height = 0.0;           // highest grain top above the floor (the apex)
  bool by_sides = false;         // 2D and Hele-Shaw: each side of the axis fitted on its own
  double angle_deg = 0.0;        // radial profile, or the mean of both sides
  double angle_left_deg = 0.0;   // by_sides only
  double angle_right_deg = 0.0;  // by_sides only
  bool left_valid = false, right_valid = false;  // by_sides: which flanks had a fit (valid: either)
  int profile_points = 0;        // profile points in the fitted flanks
  std::int64_t grains_beyond_flank = 0;  // grains beyond the lower end of the fitted flank (foot, strays)
  std::vector<ProfilePoint> profile;    // against the distance from the axis, or x - source x (by_sides)
  // The fitted lines against |x - source x| on each side (by_sides), or the distance from the axis (radial).
  FlankLine line_left, line_right, line_radial;
};

struct RadialDistribution {
  bool valid = false;
  std::vector<double> r_over_d, g;  // bin centres in mean diameters, g(r)
};

// S = 2 (c_L - c_S) / (c_L + c_S) of a coordinate c (the height of the centre, or its distance from a
// drum axis) averaged over the large and the small grains: > 0 when the large grains have the larger c.
// Mixtures split by species (the largest and the smallest by mean radius); one polydisperse species
// splits at the median radius; invalid for one size (radii within 5 %).
struct SegregationIndex {
  bool valid = false;
  std::string basis;  // which grains were "large" and "small", or why there is no index
  double index = 0.0, mean_large = 0.0, mean_small = 0.0;
};

// Contacts per grain with other grains (walls and floor are not counted). Periodic containers wrap.
std::vector<int> coordination_numbers(const Grains& grains, int dimension, const Container& container,
                                      double contact_tol = 1e-7);

// Whether a centre lies in the bulk window (slab: only its height counts).
bool in_bulk_window(const BulkMeasures& bulk, const Vec3& x, int dimension);

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

// Highest grain top per bin of `distance` (one largest diameter wide) for the given per-grain distances.
std::vector<ProfilePoint> surface_profile(const Grains& grains, const std::vector<double>& distance);

// For a heap poured from a point source at (source_x, source_y), on the free-surface profile against the
// distance from the axis (3D) or on each side of it (2D): the pile is the run of profile bins from the
// apex outwards up to the first empty bin; the flank is the part of that run from where the profile
// first falls to 80 % of the apex height to where it first falls below 20 %. The angle is the least-
// squares line through the flank. Grains beyond the flank's foot (strays that rolled away, a flat tail)
// never enter the fit.
// by_sides: fit each side of the axis on |x - source_x| (2D, and 3D Hele-Shaw cells, whose heap is a 2D
// pile between the plates); the angle is the mean of the sides that have a flank (a heap against an
// end wall has one). Otherwise on the distance from the axis.
HeapMeasures heap_measures(const Grains& grains, int dimension, double source_x, double source_y,
                           bool by_sides);
inline HeapMeasures heap_measures(const Grains& grains, int dimension, double source_x, double source_y) {
  return heap_measures(grains, dimension, source_x, source_y, dimension == 2);
}

// g(r): the grains centred in the bulk window as centres, every grain as a neighbour (periodic sides
// wrap), normalised by the window's number density (grains centred in it / its volume); r in mean
// diameters. Shells reaching past the packing's edges are not corrected: keep rdf_max_d <= the margin.
RadialDistribution radial_distribution(const Grains& grains, int dimension, const Container& container,
                                       const BulkMeasures& bulk, const MetricsOptions& options = {});

// Vertical size segregation: c = height of the centre.
SegregationIndex vertical_segregation(const Grains& grains);
// Radial size segregation about an axis through `point` along `direction` (a drum): c = distance of the
// centre from the axis (in 2D pass direction (0, 1, 0): the distance from the point in the x-z plane).
SegregationIndex radial_segregation(const Grains& grains, const Vec3& point, const Vec3& direction);

// Per grain: distance of the centre from the axis through `point` along `direction` (2D drums: direction
// (0, 1, 0), the distance in the x-z plane).
std::vector<double> axis_distances(const Grains& grains, const Vec3& point, const Vec3& direction);

// The rotating drum's per-step measures (container.kind = drum, axis along y at z = radius).
struct DrumMeasures {
  double split_radius = 0.0;       // grains with r <= split are "small" (the upper median radius)
  double axis_small = 0.0, axis_large = 0.0;  // mean distance from the axis [m] (x-z plane)
  double core_small = 0.0, core_large = 0.0;  // mean distance from the centre of mass [m]
  double segregation_index = 0.0;  // (axis_large - axis_small) / radius: > 0 when small grains are inner
  double com_x = 0.0, com_z = 0.0;  // centre of mass (volume-weighted) [m]
  bool surface_valid = false;
  double surface_angle_deg = 0.0;   // slope of the free surface (rising towards +x is positive)
};

// Free surface: columns one largest diameter wide over |x| <= 0.6 radius, highest grain top in each;
// the angle is that of the least-squares line through them (needs 3 columns holding grains).
DrumMeasures drum_measures(const Grains& grains, int dimension, const Container& container);

// Per grain: how far its centre lies below the free surface over it (the highest grain top among the
// grains centred in its column, columns one largest diameter wide), in m.
std::vector<double> surface_depth(const Grains& grains, int dimension);

// Packing fraction against height of a periodic bed (bulk.slab): slabs `thickness` thick from the floor up to the
// lowest column top (the bulk window's top plus `margin` metres), each grain's exact part in each slab over the
// period's area. What a bulk mean hides: a bed denser at the floor than under its surface. Empty (thickness 0)
// for other containers or without a window.
struct HeightProfile {
  double thickness = 0.0;
  std::vector<double> z_mid, packing_fraction;
};
HeightProfile height_profile(const Grains& grains, int dimension, const BulkMeasures& bulk, double margin,
                             double thickness);

// Everything above for one packing, with the options that define it.
struct PackingMeasures {
  MetricsOptions options;
  std::int64_t n_grains = 0;
  double mean_diameter = 0.0, largest_diameter = 0.0;
  double max_top = 0.0, mean_centre_height = 0.0;
  std::vector<int> coordination;  // per grain
  double mean_coordination_all = 0.0;
  BulkMeasures bulk;
  RadialDistribution rdf;
  bool heap_source = false;  // a point source: heap is measured
  double source_x = 0.0, source_y = 0.0;
  HeapMeasures heap;
  std::vector<ProfilePoint> profile_x;  // free surface against x (every packing)
  SegregationIndex segregation;         // vertical
  HeightProfile height_profile;         // periodic beds: slabs one largest diameter thick
  Stratification stratification;        // heaps (heap_source) of two or more species (btr/measures/stratification.h)
};

// heap_source: measure the heap about (source_x, source_y).
PackingMeasures measure_packing(const Grains& grains, int dimension, const Container& container,
                                const MetricsOptions& options, bool heap_source, double source_x = 0.0,
                                double source_y = 0.0);

// Mean height of the free surface: the container's footprint (cylinder: its inscribed square; open
// floor: the grains' extent) cut into columns `width` wide, each with the highest grain top among the
// grains centred in it; the mean over the columns that hold a grain. 0 without grains.
double mean_surface_height(const Grains& grains, int dimension, const Container& container, double width);

// The bed measured by its height, as seed 000 measures cohesive powders (beds too loose and thin for a
// bulk window): the mean surface height <h> above (columns `width` wide) and the packing fraction
// solid volume / (footprint * <h>), with the footprint the container's floor area (2D: its width;
// Hele-Shaw: length x gap; cylinder: pi R^2). Open floors have no footprint: packing_fraction is NaN.
struct BedHeightMeasures {
  double mean_height = 0.0;
  double packing_fraction = 0.0;
};
BedHeightMeasures bed_height_measures(const Grains& grains, int dimension, const Container& container, double width);

}  // namespace btr
