#include "coupling/dem/compaction_lines.h"

#include "btr/model/number_text.h"

namespace btr {

bool read_compaction_line(const std::string& line, RelaxResult::Compaction& c) {
  const auto w = words_of(line);
  if (line.rfind("BTR-COMPACTION-END ", 0) == 0) {  // reached|not-reached friction x S t = T s phi = P
    c.ran = true;
    c.reached = w.size() > 1 && w[1] == "reached";
    for (std::size_t i = 0; i + 2 < w.size(); ++i)
      if (w[i] == "x") read_number(w[i + 1], c.friction_scale);
      else if (w[i] == "t" && w[i + 1] == "=") read_number(w[i + 2], c.time);
      else if (w[i] == "phi" && w[i + 1] == "=") read_number(w[i + 2], c.packing_fraction);
    return true;
  }
  if (line.rfind("BTR-COMPACTION-SLAB ", 0) == 0) {  // k K reached|rest|max-time t = T s phi = P
    RelaxResult::Compaction::Slab slab;
    slab.reached = w.size() > 3 && w[3] == "reached";
    for (std::size_t i = 0; i + 2 < w.size(); ++i)
      if (w[i] == "t" && w[i + 1] == "=") read_number(w[i + 2], slab.time);
      else if (w[i] == "phi" && w[i + 1] == "=") read_number(w[i + 2], slab.packing_fraction);
    c.slabs.push_back(slab);
    return true;
  }
  return false;
}

}  // namespace btr
