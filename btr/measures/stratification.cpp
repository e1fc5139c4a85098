#include "btr/measures/stratification.h"

#include "btr/measures/metrics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

namespace btr {
namespace {

constexpr double kPi = 3.14159265358979323846;

double solid(double r, int dimension) { return dimension == 3 ? 4.0 / 3.0 * kPi * r * r * r : kPi * r * r; }

// One fitted flank in the coordinates of the definitions: per grain of the heap u, s, n.
struct Side {
  FlankLine line;
  std::string name;
  double cos_t = 1.0, sin_t = 0.0, tan_t = 0.0;
  double s_lo = 0.0, s_hi = 0.0, foot_u = 0.0;  // flank extent along the line; where the line meets z = 0
};

// A grain of the heap as the measure sees it: the side it is on, and its coordinates there.
struct Member {
  int side;
  double u;        // distance from the axis over the side's foot distance L (top: < 1/3, toe: > 2/3)
  double n;        // depth of the centre below the layers' top (the flank line less the skin)
  bool in_layers;  // centre's s within the flank's fitted extent
};

// The quantities computed for the heap and for each random mixture.
struct Sample {
  std::vector<double> phi, volume;
  double sigma = 0.0, peak = -2.0;  // peak: A at the first maximum after A < 0 (-2: none)
  int peak_lag = 0;
  std::vector<double> autocorrelation;
  bool top_toe = false;
  double top = 0.0, toe = 0.0;
};

// Layers, their detrended fluctuation and autocorrelation, and the top-toe fractions for the grains with
// the given radii and species (radius[k], small[k] for members[k]).
Sample evaluate(const std::vector<Member>& members, const std::vector<double>& radius, const std::vector<char>& small,
                int dimension, double h, int layers) {
  Sample out;
  std::vector<double> vs(layers, 0.0), vt(layers, 0.0);
  double top_s = 0, top_t = 0, toe_s = 0, toe_t = 0;
  for (std::size_t k = 0; k < members.size(); ++k) {
    const Member& m = members[k];
    const double r = radius[k];
    if (m.in_layers) {
      const int first = std::max(0, static_cast<int>(std::floor((m.n - r) / h)));
      const int last = std::min(layers - 1, static_cast<int>(std::floor((m.n + r) / h)));
      Grain g;
      g.x = Vec3(0.0, 0.0, m.n);
      g.r = r;
      for (int j = first; j <= last; ++j) {
        const double v = grain_volume_in_slab(g, dimension, j * h, (j + 1) * h);
        vt[j] += v;
        if (small[k]) vs[j] += v;
      }
    }
    // top / toe: u is in units of the side's foot distance L
    const double v = solid(r, dimension);
    if (m.u < 1.0 / 3.0) top_t += v, top_s += small[k] ? v : 0.0;
    else if (m.u > 2.0 / 3.0) toe_t += v, toe_s += small[k] ? v : 0.0;
  }
  out.top_toe = top_t > 0.0 && toe_t > 0.0;
  if (out.top_toe) out.top = top_s / top_t, out.toe = toe_s / toe_t;
  out.volume = vt;
  out.phi.resize(layers);
  double all_s = std::accumulate(vs.begin(), vs.end(), 0.0), all_t = std::accumulate(vt.begin(), vt.end(), 0.0);
  for (int j = 0; j < layers; ++j) out.phi[j] = vt[j] > 0.0 ? vs[j] / vt[j] : (all_t > 0 ? all_s / all_t : 0.0);
  // detrend: least-squares line in the layer index
  const double n = layers;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (int j = 0; j < layers; ++j) sx += j, sy += out.phi[j], sxx += double(j) * j, sxy += j * out.phi[j];
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), icpt = (sy - slope * sx) / n;
  std::vector<double> res(layers);
  double ss = 0.0;
  for (int j = 0; j < layers; ++j) res[j] = out.phi[j] - (icpt + slope * j), ss += res[j] * res[j];
  out.sigma = std::sqrt(ss / n);
  const int max_lag = layers / 2;
  out.autocorrelation.assign(max_lag + 1, 0.0);
  if (ss <= 0.0) return out;
  for (int lag = 0; lag <= max_lag; ++lag) {
    double c = 0.0;
    for (int j = 0; j + lag < layers; ++j) c += res[j] * res[j + lag];
    out.autocorrelation[lag] = (c / double(layers - lag)) / (ss / n);
  }
  const std::vector<double>& a = out.autocorrelation;
  int neg = -1;
  for (int lag = 1; lag <= max_lag; ++lag)
    if (a[lag] < 0.0) {
      neg = lag;
      break;
    }
  if (neg < 0) return out;
  for (int lag = neg + 1; lag < max_lag; ++lag)
    if (a[lag] >= a[lag - 1] && a[lag] >= a[lag + 1] && a[lag] > 0.0) {
      out.peak = a[lag], out.peak_lag = lag;
      break;
    }
  return out;
}

double quantile_of(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * double(v.size()))) - 1);
  return v[k];
}

}  // namespace

Stratification stratification_measures(const Grains& grains, int dimension, const HeapMeasures& heap,
                                       double source_x, double source_y, const StratificationOptions& options) {
  Stratification st;
  st.options = options;
  if (grains.empty()) {
    st.note = "no grains";
    return st;
  }
  // species: the smallest and the largest by mean radius
  std::map<int, std::pair<double, std::int64_t>> by_species;
  double sum_d = 0.0;
  for (const Grain& g : grains) {
    auto& e = by_species[g.species];
    e.first += g.r, e.second += 1;
    sum_d += 2.0 * g.r;
  }
  st.mean_diameter = sum_d / double(grains.size());
  if (by_species.size() < 2) {
    st.note = "one species: no stratification";
    return st;
  }
  auto mean_r = [&](int sp) { return by_species[sp].first / double(by_species[sp].second); };
  st.small_species = st.large_species = by_species.begin()->first;
  for (const auto& [sp, e] : by_species) {
    if (mean_r(sp) < mean_r(st.small_species)) st.small_species = sp;
    if (mean_r(sp) > mean_r(st.large_species)) st.large_species = sp;
  }
  if (mean_r(st.large_species) < 1.05 * mean_r(st.small_species)) {
    st.note = "species of the same size (mean radii within 5 %): no small and large species";
    return st;
  }
  if (!heap.valid) {
    st.note = "no fitted flank: " + heap.note;
    return st;
  }
  // the fitted sides
  std::vector<Side> sides;
  auto add_side = [&](const FlankLine& line, const char* name) {
    if (!line.valid || !(line.angle_deg > 0.0) || !(line.intercept > 0.0)) return;
    Side s;
    s.line = line, s.name = name;
    const double t = line.angle_deg * kPi / 180.0;
    s.cos_t = std::cos(t), s.sin_t = std::sin(t), s.tan_t = std::tan(t);
    s.s_lo = line.start / s.cos_t, s.s_hi = line.end / s.cos_t;
    s.foot_u = line.intercept / s.tan_t;
    sides.push_back(s);
    st.flanks.push_back(name);
  };
  if (heap.by_sides) add_side(heap.line_left, "left"), add_side(heap.line_right, "right");
  else add_side(heap.line_radial, "radial");
  if (sides.empty()) {
    st.note = "no flank line falling away from the axis";
    return st;
  }
  // the angle per species: the species' own skyline (its highest grain top per bin of u, bins one largest
  // diameter of the heap wide) fitted over the heap's fitted extent of each side; sides averaged
  const double r_max = max_radius(grains);
  for (const auto& [sp, e] : by_species) {
    SpeciesAngle angle{sp, 2.0 * e.first / double(e.second), false, 0.0};
    int fitted = 0;
    double sum = 0.0;
    for (const Side& sd : sides) {
      std::vector<std::pair<double, double>> best;  // per bin: (u, top), top < 0 = empty
      for (const Grain& g : grains) {
        if (g.species != sp) continue;
        double u = 0.0;
        if (heap.by_sides) {
          const double c = g.x.x() - source_x;
          if ((c < 0) != (sd.name == "left")) continue;
          u = std::abs(c);
        } else {
          u = std::hypot(g.x.x() - source_x, dimension == 3 ? g.x.y() - source_y : 0.0);
        }
        if (u < sd.line.start || u > sd.line.end) continue;
        const std::size_t bin = static_cast<std::size_t>((u - sd.line.start) / (2.0 * r_max));
        if (bin >= best.size()) best.resize(bin + 1, {0.0, -1.0});
        if (g.x.z() + g.r > best[bin].second) best[bin] = {u, g.x.z() + g.r};
      }
      double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
      for (const auto& [u, top] : best)
        if (top >= 0.0) n += 1, sx += u, sy += top, sxx += u * u, sxy += u * top;
      if (n < 3 || n * sxx - sx * sx <= 0.0) continue;
      sum += std::atan(-(n * sxy - sx * sy) / (n * sxx - sx * sx)) * 180.0 / kPi;
      ++fitted;
    }
    if (fitted > 0) angle.valid = true, angle.angle_deg = sum / fitted;
    st.species_angles.push_back(angle);
  }
  // the heap's grains on the fitted sides; u is kept in units of the side's foot distance for top / toe
  const double skin = options.skin_d * 2.0 * r_max;
  std::vector<Member> members;
  std::vector<double> radius;
  std::vector<char> small;
  double deepest = 0.0;
  int left = -1, right = -1;  // index in `sides`, -1: that side has no fitted line
  for (std::size_t k = 0; k < sides.size(); ++k) (sides[k].name == "left" ? left : right) = static_cast<int>(k);
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Grain& g = grains[i];
    int side = 0;
    double u = 0.0;
    if (heap.by_sides) {
      const double c = g.x.x() - source_x;
      side = c < 0 ? left : right;
      if (side < 0) continue;
      u = std::abs(c);
    } else {
      u = std::hypot(g.x.x() - source_x, dimension == 3 ? g.x.y() - source_y : 0.0);
    }
    const Side& sd = sides[side];
    const double a = sd.line.intercept, z = g.x.z();
    const double s = u * sd.cos_t - (z - a) * sd.sin_t;
    const double n = sd.cos_t * (a - u * sd.tan_t - z) - skin;  // depth below the skin
    const bool in_layers = s >= sd.s_lo && s <= sd.s_hi && n + g.r > 0.0;
    members.push_back({side, u / sd.foot_u, n, in_layers});
    radius.push_back(g.r);
    small.push_back(g.species == st.small_species);
    if (in_layers) deepest = std::max(deepest, n + g.r);
  }
  const double h = options.layer_d * st.mean_diameter;
  st.layer_thickness = h;
  int layers = static_cast<int>(std::ceil(deepest / h));
  if (layers < 1) {
    st.note = "no grain under the flank";
    return st;
  }
  // keep the layers down to the last one holding min_layer_volume of the fullest one's solid
  Sample heap_sample = evaluate(members, radius, small, dimension, h, layers);
  const double fullest = *std::max_element(heap_sample.volume.begin(), heap_sample.volume.end());
  int keep = 0;
  for (int j = 0; j < layers; ++j)
    if (heap_sample.volume[j] >= options.min_layer_volume * fullest) keep = j + 1;
  if (keep < 8) {
    st.note = "fewer than 8 layers under the flank (" + std::to_string(keep) + ")";
    return st;
  }
  layers = keep;
  heap_sample = evaluate(members, radius, small, dimension, h, layers);
  // the null: the same sites holding the same grains in random order
  std::mt19937_64 rng(options.seed);
  std::vector<std::size_t> order(members.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<double> r_perm(members.size());
  std::vector<char> s_perm(members.size());
  std::vector<double> sigmas, peaks, top_toe;
  for (int p = 0; p < options.permutations; ++p) {
    std::shuffle(order.begin(), order.end(), rng);
    for (std::size_t k = 0; k < members.size(); ++k) r_perm[k] = radius[order[k]], s_perm[k] = small[order[k]];
    const Sample q = evaluate(members, r_perm, s_perm, dimension, h, layers);
    sigmas.push_back(q.sigma);
    peaks.push_back(q.peak);
    if (q.top_toe) top_toe.push_back(q.top - q.toe);
  }
  // the heap's numbers
  double vs = 0.0, vt = 0.0;
  for (int j = 0; j < layers; ++j) vt += heap_sample.volume[j], vs += heap_sample.phi[j] * heap_sample.volume[j];
  st.small_fraction = vt > 0.0 ? vs / vt : 0.0;
  for (int j = 0; j < layers; ++j) st.layer_depth_d.push_back((skin + (j + 0.5) * h) / st.mean_diameter);
  st.layer_small_fraction = heap_sample.phi;
  st.layer_solid = heap_sample.volume;
  st.autocorrelation = heap_sample.autocorrelation;
  st.sigma = heap_sample.sigma;
  double ms = 0.0;
  for (double s : sigmas) ms += s * s;
  st.sigma_random = sigmas.empty() ? 0.0 : std::sqrt(ms / double(sigmas.size()));
  st.sigma_threshold = sigmas.empty() ? 0.0 : quantile_of(sigmas, options.quantile);
  st.fluctuation_ratio = st.sigma_random > 0.0 ? st.sigma / st.sigma_random : 0.0;
  const double binomial = st.small_fraction * (1.0 - st.small_fraction);
  const bool fluctuates = !sigmas.empty() && st.sigma > st.sigma_threshold;
  st.contrast = fluctuates && binomial > 0.0
                    ? std::sqrt(std::max(0.0, st.sigma * st.sigma - st.sigma_random * st.sigma_random) / binomial)
                    : 0.0;
  st.has_peak = heap_sample.peak > -2.0;
  st.peak_threshold = peaks.empty() ? 0.0 : quantile_of(peaks, options.quantile);
  if (st.has_peak) {
    st.peak_lag_d = heap_sample.peak_lag * options.layer_d;
    st.peak_autocorrelation = heap_sample.peak;
    st.has_wavelength = fluctuates && heap_sample.peak > st.peak_threshold;
    if (st.has_wavelength) st.wavelength_d = st.peak_lag_d;
  }
  st.top_toe_valid = heap_sample.top_toe;
  if (st.top_toe_valid) {
    st.small_fraction_top = heap_sample.top, st.small_fraction_toe = heap_sample.toe;
    st.top_toe_index = heap_sample.top - heap_sample.toe;
    double m = 0.0, m2 = 0.0;
    for (double x : top_toe) m += x, m2 += x * x;
    const double k = double(top_toe.size());
    st.top_toe_noise = k > 1 ? std::sqrt(std::max(0.0, (m2 - m * m / k) / (k - 1))) : 0.0;
  }
  st.valid = true;
  if (sides.size() > 1) st.note = "both flanks pooled";
  return st;
}

}  // namespace btr
