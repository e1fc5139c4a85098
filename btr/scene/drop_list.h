#pragma once
// The CSV file of a list source: one drop per row, "x,y,r" (3D) or "x,r" (2D), optionally followed
// by a "species" column. An optional header row names the columns; blank lines and '#' lines are skipped.
#include <string>
#include <vector>

namespace btr {

struct ListedDrop {
  double x = 0.0, y = 0.0, r = 0.0;
  int species = 1;
  int line = 0;  // 1-based line in the file, for error messages
};

// Throws SceneError naming the file and line on a missing file or a malformed row. Checks syntax,
// finite values, r > 0 and species >= 1 only; the caller checks them against the scene.
std::vector<ListedDrop> read_drop_list(const std::string& path, int dimension);

}  // namespace btr
