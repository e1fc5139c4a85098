#pragma once
// Stratification of a two-species heap (seed 000 section 4, Figs. 7-8): stripes of the small and the
// large species in layers parallel to the free surface, and the segregation between the heap's top and
// its toe. Definitions (docs/stratification/definitions.md has them with the reasons):
// - The flank: heap_measures()'s fitted line(s) (each fitted side of a 2D or Hele-Shaw heap, pooled; or
//   the radial one), with coordinates u (distance from the source axis on that side), s along the line
//   downhill and n the depth below it, normal to it.
// - Layers: slabs n0 + k h <= n < n0 + (k + 1) h, h = layer_d mean diameters, n0 = skin_d largest diameters
//   (the rough surface, where the large grains stand out above the small, is left out), over the grains
//   whose centre's s lies
//   in the fitted extent of the flank; each grain's volume is cut exactly between the slabs. phi_k =
//   small-species volume / solid volume of layer k. Layers are kept from the surface down to the last one
//   holding at least min_layer_volume of the fullest layer's solid.
// - The sequence phi_k, with its least-squares line in k removed (r_k), gives sigma = rms(r_k) and the
//   autocorrelation A(j) = mean_k r_k r_{k+j} / sigma^2 for j <= K/2.
// - Null: the same sites holding the same grains in random order (the (radius, species) pairs permuted
//   among the heap's grains, `permutations` times, seeded): what a random mixture of these grains gives.
// - Contrast = sqrt(sigma^2 - sigma_random^2) / sqrt(phi (1 - phi)) if sigma exceeds the null's
//   `quantile`, else 0 (sigma_random^2 the null's mean square; phi the layers' overall small fraction;
//   pure alternating layers give about 1).
// - Wavelength: j* h in mean diameters, j* the first local maximum of A after its first negative value,
//   if A(j*) and sigma both exceed the null's `quantile` (the null's peak taken the same way), else none.
// - Top-toe segregation: phi over the grains with u < L/3 minus phi over those with u > 2 L/3, L = where
//   the flank line meets the floor (> 0: the small grains stay at the top); its noise is the null's std.
// - Angle per species: the species' own skyline (its highest grain top per bin of u one largest diameter
//   wide) fitted by least squares over the fitted extent of the heap's flank; sides averaged.
#include <cstdint>
#include <string>
#include <vector>

#include "btr/model/grain.h"

namespace btr {

struct HeapMeasures;  // btr/measures/metrics.h, which includes this header

struct StratificationOptions {
  double layer_d = 0.5;            // layer thickness [mean diameters]
  int permutations = 200;          // random mixtures of the null
  double quantile = 0.99;          // significance: above this quantile of the null
  double min_layer_volume = 0.3;   // deepest layer kept: solid >= this fraction of the fullest layer's
  double skin_d = 1.0;             // layers start this many largest diameters below the flank line
  std::uint64_t seed = 24;         // the null's random order (fixed: same heap -> same numbers)
};

struct SpeciesAngle {
  int species = 0;
  double mean_diameter = 0.0;
  bool valid = false;
  double angle_deg = 0.0;
};

struct Stratification {
  bool valid = false;
  std::string note;  // why there is no measure, or what was pooled
  StratificationOptions options;
  int small_species = 0, large_species = 0;
  double mean_diameter = 0.0;        // number mean over all grains [m]
  std::vector<std::string> flanks;   // "left", "right" or "radial": the fitted lines pooled
  double layer_thickness = 0.0;      // [m]
  std::vector<double> layer_depth_d;  // layer centres below the flank line [mean diameters]
  std::vector<double> layer_small_fraction, layer_solid;  // phi_k; solid volume (3D) / area (2D)
  double small_fraction = 0.0;        // over all kept layers
  std::vector<double> autocorrelation;  // A(j), j = 0..K/2, lag j h
  double sigma = 0.0, sigma_random = 0.0, sigma_threshold = 0.0, fluctuation_ratio = 0.0, contrast = 0.0;
  bool has_peak = false;  // A has a local maximum after its first negative value
  double peak_lag_d = 0.0, peak_autocorrelation = 0.0, peak_threshold = 0.0;
  bool has_wavelength = false;
  double wavelength_d = 0.0;  // [mean diameters]
  bool top_toe_valid = false;
  double small_fraction_top = 0.0, small_fraction_toe = 0.0, top_toe_index = 0.0, top_toe_noise = 0.0;
  std::vector<SpeciesAngle> species_angles;
};

// The stratification of a heap poured at (source_x, source_y), measured on heap's fitted flank(s).
Stratification stratification_measures(const Grains& grains, int dimension, const HeapMeasures& heap,
                                       double source_x, double source_y, const StratificationOptions& options = {});

}  // namespace btr
