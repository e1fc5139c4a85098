#pragma once
// Reading a scene from a TOML file (inputs/*.toml).
//
// Scene file schema (SI units: m, kg, s, Pa). Unknown keys and tables anywhere are errors.
//
// [scene]                        required
//   name       string            default: the file name without extension
//   dimension  2 | 3             required. 2D: disks in the x-z plane (y = 0); 3D: spheres. z is up.
//   seed       integer >= 0      default 1
//
// [grains]                       required
//   count       integer > 0      required, except with source.kind = "list" (then: the file's row count;
//                                a count larger than the file's row count is an error)
//   density     kg/m^3 > 0       default for every component (default 2500)
//   radius      table            default for every component; one of
//                 { distribution = "constant", value = R }
//                 { distribution = "uniform", min = A, max = B }          A < B, uniform in [A, B)
//                 { distribution = "constant-mass", min = A, max = B }    Eq. 1 of the BTR paper:
//                   R = A B / (B - u (B - A)), u uniform in [0, 1); number density ~ 1/R^2, i.e.
//                   equal mass per radius interval for disks (2D); for spheres mass per dR grows ~ R.
//                 { distribution = "list", values = [R1, R2, ...] }       used in order, cycling
//               not allowed with source.kind = "list" (the file gives the radii)
//   fraction_by "number" | "volume"   how component fractions are meant (default "number")
//   [[grains.component]]        optional, one per species of a mixture:
//     species   integer          1..K, distinct (default: position in the list, 1-based)
//     fraction  number in [0,1]  required when K > 1; fractions must sum to 1 (within 1e-9)
//     density   kg/m^3           default grains.density
//     radius    table            as grains.radius; default grains.radius
//     material  inline table     keys of [material]; each missing key falls back to [material]
//
// [container]                    required
//   kind    "open" | "box" | "periodic" | "hele-shaw" | "cylinder" | "drum" | "mesh"
//           hele-shaw, cylinder and mesh are 3D only. Coordinates are centred on the z axis (container.h).
//   file    mesh only: an STL file (ASCII or binary), relative to the scene file's folder (mesh_file.h)
//   scale   mesh only: > 0, multiplies the file's coordinates (default 1; 1e-3 for a CAD file in mm)
//   size    box, periodic: [x] in 2D, [x, y] in 3D; hele-shaw: [x] (cell length). Not for open, cylinder.
//   gap     hele-shaw only: plate distance w (>= the largest grain diameter)
//   radius  cylinder and drum: inner radius (>= the largest grain radius)
//   length  3D drum only: distance between its flat end walls (at y = +-length/2)
//   height  optional wall height for the DEM stage (> 0); omitted: derived from the packing
//   Every lateral extent must hold the largest grain (2 r_max <= size, gap, 2 radius).
//
// [source]                       required
//   kind "point":   position = [x] (2D) or [x, y] (3D), scatter >= 0 (default 0): drops are uniform on a
//                   disk (3D) or segment (2D) of that radius about the position; the whole disk must let
//                   the largest grain fit in the container (periodic: positions wrap into the domain).
//   kind "rain":    uniform over the container footprint where each grain fits; not for "open".
//   kind "region":  x = [min, max], and in 3D y = [min, max] (min < max): uniform over the rectangle,
//                   which must let the largest grain fit in the container.
//   kind "list":    file = "drops.csv" (relative to the scene file's folder): rows "x,y,r" (3D) or "x,r"
//                   (2D), optionally a last column "species"; an optional header row naming the
//                   columns; blank lines and lines starting with '#' are skipped. Drops are used in order.
//
// [material]                     optional; defaults for every component
//   young > 0 (default 5e6), poisson in (-1, 0.5) (0.3), restitution in (0, 1] (0.5),
//   friction >= 0 (0.5), rolling_friction >= 0 (0 = off)
//
// [relax]                        optional
//   engine "liggghts" | "yade" (liggghts), model "hertz" | "hooke" (hertz), max_time > 0 [s] (0.2),
//   stop_kinetic_ratio > 0 (1e-6), timestep_fraction in (0, 1] (0.2), timestep > 0 [s] (optional)
//   stop_rule "kinetic-energy" | "unbalanced-force" | "displacement" (kinetic-energy): what ends the run
//     before max_time, checked at every check of the schedule once t >= sqrt(2 r_min / g):
//     kinetic-energy: E and its mean over the check window < stop_kinetic_ratio * sum m g d;
//     unbalanced-force: YADE's utils.unbalancedForce() (mean over grains of |contact forces + m g| /
//       mean over contacts of |contact force|) < stop_unbalanced_force in (0, 1) (1e-3);
//     displacement: the largest grain displacement over the last check window < stop_displacement
//       in (0, 1) (1e-4) times the smallest grain diameter.
//   damping in [0, 1) (0 = off): YADE's NewtonIntegrator damping (local non-viscous); LIGGGHTS: fix
//     viscous of equal dissipation per oscillation (coupling/README.md)
//   open_margin > 0 (10): container "open" only: grains whose centre gets farther than open_margin largest
//     diameters beyond the packing's footprint are removed from the run and counted (both engines)
//
// [intruder]                     optional (Brazil nut): one larger grain, dropped first (it rests on the
//                                floor under the bed); needs a bed of equal grains (one component,
//                                constant radius, no list source). It comes in addition to grains.count.
//   diameter_ratio  > 0          intruder diameter / bed grain diameter (Phi)
//   position        [x] (2D) or [x, y] (3D), default the origin; must keep the intruder inside
//   The intruder's species is the bed's species + 1.
//
// [shaking]                      optional; used by `btr shake` (dynamic BTR, seed 001 section 6.6)
//   cycles          integer > 0  number of shaking cycles
//   lift            > 0 [m]      how far the whole pile is raised before each redeposition
//   noise           >= 0 [m]     amplitude a of the random horizontal displacement per grain and cycle,
//                                uniform in [-a, a] on each horizontal axis (default 0: deterministic)
//   snapshot_every  integer > 0  cycles between snapshots (default: cycles)
//
// [drum]                         optional, container.kind = "drum"; used by `btr drum` (seed 000 section 6)
//   steps_per_revolution  integer > 0   rotation steps per revolution (the paper: 100)
//   revolutions           > 0           revolutions to run (steps = round(revolutions * steps_per_revolution))
//   lift                  > 0 [m]       lift of every grain before each redeposition (default radius / 10)
//   snapshot_every        integer > 0   steps between snapshots (default steps_per_revolution)
//
// Errors name the file, the line, the key and what was expected, e.g.
//   inputs/x.toml:12: grains.count: expected a positive integer, got 0
//   inputs/x.toml:7: unknown key 'sise' in [container]; allowed: kind, size, gap, radius, height, length
#include <stdexcept>
#include <string>

#include "btr/scene/scene.h"

namespace btr {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads and validates a scene. Scene::file is `path` as given; a list source's file is stored
// resolved against the scene's folder. Throws SceneError.
Scene load_scene(const std::string& path);

}  // namespace btr
