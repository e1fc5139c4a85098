#pragma once
// `btr settle` of a heap (docs/guide/settle.md, "Heaps"): the scene poured with softened grains gives the flank
// angle (coupling/dem/settle_plan.h, heap_calibration_plan), and BTR builds the heap at that angle by raining the
// grains over its surface (btr/placement/heap_surface.h), ready for the quasi-static relaxation.
#include <string>

#include <nlohmann/json.hpp>

#include "coupling/io/packing_io.h"
#include "btr/scene/scene.h"
#include "settle_steps.h"

namespace btr_app {

struct HeapSteps {
  btr::Packing heap;           // the BTR heap at the calibrated angle (OUTDIR/btr_heap/NAME.csv)
  double angle_deg = 0.0;      // the calibration pour's flank angle
  nlohmann::json angle_from;   // settle.json "chosen.angle_deg.from"
  nlohmann::json steps;        // the calibration and heap-deposit steps' records
};

// Steps 2 and 3 of a heap's settle. `btr_heap`: the scene's plain BTR packing (step 1), whose mean column bounds
// the calibration's softening. Throws btr::SceneError when the calibration pour leaves no flank to fit.
HeapSteps settle_heap(const btr::Scene& scene, const std::string& engine, const btr::Grains& btr_heap,
                      const SettleRunOptions& o, const std::string& out);

}  // namespace btr_app
