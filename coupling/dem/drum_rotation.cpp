#include "coupling/dem/drum_rotation.h"

#include <algorithm>
#include <cmath>
#include <iostream>

#include "btr/model/number_text.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/drum_mesh.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/relax_plan.h"

namespace btr {

DrumSpeed drum_speed(const Scene& scene) {
  if (scene.container.kind != ContainerKind::Drum || !scene.drum)
    refuse_scene_field(scene, "[drum]", "a rotating drum needs container.kind = \"drum\" and a [drum] table");
  const double R = scene.container.radius;
  DrumSpeed s;
  if (scene.drum->rpm) {
    s.rpm = *scene.drum->rpm;
    s.omega = s.rpm * 2.0 * M_PI / 60.0;
    s.froude = s.omega * s.omega * R / kGravity;
    s.source = "drum.rpm";
    if (!(s.rpm > 0.0) || !std::isfinite(s.rpm)) refuse_scene_field(scene, "drum.rpm", "expected a positive number");
    if (!(s.froude < 1.0))
      refuse_scene_field(scene, "drum.rpm",
                         "= " + g6(s.rpm) + " gives the Froude number omega^2 R / g = " + g6(s.froude) +
                             ", at or above 1 (the grains centrifuge); expected below " +
                             g6(60.0 / (2.0 * M_PI) * std::sqrt(kGravity / R)) + " rpm for this radius");
    return s;
  }
  s.froude = scene.drum->froude ? *scene.drum->froude : kDefaultDrumFroude;
  s.source = scene.drum->froude ? "drum.froude" : "default";
  if (!(s.froude > 0.0 && s.froude < 1.0))
    refuse_scene_field(scene, "drum.froude", "= " + g6(s.froude) + "; expected a Froude number in (0, 1)");
  s.omega = std::sqrt(s.froude * kGravity / R);
  s.rpm = s.omega * 60.0 / (2.0 * M_PI);
  return s;
}

std::vector<std::int64_t> drum_snapshot_steps(const DrumSpec& drum, double revolutions) {
  if (!(revolutions > 0.0) || !std::isfinite(revolutions))
    throw RelaxRefused("revolutions must be a positive number, got " + g6(revolutions));
  const std::int64_t last =
      std::max<std::int64_t>(1, std::llround(revolutions * static_cast<double>(drum.steps_per_revolution)));
  std::vector<std::int64_t> steps;
  for (std::int64_t s = drum.snapshot_every; s < last; s += drum.snapshot_every) steps.push_back(s);
  steps.push_back(last);
  return steps;
}

namespace {

void check_snapshot(const DrumSnapshot& snap, std::size_t k, const Grains& start, const Scene& scene,
                    const std::vector<DemWall>& walls, const std::string& dir, const std::string& engine) {
  const std::string where = engine + " drum rotation in " + dir + ", snapshot " + std::to_string(k) + " (step " +
                            std::to_string(snap.step) + "): ";
  if (snap.grains.size() != start.size())
    throw EngineFailure(FailureKind::LostGrains, where + std::to_string(snap.grains.size()) + " grains of " +
                                                     std::to_string(start.size()));
  for (std::size_t i = 0; i < start.size(); ++i) {
    const Grain& g = snap.grains[i];
    const std::string who = "grain " + std::to_string(i + 1);
    if (!g.x.allFinite()) throw EngineFailure(FailureKind::NonFinite, where + who + " has a non-finite position");
    if (scene.dimension == 2 && std::abs(g.x.y()) > 1e-9 * g.r)
      throw EngineFailure(FailureKind::OutsideContainer, where + who + " left the plane y = 0 (y = " + g6(g.x.y()) + " m)");
    const Vec3 x = wrap_into_cell(scene.container, scene.dimension, g.x);
    for (const DemWall& w : walls)
      if (w.distance(x) < 0.0)
        throw EngineFailure(FailureKind::OutsideContainer,
                            where + who + " is outside the drum: its centre is beyond the " + w.name + " wall by " +
                                g6(-w.distance(x)) + " m",
                            {{"grain", i + 1}, {"snapshot", k}});
  }
}

}  // namespace

DrumRotationResult rotate_drum(const Packing& start, const Scene& scene, const EngineAdapter& adapter,
                               const std::string& engine, const RelaxSettings& settings, double revolutions,
                               const std::string& dir) {
  DrumRotationResult out;
  out.speed = drum_speed(scene);
  if (scene.dimension == 3 && scene.container.periodic_ends)
    refuse_scene_field(scene, "container.ends",
                       "\"periodic\": the DEM drum has no periodic ends yet (its mesh would cross the periodic "
                       "boundary); use ends = \"walls\" or dynamic BTR (btr drum without --engine)");
  const std::vector<std::int64_t> steps = drum_snapshot_steps(*scene.drum, revolutions);
  RelaxPlan plan = make_plan(start, scene, settings, engine);
  const double spr = static_cast<double>(scene.drum->steps_per_revolution);
  long previous = 0;
  for (std::int64_t s : steps) {
    const double angle = 2.0 * M_PI * static_cast<double>(s) / spr;
    const long n = std::max(previous + 1, static_cast<long>(std::llround(angle / out.speed.omega / plan.timestep)));
    plan.rotation.snapshot_steps.push_back(n);
    DrumSnapshot snap;
    snap.step = s;
    snap.angle_deg = 360.0 * static_cast<double>(s) / spr;
    snap.engine_steps = n;
    snap.time = static_cast<double>(n) * plan.timestep;
    out.snapshots.push_back(snap);
    previous = n;
  }
  plan.rotation.enabled = true;
  plan.rotation.omega = out.speed.omega;
  plan.rotation.axis_z = scene.container.radius;
  plan.max_time = out.snapshots.back().time;  // the thermo schedule's span (check_schedule)
  std::cout << "drum: " << g6(out.speed.rpm) << " rpm (Froude " << g6(out.speed.froude) << ", " << out.speed.source
            << "), " << g6(revolutions) << " revolution(s) = " << g6(plan.max_time) << " s, "
            << plan.rotation.snapshot_steps.back() << " steps, " << steps.size() << " snapshots\n";
  write_engine_inputs(start, scene, adapter, settings, plan, dir);
  out.run = run_and_read_back(start, scene, adapter, engine, settings, plan, dir, "drum rotation");
  write_run_tables(out.run, dir);
  const std::vector<DemWall> walls = dem_walls(scene.container, scene.dimension);
  for (std::size_t k = 0; k < out.snapshots.size(); ++k) {
    out.snapshots[k].grains = adapter.read_snapshot(dir, k + 1, start);
    check_snapshot(out.snapshots[k], k + 1, start.grains, scene, walls, dir, engine);
  }
  out.plan = plan;
  return out;
}

nlohmann::json drum_rotation_record(const DrumRotationResult& r, const Scene& scene, const std::string& engine,
                                    const RelaxSettings& settings, double revolutions) {
  double r_min = INFINITY;
  for (const Grain& g : r.run.relaxed.grains) r_min = std::min(r_min, g.r);
  const double turned = r.snapshots.empty() ? 0.0 : r.snapshots.back().angle_deg / 360.0;
  std::vector<long> steps;
  std::vector<double> angles;
  for (const DrumSnapshot& s : r.snapshots) steps.push_back(s.engine_steps), angles.push_back(s.angle_deg);
  return {
      {"engine", engine},
      {"np", settings.np},
      {"rpm", r.speed.rpm},
      {"froude", r.speed.froude},
      {"omega", r.speed.omega},
      {"speed_source", r.speed.source},
      {"speed_rule", "Froude = omega^2 R / g; default " + g6(kDefaultDrumFroude) +
                         " (rolling regime about 1e-4 to 1e-2, Mellmann 2001)"},
      {"sense", "lowest line towards +x (about -y), as btr drum"},
      {"revolutions", revolutions},
      {"revolutions_turned", turned},
      {"timestep", r.plan.timestep},
      {"timestep_rule", r.plan.timestep_rule},
      {"simulated_time", r.run.simulated_time},
      {"engine_cpu_seconds", r.run.cpu_seconds},
      {"engine_wall_seconds", r.run.wall_seconds},
      {"engine_cpu_seconds_per_revolution", turned > 0 ? r.run.cpu_seconds / turned : 0.0},
      {"engine_wall_seconds_per_revolution", turned > 0 ? r.run.wall_seconds / turned : 0.0},
      {"panels", drum_panels(scene.container.radius, r_min)},
      {"sagitta_fraction_of_r_min", kDrumSagittaFraction},
      {"snapshot_angles_deg", angles},
      {"snapshot_engine_steps", steps},
  };
}

}  // namespace btr
