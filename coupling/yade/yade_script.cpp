// Writes the YADE script of a relaxation: a header saying how to run it and what it does, the shared Python
// functions (yade_library.py), then the scene: numbers of the run, materials and pair values,
// the grains, and exactly the walls of the container (dem_walls.h).
//
// Matching the LIGGGHTS run (liggghts_script.cpp) as closely as YADE allows:
//  - same stop rule and schedule (check_schedule): checks, averaging window, arming time, blow-up bound;
//  - same pair values (materials.h): unlike species take the mean restitution and friction, a grain-wall
//    contact the grain's; walls have the first species' material;
//  - "hertz": Hertz-Mindlin with Tsuji's restitution damping, the formulas of LIGGGHTS' model hertz;
//  - "hooke": YADE's linear law (linear spring + Coulomb slider, i.e. Cundall-Strack, plus a normal
//    dashpot solved per contact for the restitution), its Young's modulus chosen so that kn equals
//    LIGGGHTS' model hooke k_n for two grains of a species (both are proportional to the radius), and
//    ks = kn as in LIGGGHTS. YADE's own choice kn = E r would be ~10x stiffer and unstable at the
//    contact-time step;
//  - YADE's Ip2 functors see a wall as a sphere of the grain's radius (R* = r/2, where LIGGGHTS has r):
//    the walls' Young's modulus is raised so that a first-species grain meets a wall with LIGGGHTS' stiffness.
#include "coupling/yade/yade_script.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "btr/model/number_text.h"
#include "coupling/dem/check_schedule.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/drum_mesh.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/neighbour_skin.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/dem/timestep.h"

namespace btr {
namespace {

// Round-trip decimal form of a double, a valid Python literal.
std::string num(double v) {
  if (!std::isfinite(v)) throw std::invalid_argument("yade script: non-finite number " + std::to_string(v));
  return g17(v);
}

std::string py_string(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '\\' || c == '"') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

[[noreturn]] void refuse(const Scene& scene, const std::string& field, const std::string& what) {
  throw std::invalid_argument((scene.file.empty() ? "scene '" + scene.name + "'" : scene.file) + ": " + field + ": " +
                              what);
}

void check_material(const Scene& scene, const Component& c) {
  const std::string where = "species " + std::to_string(c.species) + " material";
  const Material& m = c.material;
  if (!(m.young > 0)) refuse(scene, where + ".young", "must be > 0 Pa, got " + num(m.young));
  if (!(m.poisson >= 0 && m.poisson < 0.5)) refuse(scene, where + ".poisson", "must be in [0, 0.5), got " + num(m.poisson));
  // en = 0 has no finite damping coefficient (log 0); en = 1 is elastic.
  if (!(m.restitution > 0 && m.restitution <= 1))
    refuse(scene, where + ".restitution", "must be in (0, 1] for YADE's en, got " + num(m.restitution));
  if (!(m.friction >= 0)) refuse(scene, where + ".friction", "must be >= 0, got " + num(m.friction));
  if (!(m.rolling_friction >= 0)) refuse(scene, where + ".rolling_friction", "must be >= 0, got " + num(m.rolling_friction));
  if (!(c.density > 0)) refuse(scene, "species " + std::to_string(c.species) + " density", "must be > 0");
}

std::string label(const Component& c) { return "species" + std::to_string(c.species); }

// YADE Young's modulus of the linear law for a material: kn = E r for two grains of radius r, set equal to
// LIGGGHTS' k_n for them (proportional to r, so any r gives the same E).
double hooke_young(const Material& m, double density, double velocity) {
  const double r = 1e-3;
  const double m_eff = 0.5 * grain_mass(r, density);
  return hooke_stiffness(0.5 * r, m_eff, effective_young(m, m), velocity) / r;
}

// Factor on the walls' Young's modulus so that YADE's wall contact (seen as two spheres of radius r) has the
// stiffness LIGGGHTS gives a grain of the walls' own material against a wall.
//  Hertz: kn ~ E* sqrt(R*), LIGGGHTS R* = r, YADE r/2: E*_yade = sqrt(2) E*  ->  E_wall = E / (sqrt(2) - 1).
//  Hooke: LIGGGHTS k ~ R*^(2/5) m*^(1/5) is 2^(3/5) = c times the like-pair value (R* = r, m* = m);
//         YADE 1 / kn = 1/(2 E_wall r) + 1/(2 E r) = 1/(c E r)  ->  E_wall = c E / (2 - c).
double wall_young_factor(bool hooke) {
  if (!hooke) return 1.0 / (std::sqrt(2.0) - 1.0);
  const double c = std::pow(2.0, 0.6);
  return c / (2.0 - c);
}

// Panels of the facet cylinder: enough that the gap between a panel edge and the true cylinder,
// R (1/cos(pi/n) - 1), is at most 0.5% of the smallest radius; at least 64.
int cylinder_segments(double radius, double r_min) {
  const double tol = 0.005 * r_min;
  int n = 64;
  while (n < 100000 && radius * (1.0 / std::cos(M_PI / n) - 1.0) > tol) n = static_cast<int>(std::ceil(n * 1.05));
  return n;
}

struct PackingStats {
  double r_min = std::numeric_limits<double>::infinity();
  double r_max = 0.0;
  double r_mean = 0.0;
  double top = 0.0;  // highest z + r
};

PackingStats stats_of(const Packing& packing) {
  PackingStats s;
  for (const Grain& g : packing.grains) {
    s.r_min = std::min(s.r_min, g.r);
    s.r_max = std::max(s.r_max, g.r);
    s.r_mean += g.r;
    s.top = std::max(s.top, g.x.z() + g.r);
  }
  s.r_mean /= static_cast<double>(packing.grains.size());
  return s;
}

// Rolling resistance for the Hertz-Mindlin moment law, which takes one bending stiffness krot and one
// plastic coefficient eta for every contact (no rolling dashpot, as LIGGGHTS' epsd2): the moment is capped
// at eta (r1 + r2)/2 Fn, so eta = mu_r / 2 gives epsd2's cap mu_r R* Fn for equal radii; krot = kt R*^2 as
// epsd2, with kt the Mindlin tangential stiffness of two mean grains of the first species pressed by one
// grain's weight (YADE's krot is a constant, epsd2's follows the overlap).
std::string rolling_call(const Scene& scene, const PackingStats& st, double mu_r) {
  const Component& c = scene.grains.components.front();
  const Material& m = c.material;
  const double r_star = 0.5 * st.r_mean;
  const double kno = 4.0 / 3.0 * effective_young(m, m) * std::sqrt(r_star);
  const double overlap = std::pow(grain_mass(st.r_mean, c.density) * kGravity / kno, 2.0 / 3.0);
  const double shear_modulus = m.young / (2.0 * (1.0 + m.poisson));
  const double kt = 4.0 * shear_modulus * std::sqrt(r_star * overlap) / (2.0 - m.poisson);
  return "    set_rolling(krot=" + num(kt * r_star * r_star) + ", eta=" + num(0.5 * mu_r) + ")  # rolling friction " +
         num(mu_r) + ": krot = kt R*^2, cap mu_r R* Fn\n";
}

// How far YADE's collider extends each grain's bounding box (its verlet distance): the LIGGGHTS script's
// neighbour skin (neighbour_skin.h: YADE's default 0.5 r_min, more for a pour at a coarse step), unless a
// periodic cell needs less. YADE keeps one
// interaction per pair, with one periodic image chosen by the collider, and for a box spanning more than
// half the period along an axis (allowed here because of the floor box) it silently takes image 0 along
// that axis: two grains touching across the boundary then never meet, and one falls through the other.
// So each grain's box, 2 (r_max + d), must stay below half of every lateral period: d = 0.9 (L/4 - r_max)
// when that is smaller; a period of 4 r_max or less, where a grain can touch two images of another at
// once, is refused.
double verlet_distance(const Scene& scene, double skin, const PackingStats& st, double period_x, double period_y) {
  if (scene.container.kind != ContainerKind::Periodic) return skin;
  const double period = std::min(period_x, period_y);
  const double room = 0.25 * period - st.r_max;
  if (!(room > 0.0))
    refuse(scene, "container.size",
           "YADE needs a period above 4 largest radii (" + num(4.0 * st.r_max) + " m) to give each pair one periodic "
           "image; got " + num(period) + " m");
  return std::min(skin, 0.9 * room);
}

// COMPACTION's slabs (CompactionPlan::slabs; nothing for the bed at once): per slab its first and last packing ids
// (1-based, as POUR's batches) and its window's z bounds and measure.
std::string slabs_entry(const CompactionPlan& c) {
  if (c.slabs.empty()) return "";
  std::string rows;
  for (std::size_t k = 0; k < c.slabs.size(); ++k) {
    const CompactionPlan::Slab& s = c.slabs[k];
    rows += "\n        (" + std::to_string(k == 0 ? 1 : c.slabs[k - 1].last + 2) + ", " + std::to_string(s.last + 1) +
            ", " + num(s.window_lo_z) + ", " + num(s.window_hi_z) + ", " + num(s.window_measure) + "),";
  }
  return ",\n    slabs=[  # compacted in turn from the floor up (class Compaction): (first id, last id, window z "
         "from, to [m], measure)" + rows + "]";
}

// COMPACTION: None, or the plan's compaction to a target packing fraction (CompactionPlan), checked at every
// sample of the stop rule (every AVERAGE_EVERY steps).
std::string compaction_constant(const RelaxPlan& plan, const Grains& grains, const CheckSchedule& sched) {
  const CompactionPlan& c = plan.compaction;
  if (!c.enabled) return "COMPACTION = None  # no target packing fraction\n";
  std::string scales;
  for (double f : c.friction_scales) scales += (scales.empty() ? "" : ", ") + num(f);
  const long samples = std::max(1L, static_cast<long>(std::ceil(plan.max_time / c.timestep / sched.average_every)));
  auto vec = [](const Vec3& v) { return "(" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + ")"; };
  return "COMPACTION = dict(  # btr relax --target-phi: compaction before the stop rule (class Compaction)\n"
         "    target=" + num(c.target) + ", friction_scales=[" + scales + "], damping=" + num(c.damping) + ",\n"
         "    timestep=" + num(c.timestep) + ",  # s (fraction " + num(c.timestep_fraction) + "; the settle's: TIMESTEP)\n"
         "    slab=" + std::string(c.slab ? "True" : "False") + ", window_lo=" + vec(c.window_lo) + ", window_hi=" +
         vec(c.window_hi) + ", window_measure=" + num(c.window_measure) + ",\n"
         "    rest_kinetic=" + num(c.rest_kinetic) + ", max_samples_per_scale=" + std::to_string(samples) +
         ", arming=" + num(stop_arming_time(grains)) + slabs_entry(c) + ")\n";
}

// POUR: None, or a reference pour's release (engine_adapter.h, PourRelease): batches as (first id, last id,
// steps), the drop gap and the largest radius; yade_library.py's release() runs it before the stop rule.
std::string pour_constant(const RelaxPlan& plan) {
  const PourRelease& p = plan.pour;
  if (!p.enabled) return "POUR = None  # not a pour\n";
  std::string batches;
  for (const PourRelease::Batch& b : p.batches)
    batches += (batches.empty() ? "" : ", ") + std::string("(") + std::to_string(b.first + 1) + ", " +
               std::to_string(b.last + 1) + ", " + std::to_string(b.steps) + ")";
  return "POUR = dict(  # btr pour: the grains start held on the lattice; release() frees them batch by batch\n"
         "    batches=[" + batches + "],  # (first id, last id, steps)\n"
         "    drop_gap=" + num(p.drop_gap) + ", r_max=" + num(p.r_max) + ")  # m; the settle's max time follows the release (" +
         num(p.release_time) + " s)\n";
}

std::string rotation_constant(const RelaxPlan& plan) {
  const DrumRotation& r = plan.rotation;
  if (!r.enabled) return "ROTATION = None  # not a rotating drum\n";
  std::string steps;
  for (long n : r.snapshot_steps) steps += (steps.empty() ? "" : ", ") + std::to_string(n);
  return "ROTATION = dict(  # btr drum --engine yade: the drum's facets turn about its axis (along y through x = 0,\n"
         "    # z = axis_z) at omega rad/s, lowest line towards +x (about -y); positions written at each step count\n"
         "    omega=" + num(r.omega) + ", axis_z=" + num(r.axis_z) + ", snapshot_steps=[" + steps + "])\n";
}

// TAP: None, or the plan's tapping (TapSchedule, tap_schedule.h); yade_library.py's tap() runs it instead of the
// stop rule.
std::string tap_constant(const RelaxPlan& plan) {
  const TapSchedule& t = plan.tap;
  if (!t.enabled) return "TAP = None  # not tapped\n";
  return "TAP = dict(  # btr shake --engine yade: per tap the floor moves by z = amplitude sin(2 pi frequency t) for one\n"
         "    # period (steps_per_tap steps of TIMESTEP), then the bed rests (windows of steps_per_check steps)\n"
         "    taps=" + std::to_string(t.taps) + ", amplitude=" + num(t.amplitude) + ", frequency=" + num(t.frequency) +
         ", gamma=" + num(t.gamma) + ",\n    steps_per_tap=" + std::to_string(t.steps_per_tap) +
         ", steps_per_check=" + std::to_string(t.steps_per_check) + ", max_rest_checks=" +
         std::to_string(t.max_rest_checks) + ")\n";
}

const char* kHeader = R"(#
# Run it in one of two ways (every file is read from and written to this script's folder):
#   PYTHONPATH=/usr/lib/x86_64-linux-gnu/yade-double/py OMP_NUM_THREADS=1 /usr/bin/python3 relax_yade.py
#       what `btr relax` does: importing the yade module opens no network service;
#   yade -n -x -j 4 relax_yade.py
#       e.g. on a cluster; the launcher also opens a TCP Python console (port 9000+) and an XML-RPC
#       server (port 21000+).
# Input: yade_packing.csv (id,x,y,z,radius,species[,cluster]; the grains of a cluster > 0 form one clump,
# a rigid body, O.bodies.appendClumped; in a periodic cell a cluster's members are unwrapped, together across
# the boundary). Outputs: yade_final.csv (id,x,y,z,vx,vy,vz; clump members too; wrapped into a periodic cell),
# yade_kinetic.csv (time,kinetic_energy), yade_contacts.csv (i,j,fn,overlap; j = 0 for a wall), yade.log,
# and, written last, yade_status.json (status "ok" or "failed", stop reason, time, steps, message).
#
# Contact law: "hertz" is Hertz-Mindlin (Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin);
# "hooke" is YADE's linear law (Ip2_ViscElMat_ViscElMat_ViscElPhys, Law2_ScGeom_ViscElPhys_Basic: linear
# spring and Coulomb slider as in Cundall-Strack, plus a normal dashpot), with kn equal to LIGGGHTS' model
# hooke k_n for like grains and ks = kn. Rolling friction only if the scene sets it (Hertz-Mindlin moment law).
# Damping: viscous, from the pair's restitution coefficient (the Ip2 functors' en MatchMaker); NewtonIntegrator
# damping only if DAMPING > 0 (scene relax.damping or `btr relax --damping`; off by default).
# Pairs: unlike species take the mean restitution and friction, a grain-wall contact the grain's values.
# Walls: the first species' material, Young's modulus raised because YADE sees a wall as a sphere of the
# grain's radius; planes are infinite (utils.wall); a periodic floor is a thin box wider than the cell.
# Stop rules (the LIGGGHTS script's), checked every STEPS_PER_CHECK steps: STOP_RULE "kinetic-energy" (the
# translational kinetic energy E and its mean over the last STEPS_PER_CHECK steps below KINETIC_THRESHOLD,
# once armed: the mean was above it once, or t >= ARMING_TIME), "unbalanced-force" (utils.unbalancedForce()
# below UNBALANCED_THRESHOLD) or "displacement" (largest displacement since the last check below
# DISPLACEMENT_THRESHOLD), each from t >= ARMING_TIME; else after MAX_CHECKS checks (max-time).
# Open floor (REGION): grains whose centre left the region are erased at each check and listed as removed.
# A reference pour (POUR, `btr pour`): every grain starts held on a lattice (all degrees of freedom blocked);
# batches of ids are moved down to a small drop height above the pile and freed one after the other, then the
# stop rule runs (ARMING_TIME lies after the release; MAX_CHECKS counts from its end).
# Tapping (TAP, `btr shake --engine yade`) replaces the stop rule: a HarmonicMotionEngine moves the floor body by
# one period of a sine per tap, then the bed rests; yade_tap_K.csv (id,x,y,z) and yade_taps.json after each tap.
# The rule runs inside YADE's loop (a PyRunner every AVERAGE_EVERY steps), which pauses YADE when it decides.
# A run fails on NaN, E above KINETIC_BOUND (checked at every sample), lost bodies, or a grain below the floor.
# Periodic cells: YADE gives a pair one periodic image, chosen by the collider, and only while each grain's
# bounding box (diameter + 2 VERLET_DIST) is below half the period; VERLET_DIST is chosen for that.
# 2D: disks in the x-z plane are YADE spheres (sphere masses) with blockedDOFs "yXZ": no motion along y,
# rotation about y only.
)";

}  // namespace

std::string yade_script(const Packing& packing, const Scene& scene, const RelaxPlan& plan) {
  const std::string& model = scene.relax.model;
  if (model == "hooke-stiffness")
    refuse(scene, "relax.model",
           "\"hooke-stiffness\" is LIGGGHTS-only: YADE's linear law (ViscElMat) takes an absolute damping cn [N s/m]\n"
           "per material and mixes kn in series, while this model's gamma_n is a rate multiplied by each contact's\n"
           "effective mass and its grain-wall gamma_t differs from the grain-grain one; no YADE material reproduces\n"
           "both for every pair. Use engine = \"liggghts\", or relax.model = \"hooke\" with YADE");
  if (model != "hertz" && model != "hooke") refuse(scene, "relax.model", "expected \"hertz\" or \"hooke\", got \"" + model + "\"");
  if (scene.dimension != 2 && scene.dimension != 3) refuse(scene, "scene.dimension", "expected 2 or 3");
  if (packing.grains.empty()) refuse(scene, "packing", "has no grains to relax");
  if (scene.grains.components.empty()) refuse(scene, "grains", "has no component (no material)");
  if (!(plan.timestep > 0) || !(plan.max_time > 0) || !(plan.kinetic_threshold > 0))
    throw std::invalid_argument("yade script: time step, max time and kinetic threshold must be > 0");
  const bool hooke = model == "hooke";
  const auto& comps = scene.grains.components;
  for (const Component& c : comps) check_material(scene, c);
  for (const Grain& g : packing.grains) component_index(scene, g.species);  // throws for an unknown species

  // YADE's Hertz-Mindlin moment law takes one rolling friction for all contacts; the linear law has none.
  const double rolling = comps.front().material.rolling_friction;
  for (const Component& c : comps) {
    if (c.material.rolling_friction > 0 && hooke)
      refuse(scene, "material.rolling_friction",
             "YADE's linear law (Law2_ScGeom_ViscElPhys_Basic) has no Coulomb rolling friction; use model \"hertz\"");
    if (c.material.rolling_friction != rolling)
      refuse(scene, "material.rolling_friction",
             "YADE's Hertz-Mindlin moment law takes one rolling friction for all species; they differ here");
  }

  std::vector<DemWall> walls;
  try {
    walls = dem_walls(scene.container, scene.dimension);
  } catch (const std::runtime_error& e) {
    refuse(scene, "container", e.what());
  }
  const PackingStats st = stats_of(packing);
  const Container& box = scene.container;
  // Periodic cell: 2D gets a y period wide enough that no disk meets its own image; z is far above the packing.
  const double period_y = scene.dimension == 2 ? 8.0 * st.r_max : box.size_y;
  const double period_z = std::max(2.0 * box.height, 4.0 * st.top);
  const double skin = neighbour_skin(plan, st.r_min);
  const double verlet = verlet_distance(scene, skin, st, box.size_x, period_y);
  const CheckSchedule sched = check_schedule(packing.grains, scene, plan);
  const double velocity = hooke ? hooke_characteristic_velocity(packing.grains) : 0.0;

  std::ostringstream out;
  out << "#!/usr/bin/python3\n"
      << (plan.pour.enabled  ? "# YADE reference pour of the grains of scene "
          : plan.tap.enabled ? "# YADE tapping of the packing of scene "
                             : "# YADE relaxation of the packing of scene ") << py_string(scene.name) << " (" << py_string(scene.file)
      << "), written by btr " << BTR_VERSION << " (coupling/yade/yade_script.cpp).\n"
      << kHeader << yade_script_library();
  out << "\n\n# " << std::string(100, '-') << "\n# The scene (generated)\n"
      << "MODEL = " << py_string(model) << "\n"
      << "DIMENSION = " << scene.dimension << "\n"
      << "GRAVITY = " << num(kGravity) << "  # m/s^2, along -z\n"
      << "TIMESTEP = " << num(plan.timestep) << "  # s\n"
      << "TIMESTEP_RULE = " << py_string(plan.timestep_rule) << "\n"
      << "KINETIC_THRESHOLD = " << num(plan.kinetic_threshold) << "  # J, stop_kinetic_ratio * sum m g d\n"
      << "KINETIC_BOUND = " << num(sched.blowup_bound) << "  # J, twice the gravitational + elastic energy\n"
      << "STEPS_PER_CHECK = " << sched.steps_per_check << "\n"
      << "AVERAGE_EVERY = " << sched.average_every << "  # steps between samples of the mean\n"
      << "MAX_CHECKS = " << sched.max_checks << "  # max_time " << num(plan.max_time) << " s\n"
      << "ARMING_TIME = " << num(sched.arming_time)
      << (plan.arming_time > 0.0 ? "  # s, pre-loaded start: sqrt(2 delta_max / g)\n" : "  # s, sqrt(2 r_min / g)\n")
      << "STOP_RULE = " << py_string(plan.stop_rule) << "\n"
      << "UNBALANCED_THRESHOLD = " << num(plan.unbalanced_threshold) << "  # utils.unbalancedForce()\n"
      << "DISPLACEMENT_THRESHOLD = " << num(plan.displacement_threshold)
      << "  # m per check window, stop_displacement * smallest diameter\n"
      << "DAMPING = " << num(plan.damping) << "  # NewtonIntegrator damping (0 = off)\n"
      << "REGION = "
      << (plan.has_region ? "(" + num(plan.region_lo[0]) + ", " + num(plan.region_hi[0]) + ", " + num(plan.region_lo[1]) +
                                ", " + num(plan.region_hi[1]) + ")  # open floor: x0, x1, y0, y1 [m]; grains leaving it are removed"
                          : std::string("None  # no removal region (not an open floor)"))
      << "\n"
      << compaction_constant(plan, packing.grains, sched) << pour_constant(plan) << rotation_constant(plan) << tap_constant(plan)
      << "VERLET_DIST = " << num(verlet) << "  # m, collider's bounding-box margin: "
      << (verlet < skin ? "below half the period with the largest grain"
                                                         : "the neighbour skin, " + num(verlet / st.r_min) + " r_min") << "\n\n\n"
      << "def scene():\n";

  // Materials: elastic constants and density per species, then the walls'.
  if (hooke)
    out << "    # young: kn = young * r for two grains of radius r equals LIGGGHTS' model hooke k_n with the\n"
        << "    # characteristic velocity " << num(velocity) << " m/s; poisson = ks/kn = 1 (LIGGGHTS: kt = kn)\n";
  auto young_of = [&](const Component& c) {
    return hooke ? hooke_young(c.material, c.density, velocity) : c.material.young;
  };
  for (const Component& c : comps)
    out << "    add_material(" << py_string(label(c)) << ", young=" << num(young_of(c))
        << ", poisson=" << num(hooke ? 1.0 : c.material.poisson) << ", density=" << num(c.density)
        << ", species=" << c.species << ")\n";
  const Component& wall = wall_component(scene);
  out << "    add_material(\"walls\", young=" << num(young_of(wall) * wall_young_factor(hooke))
      << ", poisson=" << num(hooke ? 1.0 : wall.material.poisson) << ", density=" << num(wall.density)
      << ")  # species " << wall.species << "'s material, stiffer (YADE sees a wall as a sphere)\n";
  for (std::size_t a = 0; a < comps.size(); ++a) {
    for (std::size_t b = a; b < comps.size(); ++b) {
      const Material p = pair_material(comps[a].material, comps[b].material);
      out << "    pair(" << py_string(label(comps[a])) << ", " << py_string(label(comps[b]))
          << ", restitution=" << num(p.restitution) << ", friction=" << num(p.friction) << ")\n";
    }
    out << "    pair(" << py_string(label(comps[a])) << ", \"walls\", restitution="
        << num(comps[a].material.restitution) << ", friction=" << num(comps[a].material.friction) << ")\n";
  }
  if (rolling > 0) out << rolling_call(scene, st, rolling);

  if (box.kind == ContainerKind::Periodic) {
    out << "    periodic_cell(" << num(box.size_x) << ", " << num(period_y) << ", " << num(period_z)
        << ")  # the container's period" << (scene.dimension == 2 ? " in x" : "s in x and y")
        << "; z: 4x the packing top\n";
  }
  out << "    add_grains(" << py_string(yade_files::kPacking) << ")\n";
  for (const DemWall& w : walls) {
    if (w.kind == DemWall::Kind::Plane) {
      out << "    add_plane(axis=" << w.axis << ", position=" << num(w.position) << ")  # " << w.name << "\n";
    } else if (w.kind == DemWall::Kind::Mesh) {
      if (w.triangles)
        out << "    add_mesh(" << py_string(yade_files::kMesh) << ")  # the container's " << w.triangles->triangles.size()
            << " triangles, from " << py_string(w.triangles->file) << "\n";
      else  // a drum: its panels for these grains (drum_mesh.h), written beside the script by the adapter
        out << "    add_mesh(" << py_string(yade_files::kMesh) << ")  # the drum's "
            << drum_mesh(box, scene.dimension, packing.grains)->triangles.size() << " triangles, "
            << drum_panels(box.radius, st.r_min) << " panels tangent to its cylinder\n";
    } else {
      const double height = box.height > 0 ? box.height : 2.0 * st.top;
      out << "    add_cylinder(radius=" << num(w.position) << ", height=" << num(height)
          << ", segments=" << cylinder_segments(w.position, st.r_min) << ")  # " << w.name
          << ": panel edges at most r_min/200 outside; height " << (box.height > 0 ? "of the container" : "2x the packing top")
          << "\n";
    }
  }
  out << "\n\nsys.exit(main())\n";
  return out.str();
}

}  // namespace btr
