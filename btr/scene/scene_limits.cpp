#include "btr/scene/scene_limits.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "btr/model/number_text.h"

namespace btr {
namespace {

struct Length {
  std::string json_field, toml_field;
  double value;
  bool positive = false;  // a container's dimension: > 0 (other lengths >= 0)
  const std::string& field(FieldNames n) const { return n == FieldNames::Toml ? toml_field : json_field; }
};

// The radii the scene's drops can have, with the field each comes from.
std::vector<Length> radii(const Scene& s) {
  std::vector<Length> out;
  const bool one = s.grains.components.size() == 1;
  for (std::size_t i = 0; i < s.grains.components.size(); ++i) {
    const RadiusSpec& r = s.grains.components[i].radius;
    const std::string json = "grains.components[" + std::to_string(i) + "].radius";
    const std::string toml = one ? "grains.radius" : "grains.component[" + std::to_string(i) + "].radius";
    switch (r.kind) {
      case RadiusSpec::Kind::Constant: out.push_back({json + ".value", toml + ".value", r.value}); break;
      case RadiusSpec::Kind::Uniform:
      case RadiusSpec::Kind::ConstantMass:
        out.push_back({json + ".min", toml + ".min", r.min});
        out.push_back({json + ".max", toml + ".max", r.max});
        break;
      case RadiusSpec::Kind::List:
        for (double v : r.list) out.push_back({json + ".list", "source.file", v});
        break;
    }
  }
  if (s.intruder && !s.grains.components.empty())
    out.push_back({"intruder.diameter_ratio", "intruder.diameter_ratio",
                   s.intruder->diameter_ratio * s.grains.components[0].radius.value});
  return out;
}

// The lengths of the scene other than radii that set coordinates, with their fields.
std::vector<Length> lengths(const Scene& s) {
  const Container& c = s.container;
  std::vector<Length> out;
  switch (c.kind) {
    case ContainerKind::Box:
    case ContainerKind::Periodic:
      out.push_back({"container.size_x", "container.size", c.size_x, true});
      if (s.dimension == 3) out.push_back({"container.size_y", "container.size", c.size_y, true});
      break;
    case ContainerKind::HeleShaw:
      out.push_back({"container.size_x", "container.size", c.size_x, true});
      out.push_back({"container.gap", "container.gap", c.gap, true});
      break;
    case ContainerKind::Cylinder: out.push_back({"container.radius", "container.radius", c.radius, true}); break;
    case ContainerKind::Drum:
      out.push_back({"container.radius", "container.radius", c.radius, true});
      if (s.dimension == 3) out.push_back({"container.size_y", "container.length", c.size_y, true});
      break;
    case ContainerKind::Mesh:  // its bounding box, as placed
      out.push_back({"container.size_x", "container.file", c.size_x, true});
      out.push_back({"container.size_y", "container.file", c.size_y, true});
      break;
    case ContainerKind::Open: break;
  }
  if (c.height != 0.0) out.push_back({"container.height", "container.height", c.height});  // 0: from the packing
  const SourceSpec& src = s.source;
  switch (src.kind) {
    case SourceSpec::Kind::Point:
      out.push_back({"source.x", "source.position", std::abs(src.x)});
      out.push_back({"source.y", "source.position", std::abs(src.y)});
      out.push_back({"source.scatter", "source.scatter", src.scatter});
      break;
    case SourceSpec::Kind::Region:
      for (auto [f, v] : {std::pair{"x_min", src.x_min}, {"x_max", src.x_max}})
        out.push_back({std::string("source.") + f, "source.x", std::abs(v)});
      for (auto [f, v] : {std::pair{"y_min", src.y_min}, {"y_max", src.y_max}})
        out.push_back({std::string("source.") + f, "source.y", std::abs(v)});
      break;
    default: break;
  }
  if (s.intruder) {
    out.push_back({"intruder.x", "intruder.position", std::abs(s.intruder->x)});
    out.push_back({"intruder.y", "intruder.position", std::abs(s.intruder->y)});
  }
  if (s.shaking) {
    out.push_back({"shaking.lift", "shaking.lift", s.shaking->lift});
    out.push_back({"shaking.noise", "shaking.noise", s.shaking->noise});
  }
  if (s.drum) out.push_back({"drum.lift", "drum.lift", s.drum->lift});
  return out;
}

}  // namespace

std::optional<SceneProblem> scene_value_problem(const Scene& s, FieldNames names) {
  auto problem = [&](const std::string& json_field, const std::string& toml_field, const std::string& what) {
    const std::string& f = names == FieldNames::Toml ? toml_field : json_field;
    return SceneProblem{f, f + " " + what};
  };
  auto problem_of = [&](const Length& l, const std::string& what) { return problem(l.json_field, l.toml_field, what); };
  // Signs and ranges (the TOML reader has checked these already; a packing's JSON may hold anything).
  const std::vector<Length> ls = lengths(s);
  for (const Length& l : ls) {
    if (l.positive && !(std::isfinite(l.value) && l.value > 0.0))
      return problem_of(l, "= " + g6(l.value) + ": expected a positive length [m]");
    if (!std::isfinite(l.value) || l.value < 0.0)
      return problem_of(l, "= " + g6(l.value) + ": expected a finite length >= 0 [m]");
  }
  if (s.grains.count < 0)
    return problem("grains.count", "grains.count", "= " + std::to_string(s.grains.count) + ": expected a count >= 0");
  for (std::size_t i = 0; i < s.grains.components.size(); ++i) {
    const Component& k = s.grains.components[i];
    const std::string at = "grains.components[" + std::to_string(i) + "]";
    const std::string toml = s.grains.components.size() == 1 ? "grains" : "grains.component[" + std::to_string(i) + "]";
    if (!(std::isfinite(k.density) && k.density > 0.0))
      return problem(at + ".density", toml + ".density", "= " + g6(k.density) + ": expected a positive density [kg/m^3]");
    if (!(std::isfinite(k.fraction) && k.fraction >= 0.0))
      return problem(at + ".fraction", toml + ".fraction", "= " + g6(k.fraction) + ": expected a fraction >= 0");
    const Material& m = k.material;
    const std::string mat = at + ".material", tmat = toml + ".material";
    if (!(std::isfinite(m.young) && m.young > 0.0))
      return problem(mat + ".young", tmat + ".young", "= " + g6(m.young) + ": expected a positive Young's modulus [Pa]");
    if (!(m.poisson >= 0.0 && m.poisson < 0.5))
      return problem(mat + ".poisson", tmat + ".poisson", "= " + g6(m.poisson) + ": expected a Poisson ratio in [0, 0.5)");
    if (!(m.restitution > 0.0 && m.restitution <= 1.0))
      return problem(mat + ".restitution", tmat + ".restitution", "= " + g6(m.restitution) + ": expected a restitution in (0, 1]");
    if (!(std::isfinite(m.friction) && m.friction >= 0.0))
      return problem(mat + ".friction", tmat + ".friction", "= " + g6(m.friction) + ": expected a friction coefficient >= 0");
    if (!(std::isfinite(m.rolling_friction) && m.rolling_friction >= 0.0))
      return problem(mat + ".rolling_friction", tmat + ".rolling_friction",
                     "= " + g6(m.rolling_friction) + ": expected a rolling friction coefficient >= 0");
  }
  const RelaxSpec& r = s.relax;
  if (!(std::isfinite(r.max_time) && r.max_time > 0.0))
    return problem("relax.max_time", "relax.max_time", "= " + g6(r.max_time) + ": expected a positive time [s]");
  if (!(r.timestep_fraction > 0.0 && r.timestep_fraction <= 1.0))
    return problem("relax.timestep_fraction", "relax.timestep_fraction",
                   "= " + g6(r.timestep_fraction) + ": expected a fraction in (0, 1]");
  if (!(std::isfinite(r.stop_kinetic_ratio) && r.stop_kinetic_ratio > 0.0))
    return problem("relax.stop_kinetic_ratio", "relax.stop_kinetic_ratio",
                   "= " + g6(r.stop_kinetic_ratio) + ": expected a positive ratio");
  if (!(r.damping >= 0.0 && r.damping < 1.0))
    return problem("relax.damping", "relax.damping", "= " + g6(r.damping) + ": expected a damping in [0, 1)");

  // Radii: positive, and within kMaxRadiusRatio of each other.
  const std::vector<Length> rs = radii(s);
  for (const Length& l : rs)
    if (!(std::isfinite(l.value) && l.value > 0.0))
      return problem_of(l, "= " + g6(l.value) + ": expected a positive radius [m]");
  if (rs.empty()) return std::nullopt;
  const auto [smallest, largest] =
      std::minmax_element(rs.begin(), rs.end(), [](const Length& a, const Length& b) { return a.value < b.value; });
  if (largest->value > kMaxRadiusRatio * smallest->value)
    return problem_of(*smallest,
                   "= " + g6(smallest->value) + " m is " + g6(largest->value / smallest->value) +
                       " times smaller than the largest radius (" + largest->field(names) + " = " + g6(largest->value) +
                       " m); expected grain radii within a factor " + g6(kMaxRadiusRatio) + " of each other");
  // Lengths against the smallest grain: beyond kMaxLengthRatio, rounding of the coordinates reaches the
  // precision the placement and its self-check are exact to.
  for (const Length& l : ls)
    if (l.value > kMaxLengthRatio * smallest->value)
      return problem_of(l, "= " + g6(l.value) + " m is " + g6(l.value / smallest->value) + " times the smallest grain radius (" +
                         smallest->field(names) + " = " + g6(smallest->value) + " m); expected at most " + g6(kMaxLengthRatio) +
                         " times: coordinates that large are rounded by more than the placement's precision");
  if (s.container.kind == ContainerKind::Drum && s.container.radius > kMaxDrumRadiusRatio * smallest->value)
    return problem("container.radius", "container.radius",
                   "= " + g6(s.container.radius) + " m is " + g6(s.container.radius / smallest->value) +
                       " times the smallest grain radius (" + smallest->field(names) + " = " + g6(smallest->value) +
                       " m); expected at most " + g6(kMaxDrumRadiusRatio) +
                       " times in a drum: beyond it the rolling on its wall loses the placement's precision");
  return std::nullopt;
}

}  // namespace btr
