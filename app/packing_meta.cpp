#include "packing_meta.h"

#include <sys/resource.h>

#include <algorithm>
#include <map>

#include "coupling/io/scene_json.h"

namespace btr_app {

nlohmann::json scene_packing_meta(const btr::Scene& scene, const btr::Grains& grains, std::uint64_t seed,
                                  const std::string& command) {
  std::map<int, std::int64_t> per_species;
  double r_min = grains.empty() ? 0.0 : grains[0].r, r_max = r_min;
  for (const btr::Grain& g : grains) {
    ++per_species[g.species];
    r_min = std::min(r_min, g.r), r_max = std::max(r_max, g.r);
  }
  nlohmann::json counts = nlohmann::json::object();
  for (const auto& [species, k] : per_species) counts[std::to_string(species)] = k;
  const nlohmann::json scene_json = btr::scene_to_json(scene);
  return {{"program", "btr"},
          {"version", BTR_VERSION},
          {"command", command},
          {"scene_name", scene.name},
          {"scene_file", scene.file},
          {"scene", scene_json},
          {"seed", seed},
          {"dimension", scene.dimension},
          {"container", scene_json["container"]},
          {"count", static_cast<std::int64_t>(grains.size())},
          {"counts", counts},
          {"radius_min", r_min},
          {"radius_max", r_max}};
}

double own_cpu_seconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

}  // namespace btr_app
