#include "btr/scene/cluster_list.h"

#include <algorithm>
#include <fstream>
#include <map>

#include "btr/scene/csv_fields.h"
#include "btr/scene/scene_toml.h"

namespace btr {

std::vector<ClusterShape> read_cluster_list(const std::string& path, int dimension) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the cluster list file");
  const std::vector<std::string> header{"cluster", "x", "y", "z", "radius", "species"};
  std::vector<ClusterShape> shapes;
  std::map<int, std::size_t> index;  // cluster number -> position in shapes
  std::map<int, std::vector<int>> lines;
  bool seen_header = false;
  std::string raw;
  for (int line_no = 1; std::getline(in, raw); ++line_no) {
    const std::string line = csv::trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> f = csv::split(line);
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (!seen_header) {
      if (f != header) throw SceneError(where + "header: expected '" + csv::join(header) + "', got '" + line + "'");
      seen_header = true;
      continue;
    }
    if (f.size() != header.size())
      throw SceneError(where + "expected 6 columns (" + csv::join(header) + "), got " + std::to_string(f.size()));
    int cluster = 0, species = 0;
    double v[4];
    if (!csv::parse_int(f[0], cluster) || cluster < 1)
      throw SceneError(where + "cluster: expected an integer >= 1, got '" + f[0] + "'");
    for (int k = 0; k < 4; ++k)
      if (!csv::parse_double(f[k + 1], v[k]))
        throw SceneError(where + header[k + 1] + ": expected a number, got '" + f[k + 1] + "'");
    if (!(v[3] > 0.0)) throw SceneError(where + "radius: expected a positive radius, got '" + f[4] + "'");
    if (!csv::parse_int(f[5], species) || species < 1)
      throw SceneError(where + "species: expected an integer >= 1, got '" + f[5] + "'");
    if (dimension == 2 && v[1] != 0.0) throw SceneError(where + "y: expected 0 in 2D (disks in the x-z plane), got '" + f[2] + "'");
    const auto [it, added] = index.emplace(cluster, shapes.size());
    if (added) shapes.emplace_back();
    ClusterShape& s = shapes[it->second];
    const Vec3 x(v[0], v[1], v[2]);
    for (std::size_t m = 0; m < s.size(); ++m) {
      const double gap = (x - s.offsets[m]).norm() - v[3] - s.radii[m];
      if (gap < -1e-9 * std::min(v[3], s.radii[m]))
        throw SceneError(where + "cluster " + std::to_string(cluster) + ": this grain overlaps the one of line " +
                         std::to_string(lines[cluster][m]) + " by " + std::to_string(-gap) +
                         " m; members of a rigid cluster may touch but not overlap");
    }
    s.add(x, v[3], species);
    lines[cluster].push_back(line_no);
  }
  if (!seen_header) throw SceneError(path + ": empty file; expected the header '" + csv::join(header) + "'");
  if (shapes.empty()) throw SceneError(path + ": the cluster list has no rows");
  for (ClusterShape& s : shapes) s.centre(dimension);
  return shapes;
}

}  // namespace btr
