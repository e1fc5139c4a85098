// Writes the LIGGGHTS inputs: btr.data (read_data, atom_style granular) and in.btr (the script).
// Syntax checked against the LIGGGHTS 3.8 manual (liggghts-doc) and by running liggghts.
#include "coupling/liggghts/liggghts_script.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include "btr/model/number_text.h"
#include "btr/verify/cluster_unwrap.h"
#include "coupling/dem/check_schedule.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/drum_mesh.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/neighbour_skin.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/relax_target.h"
#include "coupling/dem/timestep.h"
#include "coupling/io/atomic_file.h"
#include "coupling/io/mesh_stl.h"
#include "coupling/liggghts/liggghts_compaction.h"
#include "coupling/liggghts/liggghts_tapping.h"

namespace btr {

namespace {

// The simulation box: periodic where the container is, fixed at the walls and, for "open", at the removal
// region; shrink-wrapped upwards for every container.
struct SimulationBox {
  double lo[3], hi[3];
  std::string boundary;
};

SimulationBox make_box(const Grains& grains, int dimension, const Container& c, const RelaxPlan& plan,
                       const TriangleMesh* drum) {
  double lo[3], hi[3], r_max = 0.0;
  for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<double>::infinity(), hi[a] = -lo[a];
  for (const Grain& g : grains) {
    r_max = std::max(r_max, g.r);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], g.x[a] - g.r), hi[a] = std::max(hi[a], g.x[a] + g.r);
  }
  SimulationBox b;
  std::string bx, by;
  auto set = [&](int a, double l, double h) { b.lo[a] = l, b.hi[a] = h; };
  switch (c.kind) {
    case ContainerKind::Open:
      // Fixed lateral bounds at the removal region (a shrink-wrapped box would grow with every runaway
      // grain until binning dominates each step): a grain whose centre leaves it is lost to LIGGGHTS
      // ("thermo_modify lost ignore"), i.e. removed, and counted by the readback.
      bx = "f", by = "f";
      set(0, plan.region_lo[0], plan.region_hi[0]);
      set(1, plan.region_lo[1], plan.region_hi[1]);
      break;
    case ContainerKind::Periodic:
      bx = "p", by = "p";
      set(0, -0.5 * c.size_x, 0.5 * c.size_x);
      set(1, -0.5 * c.size_y, 0.5 * c.size_y);
      break;
    case ContainerKind::Box:
      bx = "f", by = "f";
      set(0, -0.5 * c.size_x, 0.5 * c.size_x);
      set(1, -0.5 * c.size_y, 0.5 * c.size_y);
      break;
    case ContainerKind::HeleShaw:
      bx = "f", by = "f";
      set(0, -0.5 * c.size_x, 0.5 * c.size_x);
      set(1, -0.5 * c.gap, 0.5 * c.gap);
      break;
    case ContainerKind::Cylinder:
      bx = "f", by = "f";
      set(0, -c.radius, c.radius);
      set(1, -c.radius, c.radius);
      break;
    case ContainerKind::Mesh:  // its bounding box, a hair wider so that no mesh node lies on a boundary
      bx = "f", by = "f";
      set(0, -0.5 * c.size_x * (1 + 1e-6), 0.5 * c.size_x * (1 + 1e-6));
      set(1, -0.5 * c.size_y * (1 + 1e-6), 0.5 * c.size_y * (1 + 1e-6));
      break;
    case ContainerKind::Drum:  // its mesh's bounding box, a hair wider (the panels' vertices lie outside R)
      bx = "f", by = c.periodic_ends ? "p" : "f";
      set(0, drum->lo.x() * (1 + 1e-6), drum->hi.x() * (1 + 1e-6));
      if (c.periodic_ends) set(1, -0.5 * c.size_y, 0.5 * c.size_y);
      else set(1, drum->lo.y() * (1 + 1e-6), drum->hi.y() * (1 + 1e-6));
      break;
  }
  if (dimension == 2) {  // one layer of spheres in y = 0: a fixed slab one largest diameter thick
    by = "f";
    set(1, -r_max, r_max);
  }
  // The floor is the lower boundary; the top is shrink-wrapped (grains may rise) from a start above
  // the highest grain.
  set(2, 0.0, hi[2] + 2.0 * r_max);
  if (plan.tap.enabled) b.lo[2] = -2.0 * plan.tap.amplitude;  // the tapped floor goes down to -amplitude
  // A mesh's nodes must lie inside the box (LIGGGHTS refuses a mesh that leaves it).
  if (c.kind == ContainerKind::Mesh) set(2, -1e-6 * c.mesh->hi.z(), std::max(b.hi[2], c.mesh->hi.z() * (1 + 1e-6)));
  if (drum) set(2, drum->lo.z() - 1e-6 * drum->hi.z(), std::max(b.hi[2], drum->hi.z() * (1 + 1e-6)));
  b.boundary = bx + " " + by + " fm";
  return b;
}

// "peratomtype" list and "peratomtypepair" matrix over the types 1..K (components) and K+1 (walls), and with
// `twins` K+2..2K+1: each component's twin (the same material), the type a slab's grains take while the slab is
// compacted frictionless (CompactionPlan::slabs; liggghts_slab_twin_type).
struct TypeTable {
  std::vector<Material> type_material;  // per type, 0-based
  int wall_type = 0;                    // 1-based
  int first_twin = 0;                   // 1-based; 0: no twins
};

TypeTable make_types(const Scene& scene, bool twins = false) {
  TypeTable t;
  for (const Component& c : scene.grains.components) t.type_material.push_back(c.material);
  t.type_material.push_back(wall_material(scene));
  t.wall_type = static_cast<int>(t.type_material.size());
  if (twins) {
    t.first_twin = liggghts_slab_twin_type(scene, 0);
    for (const Component& c : scene.grains.components) t.type_material.push_back(c.material);
  }
  return t;
}

template <class Get>
std::string per_type(const TypeTable& t, Get get) {
  std::string s;
  for (const Material& m : t.type_material) s += " " + g17(get(m));
  return s;
}

// Pair values: unlike species mix (pair_material); a wall contact takes the grain's value, read by
// wall_get (the same getter unless a wall value differs, as gammat's wall_gamma_t).
template <class Get, class WallGet>
double pair_value(const TypeTable& t, int i, int j, Get get, WallGet wall_get) {
  const Material& a = t.type_material[i - 1];
  const Material& b = t.type_material[j - 1];
  if (i == t.wall_type && j == t.wall_type) return wall_get(a);
  if (i == t.wall_type) return wall_get(b);
  if (j == t.wall_type) return wall_get(a);
  return get(pair_material(a, b));
}

template <class Get, class WallGet>
std::string per_type_pair(const TypeTable& t, Get get, WallGet wall_get) {
  const int n = static_cast<int>(t.type_material.size());
  std::string s = " " + std::to_string(n);
  for (int i = 1; i <= n; ++i)
    for (int j = 1; j <= n; ++j) s += " " + g17(pair_value(t, i, j, get, wall_get));
  return s;
}

template <class Get>
std::string per_type_pair(const TypeTable& t, Get get) {
  return per_type_pair(t, get, get);
}

std::string wall_geometry(const DemWall& w) {
  if (w.kind == DemWall::Kind::Cylinder) return "zcylinder " + g17(w.position) + " 0 0";
  static const char* axis_plane[] = {"xplane", "yplane", "zplane"};
  return std::string(axis_plane[w.axis]) + " " + g17(w.position);
}

// Dump columns that give the normal force of each wall on each grain (store_force yes).
std::vector<std::string> wall_force_columns(const DemWall& w) {
  const std::string f = "f_force_" + liggghts_wall_id(w.name);
  if (w.kind == DemWall::Kind::Cylinder) return {f + "[1]", f + "[2]"};
  if (w.kind == DemWall::Kind::Mesh) return {f + "[1]", f + "[2]", f + "[3]"};
  return {f + "[" + std::to_string(w.axis + 1) + "]"};
}

bool has_clusters(const Grains& grains) {
  return std::any_of(grains.begin(), grains.end(), [](const Grain& g) { return g.cluster != 0; });
}

// Image flags that put every member of a cluster at its unwrapped position (btr/verify/cluster_unwrap.h): the
// packing wraps members into the cell one by one, fix rigid unwraps them with these flags.
std::vector<std::array<int, 3>> cluster_images(const Grains& grains, const Scene& scene) {
  const std::vector<Vec3> unwrapped = unwrap_clusters(grains, scene.dimension, scene.container);
  const double period[2] = {scene.container.size_x, scene.container.size_y};
  std::vector<std::array<int, 3>> image(grains.size(), {0, 0, 0});
  for (std::size_t i = 0; i < grains.size(); ++i)
    for (int a = 0; a < 2; ++a) {
      const double shift = unwrapped[i][a] - grains[i].x[a];
      if (shift != 0.0) image[i][a] = static_cast<int>(std::lround(shift / period[a]));
    }
  return image;
}

std::string data_file(const Packing& packing, const Scene& scene, const SimulationBox& box, int n_types) {
  const bool clusters = has_clusters(packing.grains);
  std::ostringstream out;
  out << "LIGGGHTS data file written by btr-dem: packing of scene '" << scene.name << "' (atom_style "
      << (clusters ? "hybrid granular molecular: the molecule is the grain's rigid cluster, 0 for a free grain" : "granular")
      << ")\n\n";
  out << packing.grains.size() << " atoms\n" << n_types << " atom types\n\n";
  static const char* names[] = {"xlo xhi", "ylo yhi", "zlo zhi"};
  for (int a = 0; a < 3; ++a) out << g17(box.lo[a]) << " " << g17(box.hi[a]) << " " << names[a] << "\n";
  out << "\nAtoms\n\n";
  const auto image = clusters ? cluster_images(packing.grains, scene) : std::vector<std::array<int, 3>>{};
  // fix rigid refuses a body of one atom: a cluster of one grain is a free grain (molecule 0).
  std::map<std::int32_t, int> size;
  for (const Grain& g : packing.grains) ++size[g.cluster];
  char row[320];
  for (std::size_t i = 0; i < packing.grains.size(); ++i) {
    const Grain& g = packing.grains[i];
    const int ci = component_index(scene, g.species);
    const double density = scene.grains.components[ci].density;
    if (clusters)  // id type x y z diameter density molecule ix iy iz
      std::snprintf(row, sizeof row, "%zu %d %.17g %.17g %.17g %.17g %.17g %d %d %d %d\n", i + 1, ci + 1, g.x.x(), g.x.y(),
                    g.x.z(), 2.0 * g.r, density, size[g.cluster] > 1 ? static_cast<int>(g.cluster) : 0, image[i][0],
                    image[i][1], image[i][2]);
    else  // id type diameter density x y z
      std::snprintf(row, sizeof row, "%zu %d %.17g %.17g %.17g %.17g %.17g\n", i + 1, ci + 1, 2.0 * g.r, density,
                    g.x.x(), g.x.y(), g.x.z());
    out << row;
  }
  return out.str();
}

// The pour's release (engine_adapter.h, PourRelease): batch k is the group btr_batch (one group at a time:
// LIGGGHTS allows 32), moved down with displace_atoms to its drop height, added to btr_released (which the
// integrator and the height of the pile follow) and run for its steps. bound() is evaluated between runs, so no
// compute has to be current.
std::string liggghts_release(const PourRelease& pour) {
  std::ostringstream s;
  const std::size_t n = pour.batches.size();
  s << "# Release: " << n << " batches; held grains are not integrated (fixed obstacles) until their batch.\n";
  for (std::size_t k = 0; k < n; ++k) {
    const PourRelease::Batch& b = pour.batches[k];
    s << "group btr_batch id <> " << b.first + 1 << " " << b.last + 1 << "\n"
      << "variable btr_lo equal bound(btr_batch,zmin)\n";
    if (k == 0) {
      s << "variable btr_dz equal " << g17(pour.r_max + pour.drop_gap) << "-v_btr_lo\n";
    } else {
      s << "variable btr_dz equal v_btr_top+" << g17(2.0 * pour.r_max + pour.drop_gap) << "-v_btr_lo\n"
        << "if \"${btr_dz} > 0\" then &\n"
        << "  \"print 'BTR-FAILURE the pile reached the held lattice: batch " << k + 1
        << " would move up by ${btr_dz} m'\" quit\n";
    }
    s << "displace_atoms btr_batch move 0 0 ${btr_dz} units box\n"
      << "group btr_released id <> 1 " << b.last + 1 << "\n";
    if (k == 0)
      s << "variable btr_top equal bound(btr_released,zmax)\n"
        << "fix btr_integrate btr_released nve/sphere\n";
    s << "group btr_batch delete\n"
      << "print \"BTR-BATCH " << k + 1 << " " << n << "\"\n"
      << "run " << b.steps << "\n";
  }
  return s.str() + "\n";
}

// A rotating drum's runs (DrumRotation): one run to each snapshot's step, then its positions. The run ends as at
// max_time: the rotation's duration is its length.
std::string liggghts_rotation_runs(const DrumRotation& rot) {
  std::ostringstream s;
  s << "# Rotation: " << rot.snapshot_steps.size() << " snapshots (" << liggghts_snapshot_file(1) << " ...), at steps";
  for (long n : rot.snapshot_steps) s << " " << n;
  s << "\n";
  long done = 0;
  for (std::size_t k = 0; k < rot.snapshot_steps.size(); ++k) {
    s << "run " << rot.snapshot_steps[k] - done << "\n"
      << "if \"${btr_ekin} > ${btr_bound}\" then &\n"
      << "  \"print 'BTR-FAILURE kinetic energy ${btr_ekin} J above the bound ${btr_bound} J at t = ${btr_time} s'\" quit\n"
      << "write_dump all custom " << liggghts_snapshot_file(k + 1) << " id x y z modify sort id format \"%d %.17g %.17g %.17g\"\n"
      << "print \"BTR-SNAPSHOT " << k + 1 << " t = ${btr_time} s\"\n";
    done = rot.snapshot_steps[k];
  }
  s << "print \"BTR-STOP max-time t = ${btr_time} s\"\n";
  return s.str();
}

}  // namespace

std::vector<SpeciesDamping> liggghts_species_damping(const Grains& grains, const Scene& scene, double damping) {
  const bool hooke = scene.relax.model == "hooke";
  const bool stiffness = scene.relax.model == "hooke-stiffness";
  const double v_char = hooke ? hooke_characteristic_velocity(grains) : 0.0;
  std::vector<SpeciesDamping> out;
  for (const Component& c : scene.grains.components) {
    double sum = 0.0;
    long n = 0;
    for (const Grain& g : grains)
      if (g.species == c.species) sum += g.r, ++n;
    if (n == 0) {  // a species with no grain here: any positive value, it damps nothing
      out.push_back({out.empty() ? 1.0 : out.front().gamma, 0.0, 0});
      continue;
    }
    const double r = sum / n, m = grain_mass(r, c.density), r_eff = 0.5 * r;
    const double y_eff = effective_young(c.material, c.material);
    double k;
    if (stiffness) {
      k = c.material.kn;
    } else if (hooke) {
      k = hooke_stiffness(r_eff, 0.5 * m, y_eff, v_char);
    } else {  // Hertz: F = 4/3 E* sqrt(R*) delta^(3/2), k = dF/ddelta at F = m g
      const double delta = std::pow(3.0 * m * kGravity / (4.0 * y_eff * std::sqrt(r_eff)), 2.0 / 3.0);
      k = 2.0 * y_eff * std::sqrt(r_eff * delta);
    }
    out.push_back({2.0 * damping / M_PI * std::sqrt(k * m), m, n});
  }
  if (out.front().gamma <= 0.0) throw std::invalid_argument("damping: non-positive viscous coefficient");
  return out;
}

std::vector<double> liggghts_damping_gamma(const Grains& grains, const Scene& scene, double damping) {
  std::vector<double> gamma;
  for (const SpeciesDamping& d : liggghts_species_damping(grains, scene, damping)) gamma.push_back(d.gamma);
  return gamma;
}

int liggghts_slab_twin_type(const Scene& scene, std::size_t component) {
  return static_cast<int>(scene.grains.components.size() + 2 + component);
}

// Every pair scaled, or with slab twins only the pairs with a twin (the others keep the scene's values).
std::string liggghts_friction_fixes(const Scene& scene, double scale, bool slab_twins) {
  const TypeTable full = make_types(scene, slab_twins);
  const TypeTable scaled = make_types(with_friction_scaled(scene, scale), slab_twins);
  auto matrix = [&](auto get) {
    const int n = static_cast<int>(full.type_material.size());
    std::string s = " " + std::to_string(n);
    for (int i = 1; i <= n; ++i)
      for (int j = 1; j <= n; ++j) {
        const bool scaled_pair = !slab_twins || i >= full.first_twin || j >= full.first_twin;
        s += " " + g17(pair_value(scaled_pair ? scaled : full, i, j, get, get));
      }
    return s;
  };
  std::string s = "fix btr_friction all property/global coefficientFriction peratomtypepair" +
                  matrix([](const Material& m) { return m.friction; }) + "\n";
  if (uses_rolling_friction(scene))  // the pair style's rolling model needs the property, even scaled to 0
    s += "fix btr_rolling all property/global coefficientRollingFriction peratomtypepair" +
         matrix([](const Material& m) { return m.rolling_friction; }) + "\n";
  return s;
}

std::string liggghts_viscous_fix(const std::string& id, const Grains& grains, const Scene& scene, double damping) {
  const std::vector<double> gamma = liggghts_damping_gamma(grains, scene, damping);
  std::string s = "# Damping " + g6(damping) + " (YADE's NewtonIntegrator damping): F = -gamma v with, per species,\n"
                  "# gamma = 2 (damping / pi) sqrt(k m) (k: contact stiffness of a mean grain under its weight),\n"
                  "# the viscous damping that dissipates the same energy per oscillation (coupling/README.md).\n"
                  "fix " + id + " all viscous " + g17(gamma[0]);
  for (std::size_t t = 1; t < gamma.size(); ++t) s += " scale " + std::to_string(t + 1) + " " + g17(gamma[t] / gamma[0]);
  return s + "\n";
}

std::string liggghts_local_damping_fix(const std::string& id, double damping) {
  if (!(damping > 0.0 && damping < 1.0)) throw std::invalid_argument("damping: expected a value in (0, 1)");
  const std::string d = g17(damping);
  std::string s = "# Damping " + g6(damping) + ": YADE's NewtonIntegrator damping itself, F_k -= damping |F_k| sign(v_k),\n"
                  "# on the force of the contacts, walls and gravity (the fixes before this one). Unlike a viscous\n"
                  "# drag it does not hold a free grain at a terminal velocity: a grain left in a pore falls onto its\n"
                  "# supports (coupling/README.md).\n";
  for (const char* k : {"x", "y", "z"})
    s += "variable btr_local_" + std::string(k) + " atom -" + d + "*abs(f" + k + ")*((v" + k + ">0)-(v" + k + "<0))\n";
  return s + "fix " + id + " all addforce v_btr_local_x v_btr_local_y v_btr_local_z\n";
}

std::string liggghts_snapshot_file(std::size_t k) { return "btr_rot_" + std::to_string(k) + ".dump"; }

std::string liggghts_wall_id(const std::string& wall_name) {
  std::string id = "btr_wall_";
  for (char c : wall_name) {
    if (c == '-') id += "lo";
    else if (c == '+') id += "hi";
    else id += c;
  }
  return id;
}

std::vector<std::string> write_liggghts_inputs(const Packing& packing, const Scene& scene, const RelaxPlan& plan,
                                               const std::string& dir) {
  const int dim = scene.dimension;
  const Grains& grains = packing.grains;
  const std::vector<DemWall> walls = dem_walls(scene.container, dim);
  // A drum's surface: the mesh of panels for these grains (drum_mesh.h).
  const std::shared_ptr<const TriangleMesh> drum =
      scene.container.kind == ContainerKind::Drum ? drum_mesh(scene.container, dim, grains) : nullptr;
  const SimulationBox box = make_box(grains, dim, scene.container, plan, drum.get());
  const bool slabs = plan.compaction.enabled && !plan.compaction.slabs.empty();
  const TypeTable types = make_types(scene, slabs);
  const CheckSchedule sched = check_schedule(grains, scene, plan);
  const int n_types = static_cast<int>(types.type_material.size());

  double r_min = std::numeric_limits<double>::infinity(), y_min = r_min, y_max = 0.0, r_max = 0.0;
  for (const Grain& g : grains) r_min = std::min(r_min, g.r), r_max = std::max(r_max, g.r);
  for (const Material& m : types.type_material) y_min = std::min(y_min, m.young), y_max = std::max(y_max, m.young);

  const bool hooke = scene.relax.model == "hooke";
  const bool stiffness = scene.relax.model == "hooke-stiffness";
  const bool rolling = uses_rolling_friction(scene);
  const bool clusters = has_clusters(grains);
  const std::string models = std::string("model ") + (stiffness ? "hooke/stiffness" : hooke ? "hooke" : "hertz") +
                             " tangential history" +
                             (rolling ? " rolling_friction epsd2" : "");

  std::ostringstream s;
  const PourRelease& pour = plan.pour;
  s << "# btr-dem: " << (pour.enabled ? "LIGGGHTS reference pour of the grains" : "LIGGGHTS relaxation of a BTR packing")
    << " of scene '" << scene.name << "'\n"
    << "# " << grains.size() << " grains, " << dim << "D, container " << to_string(scene.container.kind) << "\n"
    << "# Run unchanged with:  liggghts -in " << kLiggghtsScript << "   (or: mpirun -np N liggghts -in "
    << kLiggghtsScript << ")\n"
    << "# Reads " << kLiggghtsData << "; writes " << kLiggghtsLog << ", " << kLiggghtsFinalDump << ", "
    << kLiggghtsContactsDump << ".\n#\n"
    << "# Time step " << g6(plan.timestep) << " s: " << plan.timestep_rule << "\n#\n"
    << "# Stop rule \"" << plan.stop_rule << "\", checked every " << sched.steps_per_check << " steps ("
    << g6(sched.steps_per_check * plan.timestep) << " s) once t >= " << g6(sched.arming_time)
    << " s = sqrt(2 r_min / g):\n";
  if (plan.stop_rule == "kinetic-energy")
    s << "# the translational kinetic energy E = sum m v^2 / 2 and its mean over the last " << sched.steps_per_check
      << " steps are both below\n# " << g6(plan.kinetic_threshold)
      << " J = stop_kinetic_ratio * sum m g d (also armed earlier if the mean was above it once).\n";
  else if (plan.stop_rule == "unbalanced-force")
    s << "# YADE's unbalanced-force ratio (mean |resultant force| over grains / mean |contact force|) is below "
      << g6(plan.unbalanced_threshold) << ".\n";
  else
    s << "# the largest grain displacement over the last window is below " << g6(plan.displacement_threshold)
      << " m = stop_displacement * smallest diameter.\n";
  if (pour.enabled)
    s << "#\n# Pour: the grains start held on a lattice (not integrated); " << pour.batches.size()
      << " batches of consecutive ids are released in turn,\n# each moved down until its lowest centre is "
      << g6(pour.drop_gap) << " m + 2 r_max above the highest released centre, then left to fall;\n"
      << "# the stop rule runs after the last batch (" << g6(pour.release_time) << " s), max_time counts from there.\n";
  s << "# Otherwise the run stops at max_time " << g6(plan.max_time) << " s (" << sched.max_checks
    << " checks). E above " << g6(sched.blowup_bound) << " J (twice the gravitational and\n"
    << "# elastic energy the packing holds) ends the run as a failure (BTR-FAILURE).\n";
  if (plan.has_region)
    s << "#\n# Open floor: the box is fixed laterally at x in [" << g6(plan.region_lo[0]) << ", " << g6(plan.region_hi[0])
      << "], y in [" << g6(plan.region_lo[1]) << ", " << g6(plan.region_hi[1])
      << "] m (the packing's footprint + relax.open_margin largest\n# diameters, and at least the heap of its grains at "
         "relax.open_heap_angle); grains leaving it are lost (removed) and counted.\n";
  if (dim == 2)
    s << "#\n# 2D packing: the disks are relaxed as spheres of the same radii whose centres stay in y = 0\n"
      << "# (fix btr_plane zeroes the y force; contact normals and torques then stay in the x-z plane).\n";
  s << "\n"
    << "atom_style      " << (clusters ? "hybrid granular molecular" : "granular") << "\n"
    << "atom_modify     map array\n"
    << "boundary        " << box.boundary << "\n"
    << "newton          off\n"
    << "communicate     single vel yes\n"
    << "units           si\n"
    // A settled bed split along z puts nearly every grain on one rank: split only laterally.
    << "processors      " << (dim == 2 ? "* 1 1" : "* * 1") << "\n"
    << "read_data       " << kLiggghtsData << "\n";
  if (clusters)
    s << "# Rigid clusters: the grains of one molecule move as one rigid body (fix btr_rigid) and do not\n"
      << "# interact with each other (neigh_modify exclude); free grains (molecule 0) are integrated alone.\n"
      << "group           btr_clustered molecule > 0\n"
      << "group           btr_free subtract all btr_clustered\n";
  const double skin = neighbour_skin(plan, r_min);
  if (skin > kBaseSkinRadii * r_min)
    s << "# Neighbour skin " << g6(skin / r_min) << " r_min (coupling/dem/neighbour_skin.h): at this coarse step a released grain\n"
      << "# would cross half of 0.5 r_min, and so force a rebuild of the pair list, every few steps.\n";
  s << "neighbor        " << g17(skin) << " bin\n"
    << "neigh_modify    delay 0" << (clusters ? " exclude molecule btr_clustered" : "");
  // An open floor's box is mostly empty (the heap's region, a pour's tall release lattice): bins of the whole
  // neighbour cutoff, not LIGGGHTS' default half, clear 8x fewer at each rebuild. Measured on a 2000-grain
  // heap pour in a 156 mm region: 70 s of CPU time with the default bins, 26 s with these.
  if (plan.has_region) s << " binsize " << g17(2.0 * r_max + skin);
  s << "\n";
  // LIGGGHTS refuses Young's moduli outside [5e6, 1e9] Pa in SI units unless told otherwise.
  if (y_min < 5e6) s << "soft_particles  yes\n";
  if (y_max > 1e9) s << "hard_particles  yes\n";

  s << "\n# Materials: types 1.." << types.wall_type - 1 << " = species";
  for (const Component& c : scene.grains.components) s << " " << c.species;
  s << " (in this order), type " << types.wall_type << " = walls (material of species "
    << wall_component(scene).species << ")";
  if (slabs)
    s << ", types " << types.first_twin << ".." << n_types
      << " = the species' twins, the type of a slab's grains while it is compacted";
  s << ".\n# Unlike species: mean restitution and friction; grain-wall: the grain's values.\n";
  s << "fix btr_young all property/global youngsModulus peratomtype"
    << per_type(types, [](const Material& m) { return m.young; }) << "\n";
  s << "fix btr_poisson all property/global poissonsRatio peratomtype"
    << per_type(types, [](const Material& m) { return m.poisson; }) << "\n";
  s << "fix btr_restitution all property/global coefficientRestitution peratomtypepair"
    << per_type_pair(types, [](const Material& m) { return m.restitution; }) << "\n";
  const CompactionPlan& compaction = plan.compaction;
  if (compaction.enabled)
    s << "# Friction scaled by " << g6(compaction.friction_scales.front()) << (slabs ? " for the twins" : "")
      << " for the compaction to the target packing fraction (restored after it, below).\n"
      << liggghts_friction_fixes(scene, compaction.friction_scales.front(), slabs);
  else
    s << liggghts_friction_fixes(scene);
  if (stiffness) {
    // hooke/stiffness (absolute_damping off): F_n = kn delta - m_eff gamman v_n, F_t = -kt xi - m_eff gammat v_t.
    s << "# hooke-stiffness: kn, kt [N/m] and gamman, gammat [1/s, times m_eff]; unlike species: means;\n"
      << "# grain-wall: the grain's kn, kt, gamma_n and wall_gamma_t.\n";
    s << "fix btr_kn all property/global kn peratomtypepair"
      << per_type_pair(types, [](const Material& m) { return m.kn; }) << "\n";
    s << "fix btr_kt all property/global kt peratomtypepair"
      << per_type_pair(types, [](const Material& m) { return m.kt; }) << "\n";
    s << "fix btr_gamman all property/global gamman peratomtypepair"
      << per_type_pair(types, [](const Material& m) { return m.gamma_n; }) << "\n";
    s << "fix btr_gammat all property/global gammat peratomtypepair"
      << per_type_pair(types, [](const Material& m) { return m.gamma_t; },
                       [](const Material& m) { return m.wall_gamma_t; })
      << "\n";
  }
  if (hooke)
    s << "fix btr_vchar all property/global characteristicVelocity scalar "
      << g17(hooke_characteristic_velocity(grains)) << "   # sqrt(2 g d_max)\n";

  s << "\npair_style      gran " << models << "\n"
    << "pair_coeff      * *\n"
    << "timestep        " << g17(plan.timestep) << "\n\n";

  s << "# Walls: exactly the container's.\n";
  namespace fs = std::filesystem;
  std::vector<std::string> written;
  for (const DemWall& w : walls) {
    if (w.kind == DemWall::Kind::Mesh) {
      // The mesh as placed (scaled and shifted like the packing), beside this script.
      const TriangleMesh& mesh = w.triangles ? *w.triangles : *drum;
      write_mesh_stl(mesh, (fs::path(dir) / kLiggghtsMesh).string());
      written.push_back((fs::path(dir) / kLiggghtsMesh).string());
      if (drum)
        s << "# The drum: " << mesh.triangles.size() << " triangles, " << drum_panels(scene.container.radius, r_min)
          << " panels tangent to the cylinder (sagitta below " << g6(kDrumSagittaFraction) << " r_min).\n";
      s << "fix btr_mesh all mesh/surface file " << kLiggghtsMesh << " type " << types.wall_type << "\n"
        << "fix " << liggghts_wall_id(w.name) << " all wall/gran " << models
        << " mesh n_meshes 1 meshes btr_mesh store_force yes\n";
      if (plan.rotation.enabled)
        s << "# Rotation: " << g6(plan.rotation.omega) << " rad/s about the drum's axis, in its sense (lowest line towards +x)\n"
          << "fix btr_rotate all move/mesh mesh btr_mesh rotate origin 0 0 " << g17(plan.rotation.axis_z)
          << " axis 0 -1 0 period " << g17(2.0 * M_PI / plan.rotation.omega) << "\n";
      continue;
    }
    if (plan.tap.enabled && w.name == "floor") {  // a mesh that the taps move (liggghts_tapping.h)
      s << liggghts_tap_floor(box.lo[0], box.hi[0], box.lo[1], box.hi[1], types.wall_type, models,
                              liggghts_wall_id(w.name), dir);
      written.push_back((fs::path(dir) / kLiggghtsTapFloor).string());
      continue;
    }
    s << "fix " << liggghts_wall_id(w.name) << " all wall/gran " << models << " primitive type " << types.wall_type
      << " " << wall_geometry(w) << " store_force yes\n";
  }
  s << "fix btr_gravity all gravity " << g17(kGravity) << " vector 0.0 0.0 -1.0\n";
  if (compaction.enabled && compaction.damping > 0)
    s << liggghts_compaction_drag_fix(grains, scene, compaction.damping);
  else if (!compaction.enabled && plan.damping > 0)
    s << liggghts_viscous_fix("btr_damping", grains, scene, plan.damping);
  if (dim == 2) s << "fix btr_plane all setforce NULL 0.0 NULL   # after the walls and gravity\n";
  if (clusters)
    s << "fix btr_integrate btr_free nve/sphere\n"
      << "fix btr_rigid btr_clustered rigid molecule\n\n";
  else if (!pour.enabled && !slabs)  // a pour, a slab compaction integrate the released grains only
    s << "fix btr_integrate all nve/sphere\n\n";

  // Rotation is left out on purpose: a grain spinning about its contact normal meets no resistance
  // in these contact models (not even with rolling friction) and would keep E up forever without
  // moving; a rolling grain is caught by its translation.
  s << "compute btr_ke all ke\n"
    // Columns: id1 id2 periodic (1-3), force (4-6), normal force (7-9), overlap (10); LIGGGHTS allows one
    // pair/gran/local compute.
    << "compute btr_pairs all pair/gran/local id force force_normal delta\n"
    << "variable btr_ekin equal c_btr_ke\n"
    << "fix btr_kmean all ave/time " << sched.average_every << " " << kAveragedSamples << " "
    << sched.steps_per_check << " v_btr_ekin\n"
    << "variable btr_kmean equal f_btr_kmean\n"
    << "variable btr_time equal time\n"
    << "variable btr_atoms equal atoms\n";

  // YADE's utils.unbalancedForce(): mean over grains of |resultant force| (contacts + gravity; LIGGGHTS'
  // f after all fixes) over the mean over contacts of |contact force|. LIGGGHTS 3.8 has no per-contact
  // magnitude (compute reduce only sums components), so grain-grain contacts enter through the per-atom
  // pair virial: -trace(stress/atom)_i = 1/2 sum_j |x_i - x_j| F_n,ij, and sum_i of that / r_i is 2 sum_c F_n
  // exactly for equal radii (within (r_i + r_j)^2 / (4 r_i r_j) for unequal ones; tangential forces left
  // out). Wall contacts enter exactly (per-atom wall forces). coupling/README.md compares it with YADE's.
  s << "\n# Unbalanced force (YADE's utils.unbalancedForce(); grain-grain normal forces from the pair virial)\n"
    << "variable btr_fres atom sqrt(fx*fx+fy*fy+fz*fz)\n"
    << "compute btr_fres all reduce sum v_btr_fres\n"
    << "compute btr_virial all stress/atom pair\n"
    << "compute btr_radius all property/atom radius\n"
    << "variable btr_fpair atom -(c_btr_virial[1]+c_btr_virial[2]+c_btr_virial[3])/c_btr_radius\n"
    << "compute btr_fpair all reduce sum v_btr_fpair\n"
    << "compute btr_ncon all contact/atom\n"
    << "compute btr_ncon_sum all reduce sum c_btr_ncon\n";
  std::string wall_sum = "0", wall_count = "0";
  for (const DemWall& w : walls) {
    const std::string f = "f_force_" + liggghts_wall_id(w.name), v = "btr_fw_" + liggghts_wall_id(w.name).substr(9);
    s << "variable " << v << " atom sqrt(" << f << "[1]^2+" << f << "[2]^2+" << f << "[3]^2)\n"
      << "variable " << v << "_n atom v_" << v << ">0\n";
    wall_sum += "+c_btr_fwall[" + std::to_string(2 * (&w - walls.data()) + 1) + "]";
    wall_count += "+c_btr_fwall[" + std::to_string(2 * (&w - walls.data()) + 2) + "]";
  }
  s << "compute btr_fwall all reduce sum";
  for (const DemWall& w : walls) {
    const std::string v = "btr_fw_" + liggghts_wall_id(w.name).substr(9);
    s << " v_" << v << " v_" << v << "_n";
  }
  s << "\n"
    << "variable btr_npairs equal c_btr_ncon_sum/2\n"
    << "variable btr_fcontact equal (c_btr_fpair/2+" << wall_sum
    << ")/(v_btr_npairs+" << wall_count << "+1e-300)\n"
    << "variable btr_unbalanced equal c_btr_fres/(atoms+1e-300)/(v_btr_fcontact+1e-300)\n";

  const bool by_displacement = plan.stop_rule == "displacement";
  if (by_displacement) {
    // The reference positions are stored every check window by btr_dref, after btr_dwin has read the
    // displacement from the previous reference (fixes run in the order they are defined).
    s << "\n# Displacement over each check window (unwrapped positions)\n"
      << "compute btr_xu all property/atom xu yu zu\n"
      << "variable btr_disp atom sqrt((c_btr_xu[1]-f_btr_dref[1])^2+(c_btr_xu[2]-f_btr_dref[2])^2+"
         "(c_btr_xu[3]-f_btr_dref[3])^2)\n"
      << "compute btr_dmax all reduce max v_btr_disp\n"
      << "fix btr_dwin all ave/time " << sched.steps_per_check << " 1 " << sched.steps_per_check << " c_btr_dmax\n"
      << "fix btr_dref all store/state " << sched.steps_per_check << " xu yu zu\n"
      << "variable btr_dmax equal f_btr_dwin\n";
  }

  // The thermo output at the end of each chunk evaluates every compute the checks use (LIGGGHTS refuses a
  // compute between runs that was not invoked on the last step).
  if (compaction.enabled) s << liggghts_compaction_setup(compaction, dim);
  // A rotation's runs end between the mean's windows, where f_btr_kmean cannot be read: the column repeats E.
  s << "\nthermo_style    custom step time v_btr_ekin " << (plan.rotation.enabled ? "v_btr_ekin" : "f_btr_kmean")
    << " v_btr_unbalanced" << (by_displacement ? " v_btr_dmax" : "")
    << (compaction.enabled ? " v_btr_phi" : "") << "\n"
    << "thermo_modify   norm no lost " << (plan.has_region ? "ignore" : "error") << " format float %.17g\n"
    << "thermo          " << sched.steps_per_check << "\n\n";

  std::string condition, value;
  if (plan.stop_rule == "kinetic-energy") {
    condition = "(${btr_armed} > 0 || ${btr_time} >= ${btr_tarm}) && ${btr_kmean} < ${btr_threshold} && "
                "${btr_ekin} < ${btr_threshold}";
    value = "${btr_ekin}";
  } else if (plan.stop_rule == "unbalanced-force") {
    condition = "${btr_time} >= ${btr_tarm} && ${btr_unbalanced} < ${btr_threshold}";
    value = "${btr_unbalanced}";
  } else {
    condition = "${btr_time} >= ${btr_tarm} && ${btr_dmax} < ${btr_threshold}";
    value = "${btr_dmax}";
  }
  s << "variable btr_threshold equal " << g17(stop_threshold(plan)) << "\n"
    << "variable btr_kinetic equal " << g17(plan.kinetic_threshold) << "\n"
    << "variable btr_bound equal " << g17(sched.blowup_bound) << "\n"
    << "variable btr_tarm equal " << g17(sched.arming_time) << "\n"
    << "variable btr_armed equal 0\n"
    << "print \"BTR time step " << g17(plan.timestep) << " s: " << plan.timestep_rule << "\"\n\n";
  if (pour.enabled) s << liggghts_release(pour);
  // After a compaction the settle's damping is a fix addforce of atom-style variables, which needs set-up runs.
  const bool local_damping = compaction.enabled && plan.damping > 0;
  if (compaction.enabled)
    s << liggghts_compaction_loop(compaction, scene, plan.damping, plan.timestep, stop_arming_time(grains));
  std::vector<std::string> cols{"id", "x", "y", "z", "vx", "vy", "vz"};
  for (const DemWall& w : walls)
    for (const std::string& c : wall_force_columns(w)) cols.push_back(c);
  std::string names, format = "%d";
  for (const std::string& c : cols) names += " " + c;
  for (std::size_t i = 1; i < cols.size(); ++i) format += " %.17g";
  if (plan.tap.enabled)  // the taps replace the stop rule (liggghts_tapping.h)
    s << liggghts_tap_loop(plan.tap, names, format);
  else if (plan.rotation.enabled)  // the turns replace it too (drum_rotation.h)
    s << liggghts_rotation_runs(plan.rotation);
  else
    s << "label btr_loop\n"
    << "variable btr_check loop " << sched.max_checks << "\n"
    << "run " << sched.steps_per_check << (local_damping ? " post no\n" : " pre no post no\n")
    << "if \"${btr_ekin} > ${btr_bound}\" then &\n"
    << "  \"print 'BTR-FAILURE kinetic energy ${btr_ekin} J above the bound ${btr_bound} J at t = ${btr_time} s'\" "
       "quit\n"
    << "if \"${btr_kmean} >= ${btr_kinetic}\" then \"variable btr_armed equal 1\"\n"
    << "if \"" << condition << "\" then \"jump SELF btr_converged\"\n"
    << "next btr_check\n"
    << "jump SELF btr_loop\n"
    << "print \"BTR-STOP max-time t = ${btr_time} s\"\n"
    << "jump SELF btr_output\n"
    << "label btr_converged\n"
    << "print \"BTR-STOP " << plan.stop_rule << " t = ${btr_time} s value = " << value << "\"\n"
    << "label btr_output\n";
  s << "print \"BTR-FINAL unbalanced-force ${btr_unbalanced} atoms ${btr_atoms}\"\n\n";

  s << "write_dump all custom " << kLiggghtsFinalDump << names << " modify sort id format \"" << format << "\"\n"
    << "write_dump all local " << kLiggghtsContactsDump
    << " c_btr_pairs[1] c_btr_pairs[2] c_btr_pairs[3] c_btr_pairs[7] c_btr_pairs[8] c_btr_pairs[9] c_btr_pairs[10]"
    << " modify format \"%.0f %.0f %.0f %.17g %.17g %.17g %.17g\"\n";

  const std::string data_path = (fs::path(dir) / kLiggghtsData).string();
  const std::string script_path = (fs::path(dir) / kLiggghtsScript).string();
  write_text_file(data_path, data_file(packing, scene, box, n_types));
  write_text_file(script_path, s.str());
  written.insert(written.begin(), {script_path, data_path});
  return written;
}

}  // namespace btr
