#include "command_support.h"

#include <sstream>

namespace btr_app {

std::string output_name(const std::string& option, const btr::Scene& scene) {
  const std::string name = option.empty() ? scene.name : option;
  if (name.empty() || name.find('/') != std::string::npos)
    throw btr::SceneError("--name '" + name + "': expected a file name without '/'");
  return name;
}

nlohmann::json check_to_json(const btr::CheckReport& c) {
  return {{"ok", c.ok()},           {"overlaps", c.overlaps}, {"max_overlap", c.max_overlap},
          {"unsupported", c.unsupported}, {"outside", c.outside},   {"examples", c.examples}};
}

std::string check_message(const btr::CheckReport& c) {
  std::ostringstream s;
  s << c.overlaps << " overlapping pair(s) (largest overlap " << c.max_overlap << " of the smaller radius), "
    << c.unsupported << " unsupported, " << c.outside << " outside the container";
  if (!c.examples.empty()) {
    s << "; grains";
    for (std::size_t i = 0; i < c.examples.size(); ++i) s << (i ? ", " : " ") << c.examples[i];
  }
  return s.str();
}

}  // namespace btr_app
