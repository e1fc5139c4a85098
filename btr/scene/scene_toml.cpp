#include "btr/scene/scene_toml.h"
#include "btr/scene/mesh_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <toml++/toml.h>

#include "btr/scene/cluster_list.h"
#include "btr/scene/drop_list.h"
#include "btr/scene/scene_limits.h"
#include "btr/scene/size_budget.h"
#include "btr/scene/toml_reader.h"

namespace btr {
namespace {

using namespace toml_reader;

const auto positive = [](double v) { return v > 0.0; };
const auto non_negative = [](double v) { return v >= 0.0; };
const auto any = [](double) { return true; };

// Everything parsed from the file plus what the cross-checks need to point at.
class SceneParser {
 public:
  SceneParser(const std::string& path, const toml::table& root) : rd_(path), path_(path) {
    root_ = Section{&root, "", "the top level of the file", 0};
  }

  Scene parse() {
    rd_.check_keys(root_,
                   {"scene", "grains", "container", "source", "material", "relax", "intruder", "shaking", "drum", "clusters"});
    scene_.file = path_;
    parse_scene(required_table("scene"));
    parse_relax();  // first: relax.model decides which material keys are allowed
    auto material = rd_.table(root_, "material", "[material]");
    Material defaults = material ? parse_material(*material, Material{}) : Material{};
    Section container = required_table("container");
    Section source = required_table("source");
    const std::string source_kind = rd_.required_choice(source, "kind", {"point", "rain", "region", "list"});
    list_source_ = source_kind == "list";
    Section grains = required_table("grains");
    parse_grains(grains, defaults);
    check_stiffness_materials();
    parse_container(container);
    parse_source(source, source_kind);
    finish_list_source(grains);
    parse_intruder();
    parse_shaking();
    parse_drum();
    parse_clusters();
    if (auto p = scene_value_problem(scene_, FieldNames::Toml)) {
      const toml::node* n = root_.tbl->at_path(p->field).node();
      rd_.fail(n ? Reader::line_of(*n) : 0, p->message);
    }
    check_container_holds_grains(container);
    check_source_fits(source);
    check_grid_fits(container, source);
    for (auto why : {count_does_not_fit(scene_.grains.count, "grains.count"),
                     drum_overfilled(scene_, scene_.grains.count, "grains.count")})
      if (why) rd_.fail(rd_.get(grains, "count") ? Reader::line_of(*rd_.get(grains, "count")) : grains.line, *why);
    return scene_;
  }

 private:
  Reader rd_;
  std::string path_;
  Section root_;
  Scene scene_;
  bool list_source_ = false;
  std::vector<ListedDrop> listed_;
  double r_max_ = 0.0;
  int dim() const { return scene_.dimension; }

  Section required_table(const std::string& key) {
    auto t = rd_.table(root_, key, "[" + key + "]");
    if (!t) rd_.fail(0, "missing table [" + key + "]");
    return *t;
  }

  void parse_scene(const Section& s) {
    rd_.check_keys(s, {"name", "dimension", "seed"});
    scene_.name = rd_.string(s, "name", "a non-empty string")
                      .value_or(std::filesystem::path(path_).stem().string());
    auto d = rd_.integer(s, "dimension", [](std::int64_t v) { return v == 2 || v == 3; }, "2 or 3");
    if (!d) rd_.missing(s, "dimension", "2 or 3");
    scene_.dimension = static_cast<int>(*d);
    scene_.seed = static_cast<std::uint64_t>(
        rd_.integer(s, "seed", [](std::int64_t v) { return v >= 0; }, "an integer >= 0").value_or(1));
  }

  void parse_intruder() {
    auto s = rd_.table(root_, "intruder", "[intruder]");
    if (!s) return;
    rd_.check_keys(*s, {"diameter_ratio", "position"});
    const GrainsSpec& g = scene_.grains;
    if (list_source_ || g.components.size() != 1 || g.components[0].radius.kind != RadiusSpec::Kind::Constant)
      rd_.fail(s->line, "[intruder]: expected a bed of equal grains (one component, grains.radius = { distribution "
                        "= \"constant\", ... }, not a list source) for the intruder's diameter ratio to refer to");
    IntruderSpec in;
    in.diameter_ratio = rd_.required_number(*s, "diameter_ratio", positive, "a positive diameter ratio Phi");
    const std::string expect = dim() == 2 ? "[x] for dimension 2" : "[x, y] for dimension 3";
    if (auto p = rd_.numbers(*s, "position", dim() - 1, any, expect)) {
      in.x = (*p)[0];
      in.y = dim() == 3 ? (*p)[1] : 0.0;
    }
    in.species = g.components[0].species + 1;
    const double r = in.diameter_ratio * g.components[0].radius.value;
    r_max_ = std::max(r_max_, r);
    if (!disk_fits(in.x, in.y, 0.0, r))
      rd_.fail(s->line, "intruder.position: expected a drop that keeps the intruder (r = " + fmt(r) +
                            " m) inside the " + to_string(scene_.container.kind) + " container: " + allowed_text(r) +
                            ", got [" + fmt(in.x) + (dim() == 3 ? ", " + fmt(in.y) : "") + "]");
    scene_.intruder = in;
  }

  void parse_shaking() {
    auto s = rd_.table(root_, "shaking", "[shaking]");
    if (!s) return;
    rd_.check_keys(*s, {"cycles", "lift", "noise", "snapshot_every", "gamma", "frequency"});
    ShakingSpec sh;
    auto cycles = rd_.integer(*s, "cycles", [](std::int64_t v) { return v > 0; }, "a positive number of cycles");
    if (!cycles) rd_.missing(*s, "cycles", "a positive number of cycles");
    sh.cycles = *cycles;
    sh.lift = rd_.required_number(*s, "lift", positive, "a positive lift of the whole pile [m]");
    sh.noise = rd_.number_or(*s, "noise", 0.0, non_negative, "a noise amplitude >= 0 [m]");
    sh.snapshot_every = rd_.integer(*s, "snapshot_every", [](std::int64_t v) { return v > 0; },
                                    "a positive number of cycles")
                            .value_or(sh.cycles);
    sh.gamma = rd_.number(*s, "gamma", [](double v) { return v > 0.0 && v <= kMaxTapGamma; },
                          "a peak acceleration Gamma = A (2 pi f)^2 / g in (0, 100] (DEM tapping)");
    sh.frequency = rd_.number(*s, "frequency", [](double v) { return v > 0.0 && v <= kMaxTapFrequency; },
                              "a tap frequency in (0, 10000] Hz (DEM tapping)");
    scene_.shaking = sh;
  }

  void parse_clusters() {
    auto s = rd_.table(root_, "clusters", "[clusters]");
    if (!s) return;
    rd_.check_keys(*s, {"size", "block", "cycles", "file"});
    const ContainerKind kind = scene_.container.kind;
    if (kind != ContainerKind::Box && kind != ContainerKind::Periodic)
      rd_.fail(s->line, "[clusters]: expected container.kind = \"box\" or \"periodic\" (clusters are dropped at "
                        "random positions over its width), got \"" + std::string(to_string(kind)) + "\"");
    ClustersSpec c;
    c.size = rd_.integer(*s, "size", [](std::int64_t v) { return v >= 1 && v <= 100000; },
                         "an integer number of grains per initial cluster, 1 to 100000")
                 .value_or(c.size);
    // A block narrower than a grain cuts nothing out (and its index overflows): meaningless, refused.
    c.block = rd_.number_or(*s, "block", c.block, [](double v) { return v >= 1.0; },
                            "a block size of at least 1 mean grain diameter");
    c.cycles = rd_.integer(*s, "cycles", [](std::int64_t v) { return v >= 0; }, "a number of cycles >= 0")
                   .value_or(c.cycles);
    if (auto file = rd_.string(*s, "file", "a CSV file name (relative to the scene file's folder)")) {
      const int line = Reader::line_of(*rd_.get(*s, "file"));
      if (rd_.get(*s, "size"))
        rd_.fail(line, "[clusters]: give either size (random compact clusters) or file (a cluster list), not both");
      namespace fs = std::filesystem;
      fs::path p(*file);
      if (p.is_relative()) p = fs::path(path_).parent_path() / p;
      c.file = p.lexically_normal().string();
      if (!std::ifstream(c.file)) rd_.fail(line, "clusters.file: cannot open '" + c.file + "'");
      // The list decides the grains: their number must be the scene's count, their species the scene's.
      std::int64_t rows = 0;
      for (const ClusterShape& shape : read_cluster_list(c.file, dim())) {
        rows += static_cast<std::int64_t>(shape.size());
        for (int sp : shape.species)
          if (std::none_of(scene_.grains.components.begin(), scene_.grains.components.end(),
                           [&](const Component& k) { return k.species == sp; }))
            throw SceneError(c.file + ": species " + std::to_string(sp) + " is not a species of the scene " + path_);
      }
      if (scene_.grains.count != rows)
        rd_.fail(line, "clusters.file: " + c.file + " lists " + std::to_string(rows) + " grains, but grains.count is " +
                           std::to_string(scene_.grains.count) + "; set grains.count = " + std::to_string(rows));
    }
    scene_.clusters = c;
  }

  void parse_drum() {
    auto s = rd_.table(root_, "drum", "[drum]");
    if (!s) return;
    if (scene_.container.kind != ContainerKind::Drum)
      rd_.fail(s->line, "[drum]: expected container.kind = \"drum\" for a rotating drum, got \"" +
                            std::string(to_string(scene_.container.kind)) + "\"");
    rd_.check_keys(*s, {"steps_per_revolution", "revolutions", "lift", "snapshot_every", "rpm", "froude"});
    DrumSpec dr;
    auto steps = rd_.integer(*s, "steps_per_revolution", [](std::int64_t v) { return v > 0; }, "a positive integer");
    if (!steps) rd_.missing(*s, "steps_per_revolution", "a positive integer");
    dr.steps_per_revolution = *steps;
    dr.revolutions = rd_.required_number(*s, "revolutions", positive, "a positive number of revolutions");
    dr.lift = rd_.number_or(*s, "lift", 0.1 * scene_.container.radius, positive,
                            "a positive lift [m] (default: radius / 10, as in the BTR paper)");
    dr.snapshot_every = rd_.integer(*s, "snapshot_every", [](std::int64_t v) { return v > 0; }, "a positive number of steps")
                            .value_or(dr.steps_per_revolution);
    // The DEM drum's speed (btr drum --engine): rpm or the Froude number omega^2 R / g, not both.
    dr.rpm = rd_.number(*s, "rpm", positive, "a positive rotation speed [revolutions per minute]");
    dr.froude = rd_.number(*s, "froude", [](double v) { return v > 0.0 && v < 1.0; },
                           "a Froude number omega^2 R / g in (0, 1) (1 = centrifuging; rolling regime about 1e-4 to 1e-2)");
    if (dr.rpm && dr.froude)
      rd_.fail(Reader::line_of(*rd_.get(*s, "froude")),
               "drum.froude: give drum.rpm or drum.froude, not both (they set the same speed)");
    scene_.drum = dr;
  }

  Material parse_material(const Section& s, const Material& base) {
    rd_.check_keys(s, {"young", "poisson", "restitution", "friction", "rolling_friction", "kn", "kt", "gamma_n",
                       "gamma_t", "wall_gamma_t"});
    Material m = base;
    if (scene_.relax.model == "hooke-stiffness") {
      m.kn = rd_.number_or(s, "kn", base.kn, positive, "a positive normal stiffness [N/m]");
      m.kt = rd_.number_or(s, "kt", base.kt, positive, "a positive tangential stiffness [N/m]");
      m.gamma_n = rd_.number_or(s, "gamma_n", base.gamma_n, non_negative, "a normal damping rate >= 0 [1/s]");
      m.gamma_t = rd_.number_or(s, "gamma_t", base.gamma_t, non_negative, "a tangential damping rate >= 0 [1/s]");
      m.wall_gamma_t = rd_.number_or(s, "wall_gamma_t", s.tbl->contains("gamma_t") ? m.gamma_t : base.wall_gamma_t,
                                     non_negative, "a grain-wall tangential damping rate >= 0 [1/s]");
    } else {
      for (const char* k : {"kn", "kt", "gamma_n", "gamma_t", "wall_gamma_t"})
        rd_.forbid(s, k, "unless relax.model = \"hooke-stiffness\" (the " + scene_.relax.model +
                             " model derives its stiffness from young and poisson)");
    }
    m.young = rd_.number_or(s, "young", base.young, positive, "a positive Young's modulus [Pa]");
    m.poisson = rd_.number_or(s, "poisson", base.poisson, [](double v) { return v > -1.0 && v < 0.5; },
                              "a Poisson ratio in (-1, 0.5)");
    m.restitution = rd_.number_or(s, "restitution", base.restitution,
                                  [](double v) { return v > 0.0 && v <= 1.0; }, "a restitution in (0, 1]");
    m.friction = rd_.number_or(s, "friction", base.friction, non_negative, "a friction coefficient >= 0");
    m.rolling_friction = rd_.number_or(s, "rolling_friction", base.rolling_friction, non_negative,
                                       "a rolling friction coefficient >= 0 (0 = off)");
    return m;
  }

  void parse_relax() {
    auto s = rd_.table(root_, "relax", "[relax]");
    if (!s) return;
    rd_.check_keys(*s, {"engine", "model", "max_time", "stop_kinetic_ratio", "timestep_fraction", "timestep", "stop_rule",
                        "stop_unbalanced_force", "stop_displacement", "damping", "open_margin", "open_heap_angle",
                        "preload", "target_phi", "friction_scales", "compaction_damping", "compaction_timestep_fraction"});
    RelaxSpec& r = scene_.relax;
    r.engine = rd_.choice(*s, "engine", {"liggghts", "yade"}).value_or(r.engine);
    r.model = rd_.choice(*s, "model", {"hertz", "hooke", "hooke-stiffness"}).value_or(r.model);
    r.max_time = rd_.number_or(*s, "max_time", r.max_time, positive, "a positive time [s]");
    r.stop_kinetic_ratio = rd_.number_or(*s, "stop_kinetic_ratio", r.stop_kinetic_ratio, positive,
                                         "a positive ratio");
    r.timestep_fraction = rd_.number_or(*s, "timestep_fraction", r.timestep_fraction,
                                        [](double v) { return v > 0.0 && v <= 1.0; }, "a fraction in (0, 1]");
    if (auto t = rd_.number(*s, "timestep", positive, "a positive time step [s]")) r.timestep = *t;
    r.preload = rd_.boolean_or(*s, "preload", r.preload);
    r.stop_rule = rd_.choice(*s, "stop_rule", {"kinetic-energy", "unbalanced-force", "displacement"}).value_or(r.stop_rule);
    r.stop_unbalanced_force = rd_.number_or(*s, "stop_unbalanced_force", r.stop_unbalanced_force,
                                            [](double v) { return v > 0.0 && v < 1.0; },
                                            "a ratio in (0, 1) (mean resultant force / mean contact force)");
    r.stop_displacement = rd_.number_or(*s, "stop_displacement", r.stop_displacement,
                                        [](double v) { return v > 0.0 && v < 1.0; },
                                        "a fraction in (0, 1) of the smallest grain diameter");
    r.damping = rd_.number_or(*s, "damping", r.damping, [](double v) { return v >= 0.0 && v < 1.0; },
                              "a damping coefficient in [0, 1) (YADE's NewtonIntegrator damping; 0 = off)");
    r.open_margin = rd_.number_or(*s, "open_margin", r.open_margin, positive,
                                  "a positive number of largest grain diameters");
    r.open_heap_angle = rd_.number_or(*s, "open_heap_angle", r.open_heap_angle,
                                      [](double v) { return v > 0.0 && v < 90.0; }, "an angle in (0, 90) degrees");
    if (auto t = rd_.number(*s, "target_phi", [](double v) { return v > 0.0 && v < 1.0; },
                            "a target bulk packing fraction in (0, 1)"))
      r.target_phi = *t;
    if (auto v = rd_.numbers(*s, "friction_scales", 0, [](double x) { return x >= 0.0 && x < 1.0; },
                             "a non-empty array of friction scales in [0, 1), decreasing")) {
      for (std::size_t k = 1; k < v->size(); ++k)
        if (!((*v)[k] < (*v)[k - 1]))
          rd_.fail(s->line, "relax.friction_scales: expected decreasing scales, got " + std::to_string((*v)[k - 1]) +
                                " then " + std::to_string((*v)[k]));
      r.friction_scales = *v;
    }
    r.compaction_damping = rd_.number_or(*s, "compaction_damping", r.compaction_damping,
                                         [](double v) { return v >= 0.0 && v < 1.0; },
                                         "a damping coefficient in [0, 1) during the compaction to target_phi");
    if (auto f = rd_.number(*s, "compaction_timestep_fraction", [](double v) { return v > 0.0 && v <= 1.0; },
                            "a fraction in (0, 1] of the Rayleigh / contact time during the compaction"))
      r.compaction_timestep_fraction = *f;
  }

  // hooke-stiffness takes no default stiffness: every component must have kn and kt from [material]
  // or its own material table.
  void check_stiffness_materials() {
    if (scene_.relax.model != "hooke-stiffness") return;
    for (const Component& c : scene_.grains.components)
      if (!(c.material.kn > 0.0) || !(c.material.kt > 0.0))
        rd_.fail(0, "[material] (or the material of species " + std::to_string(c.species) +
                        "): relax.model = \"hooke-stiffness\" needs kn and kt (positive stiffnesses [N/m])");
  }

  RadiusSpec parse_radius(const Section& s) {
    rd_.check_keys(s, {"distribution", "value", "min", "max", "values"});
    const std::string kind = rd_.required_choice(s, "distribution", {"constant", "uniform", "constant-mass", "list"});
    const std::string why = "by distribution = " + quoted(kind);
    RadiusSpec r;
    if (kind == "constant") {
      r.kind = RadiusSpec::Kind::Constant;
      for (const char* k : {"min", "max", "values"}) rd_.forbid(s, k, why + " (it takes: value)");
      r.value = rd_.required_number(s, "value", positive, "a positive radius [m]");
    } else if (kind == "list") {
      r.kind = RadiusSpec::Kind::List;
      for (const char* k : {"value", "min", "max"}) rd_.forbid(s, k, why + " (it takes: values)");
      auto v = rd_.numbers(s, "values", 0, positive, "a non-empty array of positive radii [m]");
      if (!v) rd_.missing(s, "values", "a non-empty array of positive radii [m]");
      r.list = *v;
    } else {
      r.kind = kind == "uniform" ? RadiusSpec::Kind::Uniform : RadiusSpec::Kind::ConstantMass;
      for (const char* k : {"value", "values"}) rd_.forbid(s, k, why + " (it takes: min, max)");
      r.min = rd_.required_number(s, "min", positive, "a positive radius [m]");
      r.max = rd_.required_number(s, "max", [&](double v) { return v > r.min; },
                                  "a radius [m] larger than min = " + fmt(r.min));
    }
    return r;
  }

  static double largest(const RadiusSpec& r) {
    switch (r.kind) {
      case RadiusSpec::Kind::Constant: return r.value;
      case RadiusSpec::Kind::List: return *std::max_element(r.list.begin(), r.list.end());
      default: return r.max;
    }
  }

  void parse_grains(const Section& s, const Material& material) {
    rd_.check_keys(s, {"count", "density", "radius", "fraction_by", "component"});
    GrainsSpec& g = scene_.grains;
    const std::string why_list = "with source.kind = \"list\" (the file gives each drop's radius and species)";
    auto count = rd_.integer(s, "count", [](std::int64_t v) { return v > 0; }, "a positive integer");
    if (!count && !list_source_) rd_.missing(s, "count", "a positive integer");
    g.count = count.value_or(0);
    const double density = rd_.number_or(s, "density", 2500.0, positive, "a positive density [kg/m^3]");
    std::optional<RadiusSpec> radius;
    if (list_source_) rd_.forbid(s, "radius", why_list);
    if (auto r = rd_.table(s, "radius", "grains.radius")) radius = parse_radius(*r);
    if (list_source_) rd_.forbid(s, "fraction_by", why_list);
    const std::string by = rd_.choice(s, "fraction_by", {"number", "volume"}).value_or("number");
    g.fraction_by = by == "volume" ? GrainsSpec::FractionBy::Volume : GrainsSpec::FractionBy::Number;

    auto comp_node = rd_.get(s, "component");
    if (!comp_node) {
      Component c;
      c.density = density;
      c.material = material;
      if (!radius && !list_source_)
        rd_.missing(s, "radius", "a table such as { distribution = \"constant\", value = 1e-3 }");
      if (radius) c.radius = *radius;
      g.components = {c};
      return;
    }
    auto arr = comp_node->as_array();
    if (!arr || arr->empty() || !arr->is_array_of_tables())
      rd_.bad_value(s, "component", *comp_node, "an array of tables ([[grains.component]] entries)");
    const std::int64_t K = static_cast<std::int64_t>(arr->size());
    std::set<std::int64_t> seen;
    double sum = 0.0;
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const auto& node = *arr->get(i);
      const std::string name = "grains.component#" + std::to_string(i + 1);
      Section c{node.as_table(), name, "[[grains.component]] #" + std::to_string(i + 1), Reader::line_of(node)};
      rd_.check_keys(c, {"species", "fraction", "density", "radius", "material"});
      Component comp;
      comp.species = static_cast<int>(
          rd_.integer(c, "species", [&](std::int64_t v) { return v >= 1 && v <= K; },
                      "a species id in 1.." + std::to_string(K))
              .value_or(static_cast<std::int64_t>(i + 1)));
      if (!seen.insert(comp.species).second) {
        auto n = rd_.get(c, "species");
        rd_.fail(n ? Reader::line_of(*n) : c.line, name + ".species: expected distinct species ids 1.." +
                                                       std::to_string(K) + ", got " +
                                                       std::to_string(comp.species) + " twice");
      }
      if (list_source_) rd_.forbid(c, "fraction", why_list);
      auto f = rd_.number(c, "fraction", [](double v) { return v >= 0.0 && v <= 1.0; }, "a fraction in [0, 1]");
      if (!f && K > 1 && !list_source_) rd_.missing(c, "fraction", "a fraction in [0, 1] (the mixture has " +
                                                                       std::to_string(K) + " components)");
      comp.fraction = f.value_or(list_source_ ? 0.0 : 1.0);
      sum += comp.fraction;
      comp.density = rd_.number_or(c, "density", density, positive, "a positive density [kg/m^3]");
      if (list_source_) rd_.forbid(c, "radius", why_list);
      if (auto r = rd_.table(c, "radius", name + ".radius")) comp.radius = parse_radius(*r);
      else if (radius) comp.radius = *radius;
      else if (!list_source_)
        rd_.missing(c, "radius", "a radius table (or a default grains.radius)");
      auto m = rd_.table(c, "material", name + ".material");
      comp.material = m ? parse_material(*m, material) : material;
      g.components.push_back(comp);
    }
    if (!list_source_ && std::abs(sum - 1.0) > 1e-9)
      rd_.fail(Reader::line_of(*arr->get(0)),
               "grains.component: expected fractions summing to 1 (within 1e-9), got a sum of " + fmt(sum));
  }

  void parse_container(const Section& s) {
    rd_.check_keys(s, {"kind", "size", "gap", "radius", "height", "length", "ends", "file", "scale"});
    Container& c = scene_.container;
    const std::string kind =
        rd_.required_choice(s, "kind", {"open", "box", "periodic", "hele-shaw", "cylinder", "drum", "mesh"});
    if (dim() == 2 && (kind == "hele-shaw" || kind == "cylinder" || kind == "mesh"))
      rd_.fail(Reader::line_of(*rd_.get(s, "kind")),
               "container.kind: expected \"open\", \"box\" or \"periodic\" for dimension 2 (" + kind +
                   " is 3D only), got " + quoted(kind));
    c.kind = kind == "open"       ? ContainerKind::Open
             : kind == "box"      ? ContainerKind::Box
             : kind == "periodic" ? ContainerKind::Periodic
             : kind == "hele-shaw" ? ContainerKind::HeleShaw
             : kind == "cylinder"  ? ContainerKind::Cylinder
             : kind == "mesh"      ? ContainerKind::Mesh
                                   : ContainerKind::Drum;
    const std::string why = "by kind = " + quoted(kind);
    if (kind == "open" || kind == "cylinder" || kind == "drum" || kind == "mesh") rd_.forbid(s, "size", why);
    if (kind != "mesh") {
      rd_.forbid(s, "file", why + " (only mesh has a file)");
      rd_.forbid(s, "scale", why + " (only mesh has a scale)");
    }
    if (kind != "hele-shaw") rd_.forbid(s, "gap", why + " (only hele-shaw has a gap)");
    if (kind != "cylinder" && kind != "drum") rd_.forbid(s, "radius", why + " (only cylinder and drum have a radius)");
    if (kind != "drum" || dim() == 2) rd_.forbid(s, "length", why + (dim() == 2 ? " in 2D" : "") + " (only a 3D drum has a length)");
    if (kind != "drum" || dim() == 2)
      rd_.forbid(s, "ends", why + (dim() == 2 ? " in 2D" : "") + " (only a 3D drum has ends)");
    if (kind == "drum") {
      c.radius = rd_.required_number(s, "radius", positive, "a positive drum radius [m]");
      if (dim() == 3) {
        c.periodic_ends = rd_.choice(s, "ends", {"walls", "periodic"}).value_or("walls") == "periodic";
        c.size_y = rd_.required_number(s, "length", positive,
                                       c.periodic_ends ? "a positive drum length [m] (the period along the axis)"
                                                       : "a positive drum length [m] (end walls at y = +-length/2)");
      }
    }
    if (kind == "box" || kind == "periodic" || kind == "hele-shaw") {
      const std::size_t n = (kind == "hele-shaw" || dim() == 2) ? 1 : 2;
      const std::string expect =
          kind == "hele-shaw" ? "[x]: the cell length [m] (the plate distance is container.gap)"
          : n == 1            ? "[x] for dimension 2: the positive width [m]"
                              : "[x, y] for dimension 3: positive widths [m]";
      auto size = rd_.numbers(s, "size", n, positive, expect);
      if (!size) rd_.missing(s, "size", expect);
      c.size_x = (*size)[0];
      if (n == 2) c.size_y = (*size)[1];
    }
    if (kind == "hele-shaw") c.gap = rd_.required_number(s, "gap", positive, "a positive plate distance w [m]");
    if (kind == "cylinder") c.radius = rd_.required_number(s, "radius", positive, "a positive radius [m]");
    if (kind == "mesh") parse_mesh(s, c);
    c.height = rd_.number_or(s, "height", 0.0, positive, "a positive wall height [m]");
  }

  // container.file (an STL file, relative to the scene's folder) and container.scale: the mesh is read
  // here, so every later check (grain size, footprint) sees its placed bounding box.
  void parse_mesh(const Section& s, Container& c) {
    const toml::node* f = rd_.get(s, "file");
    if (!f) rd_.missing(s, "file", "an STL file (ASCII or binary), relative to the scene file");
    const auto file = f->value<std::string>();
    if (!file || file->empty())
      rd_.fail(Reader::line_of(*f), "container.file: expected the path of an STL file, got a " +
                                        std::string(file ? "empty string" : "value of another type"));
    namespace fs = std::filesystem;
    fs::path p(*file);
    if (p.is_relative()) p = fs::path(path_).parent_path() / p;
    const double scale = rd_.number_or(s, "scale", 1.0, positive, "a positive scale (1e-3: the file is in mm)");
    try {
      c.mesh = read_mesh(p.string(), scale);
    } catch (const SceneError& e) {
      rd_.fail(Reader::line_of(*f), std::string("container.file: ") + e.what());
    }
    c.size_x = c.mesh->hi.x() - c.mesh->lo.x();
    c.size_y = c.mesh->hi.y() - c.mesh->lo.y();
  }

  void parse_source(const Section& s, const std::string& kind) {
    rd_.check_keys(s, {"kind", "position", "scatter", "x", "y", "file"});
    SourceSpec& src = scene_.source;
    const std::string why = "by kind = " + quoted(kind);
    if (kind != "point") {
      rd_.forbid(s, "position", why);
      rd_.forbid(s, "scatter", why);
    }
    if (kind != "region") {
      rd_.forbid(s, "x", why);
      rd_.forbid(s, "y", why);
    }
    if (kind != "list") rd_.forbid(s, "file", why);
    if (kind == "point") {
      src.kind = SourceSpec::Kind::Point;
      const std::string expect = dim() == 2 ? "[x] for dimension 2" : "[x, y] for dimension 3";
      auto p = rd_.numbers(s, "position", dim() - 1, any, expect);
      if (!p) rd_.missing(s, "position", expect);
      src.x = (*p)[0];
      src.y = dim() == 3 ? (*p)[1] : 0.0;
      src.scatter = rd_.number_or(s, "scatter", 0.0, non_negative, "a radius >= 0 [m]");
    } else if (kind == "rain") {
      src.kind = SourceSpec::Kind::Rain;
      if (scene_.container.kind == ContainerKind::Open)
        rd_.fail(Reader::line_of(*rd_.get(s, "kind")),
                 "source.kind: expected \"point\" or \"region\" on an open floor (rain needs a container "
                 "footprint), got \"rain\"");
    } else if (kind == "region") {
      src.kind = SourceSpec::Kind::Region;
      auto range = [&](const std::string& key) {
        const std::string expect = "[min, max] with min < max [m]";
        auto v = rd_.numbers(s, key, 2, any, expect);
        if (!v) rd_.missing(s, key, expect);
        if (!((*v)[0] < (*v)[1])) rd_.bad_value(s, key, *rd_.get(s, key), expect);
        return *v;
      };
      auto x = range("x");
      src.x_min = x[0], src.x_max = x[1];
      if (dim() == 3) {
        auto y = range("y");
        src.y_min = y[0], src.y_max = y[1];
      } else {
        rd_.forbid(s, "y", "for dimension 2 (y = 0)");
      }
    } else {
      src.kind = SourceSpec::Kind::List;
      auto file = rd_.string(s, "file", "a CSV file name (relative to the scene file's folder)");
      if (!file) rd_.missing(s, "file", "a CSV file name (relative to the scene file's folder)");
      namespace fs = std::filesystem;
      fs::path p(*file);
      if (p.is_relative()) p = fs::path(path_).parent_path() / p;
      src.file = p.lexically_normal().string();
      if (!std::ifstream(src.file))
        rd_.fail(Reader::line_of(*rd_.get(s, "file")), "source.file: cannot open '" + src.file + "'");
      listed_ = read_drop_list(src.file, dim());
    }
  }

  // A list source: the file decides the count, radii and species.
  void finish_list_source(const Section& grains) {
    GrainsSpec& g = scene_.grains;
    if (list_source_) {
      const auto rows = static_cast<std::int64_t>(listed_.size());
      if (g.count > rows)
        rd_.bad_value(grains, "count", *rd_.get(grains, "count"),
                      "at most the " + std::to_string(rows) + " rows of " + scene_.source.file);
      if (g.count == 0) g.count = rows;
      listed_.resize(static_cast<std::size_t>(g.count));
      for (auto& c : g.components) c.radius = RadiusSpec{RadiusSpec::Kind::List, 0.0, 0.0, 0.0, {}};
      for (const auto& d : listed_) {
        auto it = std::find_if(g.components.begin(), g.components.end(),
                               [&](const Component& c) { return c.species == d.species; });
        if (it == g.components.end())
          throw SceneError(scene_.source.file + ":" + std::to_string(d.line) + ": species: expected one of the " +
                           std::to_string(g.components.size()) + " species of the scene, got " +
                           std::to_string(d.species));
        it->radius.list.push_back(d.r);
        r_max_ = std::max(r_max_, d.r);
      }
      return;
    }
    for (const auto& c : g.components) r_max_ = std::max(r_max_, largest(c.radius));
  }

  // Where the largest grain is named in messages.
  std::string r_max_text() const { return "the largest grain (r_max = " + fmt(r_max_) + " m)"; }

  void check_container_holds_grains(const Section& s) {
    const Container& c = scene_.container;
    const double d = 2.0 * r_max_;
    auto line = [&](const char* key) { return Reader::line_of(*rd_.get(s, key)); };
    switch (c.kind) {
      case ContainerKind::Open: return;
      case ContainerKind::Drum:
        if (c.radius < r_max_)
          rd_.fail(line("radius"), "container.radius: expected at least " + r_max_text() + ", got " + fmt(c.radius));
        if (dim() == 3 && c.size_y < d)
          rd_.fail(line("length"), "container.length: expected at least the diameter of " + r_max_text() +
                                       ", 2 r_max = " + fmt(d) + " m, got " + fmt(c.size_y));
        return;
      case ContainerKind::Cylinder:
        if (c.radius < r_max_)
          rd_.fail(line("radius"), "container.radius: expected at least " + r_max_text() + ", got " + fmt(c.radius));
        return;
      case ContainerKind::Mesh:
        if (c.size_x < d || c.size_y < d || c.mesh->hi.z() < d)
          rd_.fail(line("file"), "container.file: " + c.mesh->file + ": the mesh is smaller than one grain: expected a "
                                     "bounding box of at least the diameter of " + r_max_text() + ", 2 r_max = " +
                                     fmt(d) + " m, each way, got " + fmt(c.size_x) + " x " + fmt(c.size_y) + " x " +
                                     fmt(c.mesh->hi.z()));
        return;
      case ContainerKind::HeleShaw:
        if (c.gap < d)
          rd_.fail(line("gap"), "container.gap: expected at least the diameter of " + r_max_text() + ", 2 r_max = " +
                                    fmt(d) + " m, got " + fmt(c.gap));
        [[fallthrough]];
      default:
        if (c.size_x < d || (dim() == 3 && c.kind != ContainerKind::HeleShaw && c.size_y < d))
          rd_.fail(line("size"), "container.size: expected widths of at least the diameter of " + r_max_text() +
                                     ", 2 r_max = " + fmt(d) + " m, got " + fmt(c.size_x) +
                                     (dim() == 3 && c.kind != ContainerKind::HeleShaw ? ", " + fmt(c.size_y) : ""));
    }
  }

  // Half-widths of the band of centres where a grain of radius r fits, along x and y (infinite: no wall).
  std::pair<double, double> centre_band(double r) const {
    const Container& c = scene_.container;
    const double inf = std::numeric_limits<double>::infinity();
    switch (c.kind) {
      case ContainerKind::Box:
      case ContainerKind::Mesh: return {c.size_x / 2 - r, c.size_y / 2 - r};
      case ContainerKind::Periodic: return {c.size_x / 2, c.size_y / 2};
      case ContainerKind::HeleShaw: return {c.size_x / 2 - r, c.gap / 2 - r};
      case ContainerKind::Drum: return {c.radius - r, c.periodic_ends ? c.size_y / 2 : c.size_y / 2 - r};
      default: return {inf, inf};
    }
  }

  std::string allowed_text(double r) const {
    if (scene_.container.kind == ContainerKind::Cylinder)
      return "sqrt(x^2 + y^2) <= R - r = " + fmt(scene_.container.radius - r);
    auto [bx, by] = centre_band(r);
    std::string s = "x in [" + fmt(-bx) + ", " + fmt(bx) + "]";
    if (dim() == 3) s += ", y in [" + fmt(-by) + ", " + fmt(by) + "]";
    return s;
  }

  // A disk (3D) or segment (2D) of drop centres of radius `spread` about (x, y).
  bool disk_fits(double x, double y, double spread, double r) const {
    const Container& c = scene_.container;
    if (c.kind == ContainerKind::Cylinder) return std::hypot(x, y) + spread <= c.radius - r;
    auto [bx, by] = centre_band(r);
    // Drops wrap around a periodic axis.
    return std::abs(x) + (wraps_x(c) ? 0.0 : spread) <= bx &&
           (dim() == 2 || std::abs(y) + (wraps_y(c, dim()) ? 0.0 : spread) <= by);
  }

  bool rect_fits(const SourceSpec& s, double r) const {
    const Container& c = scene_.container;
    const double ax = std::max(std::abs(s.x_min), std::abs(s.x_max));
    const double ay = dim() == 3 ? std::max(std::abs(s.y_min), std::abs(s.y_max)) : 0.0;
    if (c.kind == ContainerKind::Cylinder) return std::hypot(ax, ay) <= c.radius - r;
    auto [bx, by] = centre_band(r);
    return ax <= bx && (dim() == 2 || ay <= by);
  }

  // The neighbour grid covers the container's footprint, or on an open floor what the drops reach: a
  // footprint too large for this machine's memory is refused before anything is allocated.
  void check_grid_fits(const Section& container, const Section& source) {
    const Container& c = scene_.container;
    const SourceSpec& src = scene_.source;
    const double cell = 2.0 * r_max_;
    auto refuse_if_too_large = [&](double lx, double ly, const Section& s, const char* key, double value) {
      if (auto why = grid_does_not_fit(dim(), lx, ly, cell, s.path + "." + key, value))
        rd_.fail(rd_.get(s, key) ? Reader::line_of(*rd_.get(s, key)) : s.line, *why);
    };
    switch (c.kind) {
      case ContainerKind::Box:
      case ContainerKind::Periodic:
        refuse_if_too_large(c.size_x, c.size_y, container, "size", std::max(c.size_x, c.size_y));
        return;
      case ContainerKind::Mesh:
        refuse_if_too_large(c.size_x, c.size_y, container, "file", std::max(c.size_x, c.size_y));
        return;
      case ContainerKind::HeleShaw:
        if (c.gap > c.size_x) refuse_if_too_large(c.size_x, c.gap, container, "gap", c.gap);
        else refuse_if_too_large(c.size_x, c.gap, container, "size", c.size_x);
        return;
      case ContainerKind::Cylinder:
        refuse_if_too_large(2.0 * c.radius, 2.0 * c.radius, container, "radius", c.radius);
        return;
      case ContainerKind::Drum:
        if (c.size_y > 2.0 * c.radius) refuse_if_too_large(2.0 * c.radius, c.size_y, container, "length", c.size_y);
        else refuse_if_too_large(2.0 * c.radius, c.size_y, container, "radius", c.radius);
        return;
      case ContainerKind::Open:
        break;
    }
    // Open floor: the grid grows from the origin to every drop position.
    switch (src.kind) {
      case SourceSpec::Kind::Point: {
        const double lx = 2.0 * (std::abs(src.x) + src.scatter), ly = 2.0 * (std::abs(src.y) + src.scatter);
        if (src.scatter >= std::max(std::abs(src.x), std::abs(src.y)))
          refuse_if_too_large(lx, ly, source, "scatter", src.scatter);
        else
          refuse_if_too_large(lx, ly, source, "position", std::max(std::abs(src.x), std::abs(src.y)));
        return;
      }
      case SourceSpec::Kind::Region: {
        const double lx = 2.0 * std::max(std::abs(src.x_min), std::abs(src.x_max));
        const double ly = 2.0 * std::max(std::abs(src.y_min), std::abs(src.y_max));
        if (lx >= ly || dim() == 2) refuse_if_too_large(lx, ly, source, "x", 0.5 * lx);
        else refuse_if_too_large(lx, ly, source, "y", 0.5 * ly);
        return;
      }
      case SourceSpec::Kind::List: {
        double lx = 0.0, ly = 0.0;
        for (const ListedDrop& d : listed_) lx = std::max(lx, 2.0 * std::abs(d.x)), ly = std::max(ly, 2.0 * std::abs(d.y));
        refuse_if_too_large(lx, ly, source, "file", std::max(lx, ly));
        return;
      }
      case SourceSpec::Kind::Rain:
        return;
    }
  }

  void check_source_fits(const Section& s) {
    const SourceSpec& src = scene_.source;
    const std::string kind = to_string(scene_.container.kind);
    switch (src.kind) {
      case SourceSpec::Kind::Point:
        if (!disk_fits(src.x, src.y, src.scatter, r_max_))
          rd_.fail(Reader::line_of(*rd_.get(s, "position")),
                   "source.position: expected drops (position +- scatter " + fmt(src.scatter) + ") that keep " +
                       r_max_text() + " inside the " + kind + " container: " + allowed_text(r_max_) +
                       (src.scatter > 0 && scene_.container.kind != ContainerKind::Periodic
                            ? " minus the scatter"
                            : "") +
                       ", got [" + fmt(src.x) + (dim() == 3 ? ", " + fmt(src.y) : "") + "]");
        return;
      case SourceSpec::Kind::Region:
        if (!rect_fits(src, r_max_)) {
          const bool x_bad = [&] {
            SourceSpec probe = src;
            probe.y_min = probe.y_max = 0.0;
            return !rect_fits(probe, r_max_);
          }();
          const bool both = scene_.container.kind == ContainerKind::Cylinder && !x_bad;  // only the corners
          const std::string key = x_bad || dim() == 2 || both ? "x" : "y";
          auto range = [&](double lo, double hi) { return "[" + fmt(lo) + ", " + fmt(hi) + "]"; };
          const std::string got = both ? "x = " + range(src.x_min, src.x_max) + ", y = " + range(src.y_min, src.y_max)
                                  : key == "x" ? range(src.x_min, src.x_max)
                                               : range(src.y_min, src.y_max);
          rd_.fail(Reader::line_of(*rd_.get(s, key)),
                   (both ? "source.x, source.y" : "source." + key) + ": expected a region that keeps " +
                       r_max_text() + " inside the " + kind + " container: " + allowed_text(r_max_) + ", got " + got);
        }
        return;
      case SourceSpec::Kind::List:
        for (const auto& d : listed_)
          if (!disk_fits(d.x, d.y, 0.0, d.r))
            throw SceneError(src.file + ":" + std::to_string(d.line) + ": expected a drop that keeps its grain (r = " +
                             fmt(d.r) + " m) inside the " + kind + " container: " + allowed_text(d.r) + ", got x = " +
                             fmt(d.x) + (dim() == 3 ? ", y = " + fmt(d.y) : ""));
        return;
      case SourceSpec::Kind::Rain: return;
    }
  }
};

}  // namespace

Scene load_scene(const std::string& path) {
  if (!std::ifstream(path)) throw SceneError(path + ": cannot open the scene file");
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw SceneError(path + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                     std::string(e.description()));
  }
  return SceneParser(path, root).parse();
}

}  // namespace btr
