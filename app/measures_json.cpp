#include "measures_json.h"

#include <cstdio>

namespace btr_app {

using nlohmann::json;

namespace {

json profile_json(const std::vector<btr::ProfilePoint>& p) {
  json coord = json::array(), top = json::array();
  for (const btr::ProfilePoint& q : p) coord.push_back(q.distance), top.push_back(q.top);
  return {{"coord", coord}, {"height", top}};
}

json segregation_json(const btr::SegregationIndex& s) {
  if (!s.valid) return {{"valid", false}, {"note", s.basis}};
  return {{"valid", true}, {"index", s.index}, {"mean_large", s.mean_large}, {"mean_small", s.mean_small},
          {"basis", s.basis}};
}

json stratification_json(const btr::Stratification& s) {
  json angles = json::array();
  for (const btr::SpeciesAngle& a : s.species_angles)
    angles.push_back({{"species", a.species}, {"mean_diameter", a.mean_diameter},
                      {"angle_of_repose_deg", a.valid ? json(a.angle_deg) : json(nullptr)}});
  const btr::StratificationOptions& o = s.options;
  json out = {{"valid", s.valid},
              {"note", s.note},
              {"angle_by_species", angles},
              {"rule", "layers parallel to the fitted flank line(s), layer_d mean diameters thick from skin_d largest diameters below it, over the flank's "
                       "fitted extent; small-species volume fraction per layer, least-squares line in depth removed; "
                       "null: the heap's (radius, species) pairs permuted among its grains; definitions: "
                       "docs/stratification/definitions.md"},
              {"layer_d", o.layer_d},
              {"permutations", o.permutations},
              {"quantile", o.quantile},
              {"min_layer_volume", o.min_layer_volume},
              {"skin_d", o.skin_d}};
  if (!s.valid) return out;
  out.update({{"small_species", s.small_species},
              {"large_species", s.large_species},
              {"mean_diameter", s.mean_diameter},
              {"flanks", s.flanks},
              {"layers", {{"depth_d", s.layer_depth_d}, {"small_fraction", s.layer_small_fraction}, {"solid", s.layer_solid}}},
              {"small_fraction", s.small_fraction},
              {"autocorrelation", s.autocorrelation},
              {"sigma", s.sigma},
              {"sigma_random", s.sigma_random},
              {"sigma_threshold", s.sigma_threshold},
              {"fluctuation_ratio", s.fluctuation_ratio},
              {"contrast", s.contrast},
              {"peak_lag_d", s.has_peak ? json(s.peak_lag_d) : json(nullptr)},
              {"peak_autocorrelation", s.has_peak ? json(s.peak_autocorrelation) : json(nullptr)},
              {"peak_threshold", s.peak_threshold},
              {"wavelength_d", s.has_wavelength ? json(s.wavelength_d) : json(nullptr)}});
  if (s.top_toe_valid)
    out["top_toe"] = {{"small_fraction_top", s.small_fraction_top}, {"small_fraction_toe", s.small_fraction_toe},
                      {"index", s.top_toe_index}, {"noise", s.top_toe_noise}};
  else
    out["top_toe"] = nullptr;
  return out;
}

}  // namespace

btr::PackingMeasures measure_in_scene(const btr::Grains& grains, const btr::Scene& scene,
                                      const btr::MetricsOptions& options) {
  const btr::SourceSpec& s = scene.source;
  if (s.kind == btr::SourceSpec::Kind::Point)
    return btr::measure_packing(grains, scene.dimension, scene.container, options, true, s.x, s.y);
  // A region source's heap is fitted by sides about the region's middle where the heap is a 2D pile (2D, and
  // between a Hele-Shaw cell's plates); a 3D region's heap has no axis to fit about.
  const bool by_sides = scene.dimension == 2 || scene.container.kind == btr::ContainerKind::HeleShaw;
  const bool region_heap = s.kind == btr::SourceSpec::Kind::Region && by_sides;
  return btr::measure_packing(grains, scene.dimension, scene.container, options, region_heap,
                              0.5 * (s.x_min + s.x_max), 0.5 * (s.y_min + s.y_max));
}

json measures_to_json(const btr::PackingMeasures& m) {
  const btr::MetricsOptions& o = m.options;
  const btr::BulkMeasures& b = m.bulk;
  json bulk = {{"valid", b.valid},
               {"note", b.note},
               {"window_margin_diameters", o.margin_diameters},
               {"window_rule", "bulk window: margin x largest diameter from the floor, the side walls and the "
                               "free surface (columns one largest diameter wide)"},
               {"contact_tolerance", o.contact_tol},
               {"contact_rule", "contact: gap < contact_tolerance x smaller radius (overlaps count)"}};
  if (b.valid) {
    bulk.update({{"window", b.slab ? "z-slab" : "box"},
                 {"window_lo", {b.window.lo.x(), b.window.lo.y(), b.window.lo.z()}},
                 {"window_hi", {b.window.hi.x(), b.window.hi.y(), b.window.hi.z()}},
                 {"window_volume", b.window_volume},
                 {"grains_in_window", b.grains_in_window},
                 {"packing_fraction", b.packing_fraction},
                 {"mean_coordination", b.mean_coordination},
                 {"coordination_histogram", b.coordination_histogram}});
  }
  json rdf = nullptr;
  if (m.rdf.valid)
    rdf = {{"r_over_d", m.rdf.r_over_d}, {"g", m.rdf.g}, {"bin_d", o.rdf_bin_d},
           {"centres", "grains centred in the bulk window"}};
  json heap = nullptr;
  if (m.heap_source) {
    const btr::HeapMeasures& h = m.heap;
    heap = {{"valid", h.valid},
            {"axis", {m.source_x, m.source_y}},
            {"profile_of", h.by_sides ? "x - axis x (each side fitted)" : "distance from the axis"},
            {"height", h.height},
            {"fit_band", {btr::HeapMeasures::kLowFraction, btr::HeapMeasures::kHighFraction}},
            {"fit_rule", "least-squares line through the surface profile of the pile from the apex outwards, from "
                         "where it first falls to the upper fraction of the height to where it first falls below "
                         "the lower one (or meets an empty bin)"},
            {"profile_points", h.profile_points},
            {"grains_beyond_flank", h.grains_beyond_flank},
            {"profile", profile_json(h.profile)}};
    json lines = json::object();
    for (const auto& [name, line] : {std::pair<const char*, const btr::FlankLine&>{"left", h.line_left},
                                     {"right", h.line_right}, {"radial", h.line_radial}})
      if (line.valid)
        lines[name] = {{"angle_deg", line.angle_deg}, {"intercept", line.intercept}, {"start", line.start},
                       {"end", line.end}};
    heap["flank_lines"] = lines;
    if (h.valid) {
      heap["angle_of_repose_deg"] = h.angle_deg;
      if (h.by_sides) {
        heap["angle_left_deg"] = h.left_valid ? json(h.angle_left_deg) : json(nullptr);
        heap["angle_right_deg"] = h.right_valid ? json(h.angle_right_deg) : json(nullptr);
      }
      if (!h.note.empty()) heap["note"] = h.note;
    } else {
      heap["note"] = h.note;
    }
  }
  return {{"n_grains", m.n_grains},
          {"mean_diameter", m.mean_diameter},
          {"largest_diameter", m.largest_diameter},
          {"mean_coordination_all_grains", m.mean_coordination_all},
          {"bulk", bulk},
          {"rdf", rdf},
          {"heap", heap},
          {"surface_profile_x", profile_json(m.profile_x)},
          {"segregation", segregation_json(m.segregation)},
          {"height_profile", m.height_profile.thickness > 0.0
                                 ? json{{"slab_thickness", m.height_profile.thickness},
                                        {"z_mid", m.height_profile.z_mid},
                                        {"packing_fraction", m.height_profile.packing_fraction}}
                                 : json(nullptr)},
          {"stratification", m.heap_source ? stratification_json(m.stratification) : json(nullptr)},
          {"height", {{"max_top", m.max_top}, {"mean_centre", m.mean_centre_height}}}};
}

std::string measures_summary(const btr::PackingMeasures& m) {
  char buf[600];
  const btr::BulkMeasures& b = m.bulk;
  if (b.valid)
    std::snprintf(buf, sizeof buf,
                  "  bulk: packing fraction %.4f, mean coordination %.3f (%lld grains; window margin %g largest "
                  "diameters, contact tolerance %g; %s)\n",
                  b.packing_fraction, b.mean_coordination, static_cast<long long>(b.grains_in_window),
                  m.options.margin_diameters, m.options.contact_tol, b.note.c_str());
  else
    std::snprintf(buf, sizeof buf, "  bulk: no measure (%s)\n", b.note.c_str());
  std::string out = buf;
  if (m.heap_source) {
    const btr::HeapMeasures& h = m.heap;
    if (h.valid && h.by_sides)
      std::snprintf(buf, sizeof buf, "  heap: height %.4g m, angle of repose %.2f deg (left %.2f, right %.2f)\n",
                    h.height, h.angle_deg, h.angle_left_deg, h.angle_right_deg);
    else if (h.valid)
      std::snprintf(buf, sizeof buf, "  heap: height %.4g m, angle of repose %.2f deg\n", h.height, h.angle_deg);
    else
      std::snprintf(buf, sizeof buf, "  heap: height %.4g m, no angle of repose (%s)\n", h.height, h.note.c_str());
    out += buf;
    const btr::Stratification& st = m.stratification;
    if (st.valid) {
      char wave[40] = "none", top_toe[40] = "none";
      if (st.has_wavelength) std::snprintf(wave, sizeof wave, "%.3g mean diameters", st.wavelength_d);
      if (st.top_toe_valid) std::snprintf(top_toe, sizeof top_toe, "%.3f", st.top_toe_index);
      std::snprintf(buf, sizeof buf, "  stratification: stripe wavelength %s, contrast %.3f, top-toe segregation %s\n",
                    wave, st.contrast, top_toe);
      out += buf;
    }
  }
  return out;
}

}  // namespace btr_app
