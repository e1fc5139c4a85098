#pragma once
// The reference DEM pour's plan, the same in both engines (docs/design.md section 4, "Reference pour"):
// the grains start on a loose lattice over the source's footprint, are released in batches as a stream
// from a small drop height, and settle under the relaxation's kinetic-energy rule or stop at max time.
// The engines' writers (liggghts_script.cpp, yade_script.cpp) turn RelaxPlan::pour into their inputs.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "btr/scene/scene.h"
#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/relax_plan.h"

namespace btr {

struct PourSettings {
  std::uint64_t seed = 1;                   // the lattice's jitter and site order
  int np = 1;                               // LIGGGHTS: MPI ranks; YADE: threads
  double pace = 1.0;                        // batch interval / the batch's free-fall time (smaller: faster)
  double drop_gap = 1.0;                    // mean diameters between a released batch and the pile's top
  int max_batches = 40;
  std::optional<double> stop_ratio;         // default: the scene's relax.stop_kinetic_ratio
  std::optional<double> settle_max_time;    // s after the last batch; default: the scene's relax.max_time
  std::optional<double> timestep_fraction;  // default: the scene's relax.timestep_fraction
  double check_interval = 0.005;            // s of simulated time between stop checks (at least 1000 steps)
  double wall_time_limit = 7200.0;          // s; the engine is killed past this
};

// The grains a scene drops, in order, as `btr deposit` draws them (btr/placement/drops.h): radii and species,
// positions at the origin. Throws SceneError (the drop sequence) or RelaxRefused for rigid clusters.
Grains scene_drop_grains(const Scene& scene, std::uint64_t seed);

// Lattice spacing in largest radii: neighbours sit 2.2 r_max apart, so no jitter makes two grains touch.
inline constexpr double kPourSpacing = 2.2;
// Each coordinate is moved by a uniform draw in [-j, j], j = this fraction of the spacing.
inline constexpr double kPourJitter = 0.04;

struct PourLattice {
  Grains grains;                 // the input grains (same order, radii, species) at their lattice sites
  std::size_t sites_per_layer = 0;
  std::size_t layers = 0;
  std::size_t layers_per_batch = 0;
  double spacing = 0.0;          // m
  double hold_base = 0.0;        // m, height of the lowest layer
  std::vector<PourRelease::Batch> batches;  // consecutive layers, steps not yet set
};

// Sites of one lattice layer over the source's footprint, (x, y) with y = 0 in 2D: rain and list sources
// the container's footprint, a region source its rectangle, a point source a disk (3D) or segment (2D) of
// radius max(scatter, 1.5 spacing) about the drop point; every site at least r_max + the jitter inside every
// wall; periodic containers fill the period evenly. Throws RelaxRefused naming the scene field when none fits
// or there is no footprint (rain on an open floor).
std::vector<std::pair<double, double>> pour_sites(const Scene& scene, double r_max);

// The grains in id order on the lattice: grain k takes layer k / sites_per_layer, a site in a seeded random
// order per layer (so a partial top layer is spread), jittered; layers from hold_base up, batches of
// ceil(layers / max_batches) layers; hold_base = (batches + 1) drop_gap [m] + 6 r_max + the jitter, above
// anything the stream of released grains reaches. Deterministic: the same grains,
// scene and seed give the same lattice.
PourLattice pour_lattice(const Grains& grains, const Scene& scene, std::uint64_t seed, int max_batches,
                         double drop_gap);

// The drop gap in metres: settings.drop_gap mean diameters of these grains.
double pour_drop_gap(const Grains& grains, const PourSettings& settings);

// The scene as the pour runs it: the kinetic-energy rule with the settings' ratio, the settle's max time,
// the settings' time-step fraction, no damping, no compaction, no pre-load.
Scene pour_scene(const Scene& scene, const PourSettings& settings);

// The whole plan: the relaxation's plan of the lattice (time step by the same rule, for `engine`; kinetic
// threshold; an open floor's region around the lattice, and around `footprint` too when given: the grains of
// a packing being poured again) plus the release, and the check window from settings.check_interval.
// Throws RelaxRefused for settings out of range.
RelaxPlan make_pour_plan(const PourLattice& lattice, const Scene& pour, const PourSettings& settings,
                         const std::string& engine, const Grains* footprint = nullptr);

}  // namespace btr
