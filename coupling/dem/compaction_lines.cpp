#include "coupling/dem/compaction_lines.h"

#include <cstdlib>
#include <sstream>
#include <vector>

namespace btr {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

bool to_double(const std::string& s, double& v) {
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size();
}

}  // namespace

bool read_compaction_line(const std::string& line, RelaxResult::Compaction& c) {
  const auto w = split(line);
  if (line.rfind("BTR-COMPACTION-END ", 0) == 0) {  // reached|not-reached friction x S t = T s phi = P
    c.ran = true;
    c.reached = w.size() > 1 && w[1] == "reached";
    for (std::size_t i = 0; i + 2 < w.size(); ++i)
      if (w[i] == "x") to_double(w[i + 1], c.friction_scale);
      else if (w[i] == "t" && w[i + 1] == "=") to_double(w[i + 2], c.time);
      else if (w[i] == "phi" && w[i + 1] == "=") to_double(w[i + 2], c.packing_fraction);
    return true;
  }
  if (line.rfind("BTR-COMPACTION-SLAB ", 0) == 0) {  // k K reached|rest|max-time t = T s phi = P
    RelaxResult::Compaction::Slab slab;
    slab.reached = w.size() > 3 && w[3] == "reached";
    for (std::size_t i = 0; i + 2 < w.size(); ++i)
      if (w[i] == "t" && w[i + 1] == "=") to_double(w[i + 2], slab.time);
      else if (w[i] == "phi" && w[i + 1] == "=") to_double(w[i + 2], slab.packing_fraction);
    c.slabs.push_back(slab);
    return true;
  }
  return false;
}

}  // namespace btr
