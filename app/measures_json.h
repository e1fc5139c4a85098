#pragma once
// The JSON form of btr::PackingMeasures: the "measures" object of NAME.json (deposit), relaxed.json
// (relax) and `btr measure`. Every number that depends on a choice sits next to that choice (contact
// tolerance, window margin, fitted height band).
#include <nlohmann/json.hpp>

#include "btr/metrics.h"

namespace btr_app {

nlohmann::json measures_to_json(const btr::PackingMeasures& m, int dimension);

// One line each for the bulk and the heap, for the programs' summaries.
std::string measures_summary(const btr::PackingMeasures& m, int dimension);

}  // namespace btr_app
