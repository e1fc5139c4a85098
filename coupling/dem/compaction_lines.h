#pragma once
// The compaction's lines in an engine's log, one format for LIGGGHTS (liggghts_compaction.cpp) and YADE
// (yade_library.py): "BTR-COMPACTION-SLAB k K reached|rest|max-time t = T s phi = P" after each slab of a
// compaction in slabs, "BTR-COMPACTION-END reached|not-reached friction x S t = T s phi = P" at its end.
#include <string>

#include "coupling/dem/relax.h"

namespace btr {

// Reads `line` into `c` if it is one of those lines (a slab line appends to c.slabs, the end line sets c.ran and
// the end's values); returns whether it was.
bool read_compaction_line(const std::string& line, RelaxResult::Compaction& c);

}  // namespace btr
