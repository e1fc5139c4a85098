// Scene <-> JSON. Every field is written, so a later stage can rebuild the Scene from NAME.json alone.
#include "coupling/io/scene_json.h"

#include "btr/scene/mesh_file.h"
#include "btr/scene/scene_toml.h"

#include "btr/scene/scene_limits.h"

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <string>

namespace btr {
using nlohmann::json;

namespace {

// ---- enum names (the same words as in the scene TOML) ----

const char* radius_kind_name(RadiusSpec::Kind k) {
  switch (k) {
    case RadiusSpec::Kind::Constant: return "constant";
    case RadiusSpec::Kind::Uniform: return "uniform";
    case RadiusSpec::Kind::ConstantMass: return "constant-mass";
    case RadiusSpec::Kind::List: return "list";
  }
  return "?";
}

const char* source_kind_name(SourceSpec::Kind k) {
  switch (k) {
    case SourceSpec::Kind::Point: return "point";
    case SourceSpec::Kind::Rain: return "rain";
    case SourceSpec::Kind::Region: return "region";
    case SourceSpec::Kind::List: return "list";
  }
  return "?";
}

// ---- strict reading: every key is required, unknown keys are errors ----

class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw std::runtime_error(origin_ + ": scene key '" + path + "': " + what);
  }

  const json& object(const json& parent, const std::string& path, const char* key,
                     std::initializer_list<const char*> allowed) const {
    const json& j = field(parent, path, key);
    std::string p = join(path, key);
    if (!j.is_object()) fail(p, "expected an object");
    check_keys(j, p, allowed);
    return j;
  }

  void check_keys(const json& j, const std::string& path, std::initializer_list<const char*> allowed) const {
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || it.key() == a;
      if (!ok) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(join(path, it.key().c_str()), "unknown key; allowed keys: " + list);
      }
    }
  }

  const json& field(const json& parent, const std::string& path, const char* key) const {
    auto it = parent.find(key);
    if (it == parent.end()) fail(join(path, key), "missing");
    return *it;
  }

  double number(const json& parent, const std::string& path, const char* key) const {
    const json& j = field(parent, path, key);
    if (!j.is_number()) fail(join(path, key), "expected a number, got " + j.dump());
    return j.get<double>();
  }

  std::int64_t integer(const json& parent, const std::string& path, const char* key) const {
    const json& j = field(parent, path, key);
    if (!j.is_number_integer()) fail(join(path, key), "expected an integer, got " + j.dump());
    return j.get<std::int64_t>();
  }

  std::uint64_t unsigned_integer(const json& parent, const std::string& path, const char* key) const {
    const json& j = field(parent, path, key);
    if (!j.is_number_unsigned()) fail(join(path, key), "expected a non-negative integer, got " + j.dump());
    return j.get<std::uint64_t>();
  }

  std::string string(const json& parent, const std::string& path, const char* key) const {
    const json& j = field(parent, path, key);
    if (!j.is_string()) fail(join(path, key), "expected a string, got " + j.dump());
    return j.get<std::string>();
  }

  static std::string join(const std::string& path, const char* key) {
    return path.empty() ? std::string(key) : path + "." + key;
  }

 private:
  std::string origin_;
};

json material_to_json(const Material& m) {
  return {{"young", m.young},
          {"poisson", m.poisson},
          {"restitution", m.restitution},
          {"friction", m.friction},
          {"rolling_friction", m.rolling_friction},
          {"kn", m.kn},
          {"kt", m.kt},
          {"gamma_n", m.gamma_n},
          {"gamma_t", m.gamma_t},
          {"wall_gamma_t", m.wall_gamma_t}};
}

json radius_to_json(const RadiusSpec& r) {
  return {{"kind", radius_kind_name(r.kind)}, {"value", r.value}, {"min", r.min}, {"max", r.max}, {"list", r.list}};
}

RadiusSpec radius_from_json(const Reader& rd, const json& parent, const std::string& path) {
  const json& j = rd.object(parent, path, "radius", {"kind", "value", "min", "max", "list"});
  std::string p = Reader::join(path, "radius");
  RadiusSpec r;
  std::string kind = rd.string(j, p, "kind");
  if (kind == "constant") r.kind = RadiusSpec::Kind::Constant;
  else if (kind == "uniform") r.kind = RadiusSpec::Kind::Uniform;
  else if (kind == "constant-mass") r.kind = RadiusSpec::Kind::ConstantMass;
  else if (kind == "list") r.kind = RadiusSpec::Kind::List;
  else rd.fail(p + ".kind", "expected constant, uniform, constant-mass or list, got '" + kind + "'");
  r.value = rd.number(j, p, "value");
  r.min = rd.number(j, p, "min");
  r.max = rd.number(j, p, "max");
  const json& list = rd.field(j, p, "list");
  if (!list.is_array()) rd.fail(p + ".list", "expected an array of numbers");
  for (const json& v : list) {
    if (!v.is_number()) rd.fail(p + ".list", "expected an array of numbers, got element " + v.dump());
    r.list.push_back(v.get<double>());
  }
  return r;
}

Material material_from_json(const Reader& rd, const json& parent, const std::string& path) {
  const json& j = rd.object(parent, path, "material", {"young", "poisson", "restitution", "friction", "rolling_friction",
                                                       "kn", "kt", "gamma_n", "gamma_t", "wall_gamma_t"});
  std::string p = Reader::join(path, "material");
  Material m;
  m.young = rd.number(j, p, "young");
  m.poisson = rd.number(j, p, "poisson");
  m.restitution = rd.number(j, p, "restitution");
  m.friction = rd.number(j, p, "friction");
  m.rolling_friction = rd.number(j, p, "rolling_friction");
  // Optional: packings written before the hooke-stiffness model have no stiffness keys.
  for (auto [key, field] : {std::pair{"kn", &m.kn}, {"kt", &m.kt}, {"gamma_n", &m.gamma_n}, {"gamma_t", &m.gamma_t},
                            {"wall_gamma_t", &m.wall_gamma_t}})
    if (j.contains(key)) *field = rd.number(j, p, key);
  return m;
}

}  // namespace

namespace {
json scene_core_to_json(const Scene& s);
}  // namespace

json scene_to_json(const Scene& s) {
  json out = scene_core_to_json(s);
  // Only drums have ends (3D); other containers' JSON is unchanged.
  if (s.container.kind == ContainerKind::Drum && s.dimension == 3)
    out["container"]["ends"] = s.container.periodic_ends ? "periodic" : "walls";
  // A mesh: its file (as resolved against the scene's folder) and scale, read again with the packing.
  if (s.container.kind == ContainerKind::Mesh && s.container.mesh) {
    out["container"]["file"] = std::filesystem::absolute(s.container.mesh->file).lexically_normal().string();
    out["container"]["scale"] = s.container.mesh->scale;
  }
  if (s.intruder)
    out["intruder"] = {{"diameter_ratio", s.intruder->diameter_ratio},
                       {"x", s.intruder->x},
                       {"y", s.intruder->y},
                       {"species", s.intruder->species}};
  if (s.drum)
    out["drum"] = {{"steps_per_revolution", s.drum->steps_per_revolution},
                   {"revolutions", s.drum->revolutions},
                   {"lift", s.drum->lift},
                   {"snapshot_every", s.drum->snapshot_every}};
  if (s.drum && s.drum->rpm) out["drum"]["rpm"] = *s.drum->rpm;
  if (s.drum && s.drum->froude) out["drum"]["froude"] = *s.drum->froude;
  if (s.shaking)
    out["shaking"] = {{"cycles", s.shaking->cycles},
                      {"lift", s.shaking->lift},
                      {"noise", s.shaking->noise},
                      {"snapshot_every", s.shaking->snapshot_every}};
  if (s.shaking && s.shaking->gamma) out["shaking"]["gamma"] = *s.shaking->gamma;
  if (s.shaking && s.shaking->frequency) out["shaking"]["frequency"] = *s.shaking->frequency;
  return out;
}

namespace {
json scene_core_to_json(const Scene& s) {
  json components = json::array();
  for (const Component& c : s.grains.components)
    components.push_back({{"species", c.species},
                          {"fraction", c.fraction},
                          {"density", c.density},
                          {"radius", radius_to_json(c.radius)},
                          {"material", material_to_json(c.material)}});
  return {
      {"name", s.name},
      {"file", s.file},
      {"dimension", s.dimension},
      {"seed", s.seed},
      {"grains",
       {{"count", s.grains.count},
        {"fraction_by", s.grains.fraction_by == GrainsSpec::FractionBy::Volume ? "volume" : "number"},
        {"components", components}}},
      {"container",
       {{"kind", to_string(s.container.kind)},
        {"size_x", s.container.size_x},
        {"size_y", s.container.size_y},
        {"gap", s.container.gap},
        {"radius", s.container.radius},
        {"height", s.container.height}}},
      {"source",
       {{"kind", source_kind_name(s.source.kind)},
        {"x", s.source.x},
        {"y", s.source.y},
        {"scatter", s.source.scatter},
        {"x_min", s.source.x_min},
        {"x_max", s.source.x_max},
        {"y_min", s.source.y_min},
        {"y_max", s.source.y_max},
        {"file", s.source.file}}},
      {"relax",
       {{"engine", s.relax.engine},
        {"model", s.relax.model},
        {"max_time", s.relax.max_time},
        {"stop_kinetic_ratio", s.relax.stop_kinetic_ratio},
        {"timestep_fraction", s.relax.timestep_fraction},
        {"timestep", s.relax.timestep ? json(*s.relax.timestep) : json(nullptr)},
        {"stop_rule", s.relax.stop_rule},
        {"stop_unbalanced_force", s.relax.stop_unbalanced_force},
        {"stop_displacement", s.relax.stop_displacement},
        {"damping", s.relax.damping},
        {"open_margin", s.relax.open_margin},
        {"open_heap_angle", s.relax.open_heap_angle},
        {"preload", s.relax.preload},
        {"target_phi", s.relax.target_phi ? json(*s.relax.target_phi) : json(nullptr)},
        {"friction_scales", s.relax.friction_scales},
        {"compaction_damping", s.relax.compaction_damping},
        {"compaction_timestep_fraction",
         s.relax.compaction_timestep_fraction ? json(*s.relax.compaction_timestep_fraction) : json(nullptr)}}},
  };
}

}  // namespace

Scene scene_from_json(const json& j, const std::string& origin) {
  Reader rd(origin);
  if (!j.is_object()) rd.fail("", "expected the scene as a JSON object");
  rd.check_keys(j, "", {"name", "file", "dimension", "seed", "grains", "container", "source", "relax", "intruder",
                     "shaking", "drum"});
  Scene s;
  s.name = rd.string(j, "", "name");
  s.file = rd.string(j, "", "file");
  s.dimension = static_cast<int>(rd.integer(j, "", "dimension"));
  if (s.dimension != 2 && s.dimension != 3) rd.fail("dimension", "expected 2 or 3");
  s.seed = rd.unsigned_integer(j, "", "seed");

  const json& g = rd.object(j, "", "grains", {"count", "fraction_by", "components"});
  s.grains.count = rd.integer(g, "grains", "count");
  std::string by = rd.string(g, "grains", "fraction_by");
  if (by == "number") s.grains.fraction_by = GrainsSpec::FractionBy::Number;
  else if (by == "volume") s.grains.fraction_by = GrainsSpec::FractionBy::Volume;
  else rd.fail("grains.fraction_by", "expected number or volume, got '" + by + "'");
  const json& comps = rd.field(g, "grains", "components");
  if (!comps.is_array() || comps.empty()) rd.fail("grains.components", "expected a non-empty array");
  for (std::size_t i = 0; i < comps.size(); ++i) {
    std::string p = "grains.components[" + std::to_string(i) + "]";
    const json& cj = comps[i];
    if (!cj.is_object()) rd.fail(p, "expected an object");
    rd.check_keys(cj, p, {"species", "fraction", "density", "radius", "material"});
    Component c;
    c.species = static_cast<int>(rd.integer(cj, p, "species"));
    c.fraction = rd.number(cj, p, "fraction");
    c.density = rd.number(cj, p, "density");
    c.radius = radius_from_json(rd, cj, p);
    c.material = material_from_json(rd, cj, p);
    s.grains.components.push_back(c);
  }

  const json& c =
      rd.object(j, "", "container", {"kind", "size_x", "size_y", "gap", "radius", "height", "ends", "file", "scale"});
  std::string kind = rd.string(c, "container", "kind");
  bool found = false;
  for (ContainerKind k : {ContainerKind::Open, ContainerKind::Box, ContainerKind::Periodic, ContainerKind::HeleShaw,
                          ContainerKind::Cylinder, ContainerKind::Drum, ContainerKind::Mesh})
    if (kind == to_string(k)) s.container.kind = k, found = true;
  if (!found)
    rd.fail("container.kind", "expected open, box, periodic, hele-shaw, cylinder, drum or mesh, got '" + kind + "'");
  s.container.size_x = rd.number(c, "container", "size_x");
  s.container.size_y = rd.number(c, "container", "size_y");
  s.container.gap = rd.number(c, "container", "gap");
  s.container.radius = rd.number(c, "container", "radius");
  s.container.height = rd.number(c, "container", "height");
  if (c.contains("ends")) {
    const std::string ends = rd.string(c, "container", "ends");
    if (s.container.kind != ContainerKind::Drum || (ends != "walls" && ends != "periodic"))
      rd.fail("container.ends", "expected \"walls\" or \"periodic\" in a drum container, got '" + ends + "' in a " +
                                    to_string(s.container.kind) + " container");
    s.container.periodic_ends = ends == "periodic";
  }
  if (s.container.kind == ContainerKind::Mesh) {
    if (!c.contains("file")) rd.fail("container.file", "expected the mesh file of a mesh container");
    const std::string file = rd.string(c, "container", "file");
    const double scale = c.contains("scale") ? rd.number(c, "container", "scale") : 1.0;
    try {
      s.container.mesh = read_mesh(file, scale);
    } catch (const SceneError& e) {
      rd.fail("container.file", std::string("the packing's mesh cannot be read again: ") + e.what());
    }
    const Vec3 size = s.container.mesh->hi - s.container.mesh->lo;
    if (std::abs(size.x() - s.container.size_x) > 1e-9 * size.norm() ||
        std::abs(size.y() - s.container.size_y) > 1e-9 * size.norm())
      rd.fail("container.file", file + ": the mesh changed since the packing was made (its bounding box is " +
                                    std::to_string(size.x()) + " x " + std::to_string(size.y()) + ", the packing's " +
                                    std::to_string(s.container.size_x) + " x " + std::to_string(s.container.size_y) + ")");
  } else if (c.contains("file") || c.contains("scale")) {
    rd.fail("container.file", "only a mesh container has a file and a scale");
  }

  const json& src =
      rd.object(j, "", "source", {"kind", "x", "y", "scatter", "x_min", "x_max", "y_min", "y_max", "file"});
  std::string skind = rd.string(src, "source", "kind");
  if (skind == "point") s.source.kind = SourceSpec::Kind::Point;
  else if (skind == "rain") s.source.kind = SourceSpec::Kind::Rain;
  else if (skind == "region") s.source.kind = SourceSpec::Kind::Region;
  else if (skind == "list") s.source.kind = SourceSpec::Kind::List;
  else rd.fail("source.kind", "expected point, rain, region or list, got '" + skind + "'");
  s.source.x = rd.number(src, "source", "x");
  s.source.y = rd.number(src, "source", "y");
  s.source.scatter = rd.number(src, "source", "scatter");
  s.source.x_min = rd.number(src, "source", "x_min");
  s.source.x_max = rd.number(src, "source", "x_max");
  s.source.y_min = rd.number(src, "source", "y_min");
  s.source.y_max = rd.number(src, "source", "y_max");
  s.source.file = rd.string(src, "source", "file");

  const json& r = rd.object(j, "", "relax",
                            {"engine", "model", "max_time", "stop_kinetic_ratio", "timestep_fraction", "timestep",
                             "stop_rule", "stop_unbalanced_force", "stop_displacement", "damping", "open_margin",
                             "open_heap_angle", "preload", "target_phi", "friction_scales", "compaction_damping", "compaction_timestep_fraction"});
  s.relax.engine = rd.string(r, "relax", "engine");
  s.relax.model = rd.string(r, "relax", "model");
  s.relax.max_time = rd.number(r, "relax", "max_time");
  s.relax.stop_kinetic_ratio = rd.number(r, "relax", "stop_kinetic_ratio");
  s.relax.timestep_fraction = rd.number(r, "relax", "timestep_fraction");
  const json& ts = rd.field(r, "relax", "timestep");
  if (ts.is_null()) s.relax.timestep.reset();
  else if (ts.is_number()) s.relax.timestep = ts.get<double>();
  else rd.fail("relax.timestep", "expected a number or null, got " + ts.dump());
  if (r.contains("preload")) {  // absent in packings written before the option existed
    if (!r["preload"].is_boolean()) rd.fail("relax.preload", "expected true or false, got " + r["preload"].dump());
    s.relax.preload = r["preload"].get<bool>();
  }
  // Keys added later: packings written before them have none and take the defaults.
  if (r.contains("stop_rule")) s.relax.stop_rule = rd.string(r, "relax", "stop_rule");
  if (r.contains("stop_unbalanced_force")) s.relax.stop_unbalanced_force = rd.number(r, "relax", "stop_unbalanced_force");
  if (r.contains("stop_displacement")) s.relax.stop_displacement = rd.number(r, "relax", "stop_displacement");
  if (r.contains("damping")) s.relax.damping = rd.number(r, "relax", "damping");
  if (r.contains("open_margin")) s.relax.open_margin = rd.number(r, "relax", "open_margin");
  if (r.contains("open_heap_angle")) s.relax.open_heap_angle = rd.number(r, "relax", "open_heap_angle");
  if (r.contains("target_phi") && !r["target_phi"].is_null()) s.relax.target_phi = rd.number(r, "relax", "target_phi");
  if (r.contains("friction_scales")) {
    const json& f = r["friction_scales"];
    if (!f.is_array() || f.empty()) rd.fail("relax.friction_scales", "expected a non-empty array, got " + f.dump());
    s.relax.friction_scales.clear();
    for (const json& v : f) {
      if (!v.is_number()) rd.fail("relax.friction_scales", "expected numbers, got " + v.dump());
      s.relax.friction_scales.push_back(v.get<double>());
    }
  }
  if (r.contains("compaction_damping")) s.relax.compaction_damping = rd.number(r, "relax", "compaction_damping");
  if (r.contains("compaction_timestep_fraction") && !r["compaction_timestep_fraction"].is_null())
    s.relax.compaction_timestep_fraction = rd.number(r, "relax", "compaction_timestep_fraction");
  if (j.contains("intruder")) {
    const json& in = rd.object(j, "", "intruder", {"diameter_ratio", "x", "y", "species"});
    IntruderSpec spec;
    spec.diameter_ratio = rd.number(in, "intruder", "diameter_ratio");
    spec.x = rd.number(in, "intruder", "x");
    spec.y = rd.number(in, "intruder", "y");
    spec.species = static_cast<int>(rd.integer(in, "intruder", "species"));
    s.intruder = spec;
  }
  if (j.contains("drum")) {
    const json& dr = rd.object(j, "", "drum", {"steps_per_revolution", "revolutions", "lift", "snapshot_every", "rpm", "froude"});
    DrumSpec spec;
    spec.steps_per_revolution = rd.integer(dr, "drum", "steps_per_revolution");
    spec.revolutions = rd.number(dr, "drum", "revolutions");
    spec.lift = rd.number(dr, "drum", "lift");
    spec.snapshot_every = rd.integer(dr, "drum", "snapshot_every");
    if (dr.contains("rpm")) spec.rpm = rd.number(dr, "drum", "rpm");
    if (dr.contains("froude")) spec.froude = rd.number(dr, "drum", "froude");
    s.drum = spec;
  }
  if (j.contains("shaking")) {
    const json& sh = rd.object(j, "", "shaking", {"cycles", "lift", "noise", "snapshot_every", "gamma", "frequency"});
    ShakingSpec spec;
    spec.cycles = rd.integer(sh, "shaking", "cycles");
    spec.lift = rd.number(sh, "shaking", "lift");
    spec.noise = rd.number(sh, "shaking", "noise");
    spec.snapshot_every = rd.integer(sh, "shaking", "snapshot_every");
    if (sh.contains("gamma")) spec.gamma = rd.number(sh, "shaking", "gamma");
    if (sh.contains("frequency")) spec.frequency = rd.number(sh, "shaking", "frequency");
    s.shaking = spec;
  }
  if (auto p = scene_value_problem(s, FieldNames::Json)) rd.fail(p->field, p->message.substr(p->field.size() + 1));
  return s;
}

}  // namespace btr
