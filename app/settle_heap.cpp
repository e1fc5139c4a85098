#include "settle_heap.h"

#include <cmath>
#include <filesystem>

#include "btr/placement/heap_surface.h"
#include "btr/placement/run_scene.h"
#include "btr/scene/scene_toml.h"
#include "btr/model/number_text.h"
#include "coupling/dem/settle_plan.h"
#include "measures_json.h"
#include "packing_meta.h"

namespace btr_app {

namespace fs = std::filesystem;
using nlohmann::json;

HeapSteps settle_heap(const btr::Scene& scene, const std::string& engine, const btr::Grains& btr_heap,
                      const SettleRunOptions& o, const std::string& out) {
  HeapSteps r;
  r.steps = json::array();

  // ---- 2. the calibration: the scene poured with softened grains
  const btr::HeapCalibrationPlan cal = [&] {
    try {
      return btr::heap_calibration_plan(scene, btr_heap);
    } catch (const btr::RelaxRefused& e) {
      throw btr::SceneError(e.what());
    }
  }();
  say("2/4 calibration pour of the scene's " + std::to_string(scene.grains.count) + " grains softened x " +
      btr::g6(cal.softening) + " (" + engine + ")");
  {
    const StepClock clock;
    const std::string dir = (fs::path(out) / "calibration").string();
    const CalibrationPour pour = calibration_pour(cal.scene, engine, o, dir, btr::MetricsOptions{});
    const btr::HeapMeasures& h = pour.measures.heap;
    if (!h.valid)
      throw btr::SceneError(scene.file + ": grains.count: the calibration pour of " +
                            std::to_string(scene.grains.count) + " grains left no heap flank to fit (" + h.note +
                            "): a heap needs more grains");
    r.angle_deg = h.angle_deg;
    r.angle_from = {{"source", "calibration pour"},
                    {"softening", cal.record},
                    {"grains", scene.grains.count},
                    {"seed", o.seed},
                    {"engine", engine},
                    {"heap_height", h.height},
                    {"output", "calibration/poured.csv"}};
    r.steps.push_back(clock.finish("calibration", pour.engine_cpu_seconds,
                                   {{"what", "pour of the scene with softened grains"},
                                    {"grains", scene.grains.count},
                                    {"softening", cal.softening},
                                    {"angle_deg", h.angle_deg},
                                    {"simulated_seconds", pour.result.run.simulated_time},
                                    {"stop_reason", pour.result.run.stop_reason}}));
  }
  say("flank angle " + btr::g6(r.angle_deg) + " deg (calibration pour)");

  // ---- 3. the BTR heap at that angle: the fitted flank of a heap of a few thousand grains scatters by 0.4-2 deg
  // from one draw of the drop positions to the next, and stands off the surface it was rained over by a bias that
  // depends on the container (+1.7 deg between a Hele-Shaw cell's plates 5 d apart, flatter on an open floor). So
  // kHeapDraws heaps are built over the calibration's angle, their mean flank gives the bias, kHeapDraws more are
  // built over the angle less that bias, and the heap whose flank is nearest the calibration's is kept.
  say("3/4 BTR heap at " + btr::g6(r.angle_deg) + " deg (" + std::to_string(btr::kHeapDraws) +
      " draws, then as many over the angle less their bias)");
  {
    const StepClock clock;
    const double phi = scene.dimension == 3 ? btr::kHeapSurfacePackingFraction3d : btr::kHeapSurfacePackingFraction2d;
    json rounds = json::array();
    double best = INFINITY;
    btr::PackingMeasures built;
    double reach = 0.0, apex = 0.0;
    auto build_round = [&](double surface_deg, int first_draw) {
      const btr::HeapSurfaceSampler sampler(scene, o.seed, scene.grains.count, surface_deg * M_PI / 180.0, phi);
      json angles = json::array();
      double sum = 0.0;
      int valid = 0;
      for (int draw = first_draw; draw < first_draw + btr::kHeapDraws; ++draw) {
        btr::Grains grains = btr::run_drops(scene, sampler.draw(static_cast<std::uint64_t>(draw)), nullptr).grains;
        btr::PackingMeasures m = measure_in_scene(grains, scene);
        angles.push_back(m.heap.valid ? json(m.heap.angle_deg) : json());
        if (m.heap.valid) {
          sum += m.heap.angle_deg;
          ++valid;
        }
        const double miss = m.heap.valid ? std::abs(m.heap.angle_deg - r.angle_deg) : INFINITY;
        if (miss < best || r.heap.grains.empty()) {
          best = miss;
          r.heap.grains = std::move(grains);
          built = std::move(m);
          reach = sampler.surface().reach;
          apex = sampler.surface().apex_height;
        }
      }
      rounds.push_back({{"surface_angle_deg", surface_deg}, {"draws_angle_deg", angles}});
      return valid > 0 ? sum / valid - surface_deg : NAN;
    };
    const double bias = build_round(r.angle_deg, 0);
    const double corrected = r.angle_deg - bias;
    json second = {{"bias_deg", std::isnan(bias) ? json() : json(bias)}};
    if (std::isnan(bias))
      second["skipped"] = "no draw of the first round had a flank to fit";
    else if (!(corrected > 0.0 && corrected < 90.0))
      second["skipped"] = "the corrected surface angle " + btr::g6(corrected) + " deg lies outside (0, 90)";
    else
      build_round(corrected, btr::kHeapDraws);
    if (!built.heap.valid)
      throw btr::SceneError(scene.file + ": grains.count: no BTR heap built at " + btr::g6(r.angle_deg) +
                            " deg had a flank to fit (" + built.heap.note + ")");
    r.heap.meta = scene_packing_meta(scene, r.heap.grains, o.seed, "settle heap");
    r.heap.meta["measures"] = measures_to_json(built);
    const std::string dir = (fs::path(out) / "btr_heap").string();
    btr::write_packing(dir, scene.name, r.heap);
    btr::write_packing_meta(dir, scene.name, r.heap.meta);
    r.steps.push_back(clock.finish("heap deposit", 0.0,
                                   {{"what", "BTR heap rained over the surface of the calibrated angle"},
                                    {"surface_packing_fraction", phi},
                                    {"apex_height", apex},
                                    {"built_angle_deg", built.heap.angle_deg},
                                    {"rounds", rounds},
                                    {"correction", second},
                                    {"reach", reach},
                                    {"output", "btr_heap/" + scene.name + ".csv"}}));
  }
  return r;
}

}  // namespace btr_app
