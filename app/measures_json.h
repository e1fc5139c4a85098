#pragma once
// The JSON form of btr::PackingMeasures: the "measures" object of NAME.json (deposit), relaxed.json
// (relax) and `btr measure`. Every number that depends on a choice sits next to that choice (contact
// tolerance, window margin, fitted height band).
#include <nlohmann/json.hpp>

#include "btr/measures/metrics.h"
#include "btr/scene/scene.h"

namespace btr_app {

// The measures of grains in a scene's container; heaps (point sources) are measured about the source.
btr::PackingMeasures measure_in_scene(const btr::Grains& grains, const btr::Scene& scene,
                                      const btr::MetricsOptions& options = {});

nlohmann::json measures_to_json(const btr::PackingMeasures& m);

// One line each for the bulk and the heap, for the programs' summaries.
std::string measures_summary(const btr::PackingMeasures& m);

}  // namespace btr_app
