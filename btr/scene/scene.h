#pragma once
// A scene: everything one use case needs, read from a TOML file in inputs/ (see scene_toml.h).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "btr/model/container.h"

namespace btr {

// How the radii of one component are drawn.
struct RadiusSpec {
  enum class Kind { Constant, Uniform, ConstantMass, List };
  Kind kind = Kind::Constant;
  double value = 0.0;           // constant
  double min = 0.0, max = 0.0;  // uniform, constant-mass (Eq. 1 of the BTR paper)
  std::vector<double> list;     // list: radii used in order, cycling
};

// Contact material of one species (used by the DEM stage only).
struct Material {
  double young = 5e6;        // Pa
  double poisson = 0.3;
  double restitution = 0.5;
  double friction = 0.5;
  double rolling_friction = 0.0;  // 0 = off
  // Explicit linear contact (relax.model = "hooke-stiffness" only, else 0): LIGGGHTS' hooke/stiffness
  // coefficients, F_n = kn delta - m_eff gamma_n v_n, F_t = -kt xi - m_eff gamma_t v_t (Silbert et al.).
  double kn = 0.0;             // N/m
  double kt = 0.0;             // N/m
  double gamma_n = 0.0;        // 1/s (multiplied by the effective mass)
  double gamma_t = 0.0;        // 1/s, grain-grain
  double wall_gamma_t = 0.0;   // 1/s, this species on a wall (defaults to gamma_t)
};

// One component of the grain mixture; a monodisperse or polydisperse scene has exactly one.
struct Component {
  int species = 1;
  double fraction = 1.0;  // number or volume fraction (see Grains::fraction_by)
  double density = 2500.0;  // kg/m^3
  RadiusSpec radius;
  Material material;
};

struct GrainsSpec {
  std::int64_t count = 0;
  enum class FractionBy { Number, Volume };
  FractionBy fraction_by = FractionBy::Number;
  std::vector<Component> components;  // at least one
};

struct SourceSpec {
  enum class Kind { Point, Rain, Region, List };
  Kind kind = Kind::Rain;
  double x = 0.0, y = 0.0;      // point: drop position
  double scatter = 0.0;         // point: drops are spread uniformly over a disk of this radius [m]
  double x_min = 0, x_max = 0;  // region
  double y_min = 0, y_max = 0;  // region (3D)
  std::string file;             // list: CSV "x,y,r" (3D) or "x,r" (2D), resolved against the scene's folder
};

struct RelaxSpec {
  std::string engine = "liggghts";  // liggghts | yade
  std::string model = "hertz";      // hertz | hooke | hooke-stiffness
  double max_time = 0.2;            // s
  double stop_kinetic_ratio = 1e-6; // stop when kinetic energy < ratio * sum_i m_i g d_i
  double timestep_fraction = 0.2;   // of the Rayleigh / contact time
  std::optional<double> timestep;   // requested step; refused if above the stable one
  bool preload = false;             // start from the pre-loaded packing (coupling/dem/preload.h)
  // Which rule ends the relaxation (besides max_time): "kinetic-energy" (E < stop_kinetic_ratio sum m g d),
  // "unbalanced-force" (YADE's utils.unbalancedForce() < stop_unbalanced_force) or "displacement" (the
  // largest grain displacement over the last check window < stop_displacement * smallest diameter).
  std::string stop_rule = "kinetic-energy";
  double stop_unbalanced_force = 1e-3;
  double stop_displacement = 1e-4;
  double damping = 0.0;             // YADE's NewtonIntegrator damping (local, non-viscous), in [0, 1); 0 = off
  double open_margin = 10.0;        // open container: grains farther than this many largest diameters
                                    // beyond the packing's footprint are removed (and counted)
  double open_heap_angle = 2.0;     // open container: the region also holds the grains' volume as a heap at
                                    // this angle [deg] (coupling/dem/open_floor_region.h)
  // Land on this bulk packing fraction (coupling/dem/relax_target.h): in the same run, before the stop rule,
  // friction is scaled by friction_scales[0] (then the next scale if the bed comes to rest below the target)
  // with damping compaction_damping, until the bulk packing fraction reaches target_phi; then the friction is
  // restored, the grains are stopped and the run settles with `damping` on the stop rule. Unset: no compaction.
  std::optional<double> target_phi;
  std::vector<double> friction_scales{0.0};  // decreasing, in [0, 1)
  double compaction_damping = 0.15;          // in [0, 1), as `damping`; 0 = undamped collapse
  // The compaction's time step: the run's step times compaction_timestep_fraction / timestep_fraction (the
  // same rule with another fraction of the Rayleigh or contact time); unset: the run's step.
  std::optional<double> compaction_timestep_fraction;
};

// A single larger grain dropped first, so it sits on the floor under the bed (Brazil nut).
struct IntruderSpec {
  double diameter_ratio = 1.0;  // intruder diameter / small-grain diameter (Phi)
  double x = 0.0, y = 0.0;      // drop position (y = 0 in 2D)
  int species = 2;              // one more than the bed's species
};

// Dynamic BTR by shaking (seed 001 section 6.6): per cycle, number the grains by height, lift the
// pile, redeposit them in that order; noise: a uniform horizontal displacement in [-a, a] per axis.
struct ShakingSpec {
  std::int64_t cycles = 0;
  double lift = 0.0;                // m
  double noise = 0.0;               // amplitude a [m]; 0 = the deterministic model
  std::int64_t snapshot_every = 0;  // cycles between snapshots (the initial and last are always written)
  // DEM tapping only (btr shake --engine, docs/guide/shake_dem.md): the floor's tap z = A sin(2 pi f t) over one
  // period, with peak acceleration gamma g = A (2 pi f)^2. Unset: kDefaultTapGamma, kDefaultTapFrequency.
  std::optional<double> gamma;      // dimensionless, in (0, kMaxTapGamma]
  std::optional<double> frequency;  // Hz, in (0, kMaxTapFrequency]
};
// Defaults of the tap: Gamma 3 and 30 Hz single-cycle taps, after the tapping experiments of Knight, Jaeger and
// Nagel on the Brazil nut and compaction (docs/guide/shake_dem.md gives the reasons).
inline constexpr double kDefaultTapGamma = 3.0;
inline constexpr double kDefaultTapFrequency = 30.0;
inline constexpr double kMaxTapGamma = 100.0;
inline constexpr double kMaxTapFrequency = 10000.0;

// Dynamic BTR in a rotating drum (seed 000 section 6): per step, rotate every grain with the drum by
// 2 pi / steps_per_revolution about its axis, lift every grain by `lift`, redeposit them lowest first.
struct DrumSpec {
  std::int64_t steps_per_revolution = 100;
  double revolutions = 1.0;
  double lift = 0.0;                // m; default radius / 10
  std::int64_t snapshot_every = 0;  // steps between snapshots (the initial and last are always written)
  // The DEM drum's speed (btr drum --engine; coupling/dem/drum_rotation.h): at most one of them; neither = the
  // default Froude number there.
  std::optional<double> rpm;        // revolutions per minute, > 0
  std::optional<double> froude;     // omega^2 R / g, in (0, 1)
};

// Rigid clusters (seed 000 section 5, cohesive nano-powders): the grains are dropped as random compact
// clusters of `size` grains, then `cycles` times the deposit is cut into square (cubic) blocks
// `block` mean diameters wide, split into clusters of touching grains, and those are dropped again.
struct ClustersSpec {
  std::int64_t size = 3;
  double block = 50.0;      // mean grain diameters
  std::int64_t cycles = 0;
  std::string file;         // cluster list (cluster_list.h), resolved against the scene's folder; empty: random
                            // compact clusters of `size`
};

struct Scene {
  std::string name;
  std::string file;  // path it was read from
  int dimension = 3;
  std::uint64_t seed = 1;
  GrainsSpec grains;
  Container container;
  SourceSpec source;
  RelaxSpec relax;
  std::optional<IntruderSpec> intruder;
  std::optional<ShakingSpec> shaking;
  std::optional<DrumSpec> drum;
  std::optional<ClustersSpec> clusters;
};

}  // namespace btr
