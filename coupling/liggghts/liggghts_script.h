#pragma once
// The LIGGGHTS inputs of a relaxation: a read_data file (atom_style granular) and an input script.
//
// Choices (see coupling/README.md):
//  - atom types 1..K are the scene's components in order, type K+1 is the walls' material;
//  - walls are primitive fix wall/gran planes / a z-cylinder, exactly the container's (dem_walls.h);
//    periodic containers use periodic boundaries instead of side walls;
//  - 2D packings (disks in the x-z plane) run as spheres held in y = 0 by "fix setforce NULL 0 NULL";
//  - the stop rule is a loop of runs of one check window each (label / run / if ... jump SELF / next /
//    jump); it prints "BTR-STOP <rule> t = T s value = V" (rule: kinetic-energy, unbalanced-force or
//    displacement) or "BTR-STOP max-time t = T s", then "BTR-FINAL unbalanced-force U atoms N";
//  - open floors: the box is fixed laterally at the plan's removal region, lost atoms are ignored (and
//    counted by the readback); damping (plan.damping > 0): fix viscous, liggghts_damping_gamma, except after a
//    compaction to a target packing fraction, where the settle runs under YADE's own local damping
//    (liggghts_local_damping_fix; coupling/README.md says why);
//  - the final state goes to btr_final.dump (id x y z vx vy vz and the normal force of each wall)
//    and btr_contacts.dump (pair ids, periodic flag, normal force vector, overlap), full precision.
#include <string>
#include <vector>

#include "coupling/dem/engine_adapter.h"

namespace btr {

inline constexpr const char* kLiggghtsScript = "in.btr";
inline constexpr const char* kLiggghtsData = "btr.data";
inline constexpr const char* kLiggghtsMesh = "btr_mesh.stl";  // a mesh container's triangles, as placed
inline constexpr const char* kLiggghtsScreen = "screen.liggghts";  // a mesh container's run: LIGGGHTS' screen
inline constexpr const char* kLiggghtsLog = "log.liggghts";  // also LIGGGHTS' default log name
inline constexpr const char* kLiggghtsFinalDump = "btr_final.dump";
inline constexpr const char* kLiggghtsContactsDump = "btr_contacts.dump";

// A rotating drum's snapshot k (1-based, DrumRotation): "btr_rot_K.dump" (id x y z, sorted by id).
std::string liggghts_snapshot_file(std::size_t k);

// The LIGGGHTS fix ID of a wall ("floor" -> "btr_wall_floor", "x-" -> "btr_wall_xlo", ...).
std::string liggghts_wall_id(const std::string& wall_name);

// fix viscous coefficients (per species, in the scene's order) equivalent to YADE's NewtonIntegrator damping
// `damping`: equal energy lost per oscillation of a mean grain on a contact under its weight,
// gamma = 2 (damping / pi) sqrt(k m).
std::vector<double> liggghts_damping_gamma(const Grains& grains, const Scene& scene, double damping);

// The same per species with what it was computed from: the mass of the species' mean grain and its grain count
// (0 and 0 for a species with no grain here, whose gamma is any positive value).
struct SpeciesDamping {
  double gamma = 0.0, mean_mass = 0.0;
  long grains = 0;
};
std::vector<SpeciesDamping> liggghts_species_damping(const Grains& grains, const Scene& scene, double damping);

// The fix property/global lines of the scene's friction (and rolling friction, if the scene has any) per type
// pair, in this writer's type order, every coefficient times `scale`; re-issued between runs they change the
// friction.
// `slab_twins`: the script has the slab compaction's twin types (CompactionPlan::slabs: types 1..K species, K+1
// walls, K+2..2K+1 the species' twins), and only the pairs with a twin are scaled.
std::string liggghts_friction_fixes(const Scene& scene, double scale = 1.0, bool slab_twins = false);

// The type a grain of the scene's component (0-based) takes while its slab is compacted (liggghts_friction_fixes).
int liggghts_slab_twin_type(const Scene& scene, std::size_t component);

// "fix ID all viscous ..." (with its comment): the damping `damping` as liggghts_damping_gamma computes it.
std::string liggghts_viscous_fix(const std::string& id, const Grains& grains, const Scene& scene, double damping);

// "fix ID all addforce ..." with its three atom-style variables (and comment): YADE's NewtonIntegrator damping
// itself, each force component reduced by damping x |F_k| in the direction of motion. It must be defined after
// every fix that adds a force (walls, gravity), and the runs after it must not be "pre no": LIGGGHTS 3.8 finds
// the fix's variables again only when a run sets up (a "pre no" run after it crashes in Variable::compute_atom).
std::string liggghts_local_damping_fix(const std::string& id, double damping);

// Writes dir/btr.data and dir/in.btr, and for a mesh container dir/btr_mesh.stl; returns their paths.
std::vector<std::string> write_liggghts_inputs(const Packing& packing, const Scene& scene, const RelaxPlan& plan,
                                               const std::string& dir);

}  // namespace btr
