#include "btr/scene/drop_list.h"

#include <fstream>

#include "btr/scene/csv_fields.h"
#include "btr/scene/scene_toml.h"

namespace btr {
using csv::join;
using csv::parse_double;
using csv::parse_int;
using csv::split;
using csv::trim;

std::vector<ListedDrop> read_drop_list(const std::string& path, int dimension) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the drop list file");
  const std::vector<std::string> base = dimension == 2 ? std::vector<std::string>{"x", "r"}
                                                       : std::vector<std::string>{"x", "y", "r"};
  auto with_species = base;
  with_species.push_back("species");

  std::vector<ListedDrop> drops;
  std::vector<std::string> columns;  // fixed by the header or by the first data row
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    auto fields = split(line);
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    const bool is_header = std::isalpha(static_cast<unsigned char>(line[0]));
    if (is_header) {
      if (!columns.empty() || !drops.empty())
        throw SceneError(where + "expected a row of numbers, got '" + line + "'");
      if (fields != base && fields != with_species)
        throw SceneError(where + "header: expected '" + join(base) + "' or '" + join(with_species) +
                         "' for dimension " + std::to_string(dimension) + ", got '" + line + "'");
      columns = fields;
      continue;
    }
    if (columns.empty()) {
      if (fields.size() == base.size()) columns = base;
      else if (fields.size() == with_species.size()) columns = with_species;
    }
    if (fields.size() != columns.size() || columns.empty())
      throw SceneError(where + "expected " + std::to_string(columns.empty() ? base.size() : columns.size()) +
                       " columns (" + join(columns.empty() ? base : columns) + ") for dimension " +
                       std::to_string(dimension) + ", got " + std::to_string(fields.size()));
    ListedDrop d;
    d.line = line_no;
    std::string r_text;
    for (std::size_t i = 0; i < columns.size(); ++i) {
      if (columns[i] == "species") {
        if (!parse_int(fields[i], d.species) || d.species < 1)
          throw SceneError(where + "species: expected an integer >= 1, got '" + fields[i] + "'");
        continue;
      }
      double v = 0.0;
      if (!parse_double(fields[i], v))
        throw SceneError(where + columns[i] + ": expected a number, got '" + fields[i] + "'");
      if (columns[i] == "x") d.x = v;
      else if (columns[i] == "y") d.y = v;
      else d.r = v, r_text = fields[i];
    }
    if (!(d.r > 0.0)) throw SceneError(where + "r: expected a positive radius, got '" + r_text + "'");
    drops.push_back(d);
  }
  if (drops.empty()) throw SceneError(path + ": the drop list has no rows");
  return drops;
}

}  // namespace btr
