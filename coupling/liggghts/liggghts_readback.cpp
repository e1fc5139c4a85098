#include "coupling/liggghts/liggghts_readback.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "btr/model/number_text.h"
#include "coupling/dem/compaction_lines.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/liggghts/liggghts_script.h"
#include "coupling/liggghts/liggghts_tapping.h"

namespace btr {

namespace {

[[noreturn]] void fail(const std::string& file, const std::string& what, FailureKind kind = FailureKind::BadOutput,
                       const nlohmann::json& values = nlohmann::json::object()) {
  throw EngineFailure(kind, file + ": " + what, values);
}

// One snapshot of a LIGGGHTS dump: the column names after "ITEM: ATOMS" / "ITEM: ENTRIES" and the rows.
struct Dump {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  int column(const std::string& name, const std::string& file) const {
    for (std::size_t i = 0; i < columns.size(); ++i)
      if (columns[i] == name) return static_cast<int>(i);
    fail(file, "expected a column '" + name + "' in the dump");
  }
};

Dump read_dump(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "missing: the run did not write its final dump");
  Dump d;
  std::string line;
  long expected = -1;
  while (std::getline(in, line)) {
    if (line.rfind("ITEM: NUMBER OF", 0) == 0) {
      std::string n;
      if (!std::getline(in, n)) break;
      expected = std::atol(n.c_str());
    } else if (line.rfind("ITEM: ATOMS", 0) == 0 || line.rfind("ITEM: ENTRIES", 0) == 0) {
      auto words = words_of(line);
      d.columns.assign(words.begin() + 2, words.end());
      while (static_cast<long>(d.rows.size()) < expected && std::getline(in, line)) {
        auto f = words_of(line);
        if (f.size() != d.columns.size())
          fail(path, "row " + std::to_string(d.rows.size() + 1) + ": expected " + std::to_string(d.columns.size()) +
                         " values, got " + std::to_string(f.size()));
        std::vector<double> row(f.size());
        for (std::size_t i = 0; i < f.size(); ++i)
          if (!read_number(f[i], row[i]) || !std::isfinite(row[i]))
            fail(path,
                 "row " + std::to_string(d.rows.size() + 1) + ", column '" + d.columns[i] +
                     "': expected a finite number, got '" + f[i] + "'",
                 read_number(f[i], row[i]) ? FailureKind::NonFinite : FailureKind::BadOutput);
        d.rows.push_back(std::move(row));
      }
      break;
    }
  }
  if (expected < 0 || d.columns.empty()) fail(path, "not a LIGGGHTS dump (no ITEM: NUMBER OF / ATOMS section)");
  if (static_cast<long>(d.rows.size()) != expected)
    fail(path, "truncated: " + std::to_string(d.rows.size()) + " rows of " + std::to_string(expected));
  return d;
}

// The kind and numbers of the log's first failure line: the script's own blow-up guard ("BTR-FAILURE kinetic
// energy E J above the bound B J at t = T s", liggghts_script.cpp), LIGGGHTS' "ERROR: Lost atoms: original N
// current M", or any other ERROR (engine_error).
void classify_failure_line(const std::string& line, LiggghtsLog& log) {
  const std::vector<std::string> w = words_of(line);
  nlohmann::json values = {{"log_line", line}};
  log.failure_kind = FailureKind::EngineError;
  auto number_after = [&](const std::string& a, const std::string& b, const char* key) {
    for (std::size_t i = 0; i + 2 < w.size(); ++i) {
      double x;
      if (w[i] == a && w[i + 1] == b && read_number(w[i + 2], x))
        values[key] = std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
    }
  };
  if (line.rfind("BTR-FAILURE kinetic energy ", 0) == 0) {
    double e = 0.0;
    const bool parsed = w.size() > 3 && read_number(w[3], e);
    log.failure_kind = parsed && !std::isfinite(e) ? FailureKind::NonFinite : FailureKind::BlowUp;
    if (parsed) values["kinetic_energy"] = std::isfinite(e) ? nlohmann::json(e) : nlohmann::json(nullptr);
    number_after("the", "bound", "bound");
    number_after("t", "=", "time");
  } else if (line.find("Lost atoms") != std::string::npos) {
    log.failure_kind = FailureKind::LostGrains;
    for (std::size_t i = 0; i + 1 < w.size(); ++i) {
      double x;
      if ((w[i] == "original" || w[i] == "current") && read_number(w[i + 1], x)) values[w[i]] = x;
    }
  }
  log.failure_values = std::move(values);
}

}  // namespace

LiggghtsLog parse_liggghts_log(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "missing: LIGGGHTS wrote no log");
  LiggghtsLog log;
  std::string line;
  int col_time = -1, col_ke = -1;
  std::size_t n_cols = 0;
  bool in_thermo = false;
  double last_step = -1.0;
  while (std::getline(in, line)) {
    auto w = words_of(line);
    if (w.empty()) { in_thermo = false; continue; }
    // The script's thermo_style is "step time v_btr_ekin f_btr_kmean ..."; LIGGGHTS prints the header
    // with shortened names ("Step Time btr_ekin btr_kmea"), so the columns are taken by position.
    if (w[0] == "Step") {
      in_thermo = w.size() >= 4 && w[1] == "Time";
      n_cols = w.size();
      col_time = 1;
      col_ke = 2;
      continue;
    }
    if (line.rfind("BTR-FINAL ", 0) == 0) {
      for (std::size_t i = 0; i + 1 < w.size(); ++i)
        if (w[i] == "unbalanced-force") read_number(w[i + 1], log.final_unbalanced_force);
      continue;
    }
    if (read_compaction_line(line, log.compaction)) continue;
    if (line.rfind("BTR-STOP ", 0) == 0) {
      log.stop_reason = w.size() > 1 ? w[1] : "";
      for (std::size_t i = 0; i + 2 < w.size(); ++i)
        if (w[i] == "t" && w[i + 1] == "=") read_number(w[i + 2], log.stop_time);
        else if (w[i] == "value" && w[i + 1] == "=") read_number(w[i + 2], log.stop_value);
      continue;
    }
    if ((line.rfind("BTR-FAILURE", 0) == 0 || line.find("ERROR") != std::string::npos) && log.failure.empty()) {
      log.failure = line;
      classify_failure_line(line, log);
      continue;
    }
    if (!in_thermo) continue;
    if (w.size() != n_cols) { in_thermo = false; continue; }
    std::vector<double> v(w.size());
    bool numeric = true;
    for (std::size_t i = 0; i < w.size() && numeric; ++i) {
      numeric = read_number(w[i], v[i]);
    }
    if (!numeric) {
      // "nan" / "inf" parse as numbers; anything else ends the thermo block
      in_thermo = false;
      continue;
    }
    for (double x : v)
      if (!std::isfinite(x) && log.failure.empty()) {
        log.failure = "non-finite thermo output: " + line;
        log.failure_kind = FailureKind::NonFinite;
        log.failure_values = {{"log_line", line}};
      }
    if (col_time < 0 || col_ke < 0) continue;
    if (v[0] == last_step) continue;  // each run repeats the previous run's last row
    last_step = v[0];
    log.kinetic.emplace_back(v[col_time], v[col_ke]);
  }
  return log;
}

RelaxResult read_liggghts_result(const std::string& dir, const Packing& original, const Scene& scene,
                                 const RelaxPlan& plan) {
  namespace fs = std::filesystem;
  const std::string log_path = (fs::path(dir) / kLiggghtsLog).string();
  const LiggghtsLog log = parse_liggghts_log(log_path);
  if (!log.failure.empty()) fail(log_path, "the run failed: " + log.failure, log.failure_kind, log.failure_values);
  if (log.stop_reason.empty()) fail(log_path, "the run ended without reaching its stop rule (no BTR-STOP line)");

  RelaxResult res;
  res.stop_reason = log.stop_reason;
  res.simulated_time = log.stop_time;
  res.kinetic_history = log.kinetic;
  res.final_unbalanced_force = log.final_unbalanced_force;
  res.stop_value = log.stop_value;
  res.compaction = log.compaction;
  if (plan.compaction.enabled && !log.compaction.ran)
    fail(log_path, "the compaction to the target packing fraction did not end (no BTR-COMPACTION-END line)");

  const std::size_t n = original.grains.size();
  const std::string final_path = (fs::path(dir) / kLiggghtsFinalDump).string();
  const Dump atoms = read_dump(final_path);
  if (atoms.rows.size() != n && !(plan.has_region && atoms.rows.size() < n))
    fail(final_path, "lost atoms: " + std::to_string(atoms.rows.size()) + " grains of " + std::to_string(n),
         FailureKind::LostGrains, {{"grains", n}, {"returned", atoms.rows.size()}});
  const int c_id = atoms.column("id", final_path), c_x = atoms.column("x", final_path),
            c_y = atoms.column("y", final_path), c_z = atoms.column("z", final_path);
  const int c_vx = atoms.column("vx", final_path), c_vy = atoms.column("vy", final_path),
            c_vz = atoms.column("vz", final_path);
  res.relaxed.grains = original.grains;
  res.velocities.assign(n, Vec3::Zero());
  res.relaxed.meta = original.meta;
  std::vector<char> seen(n, 0);
  const std::vector<DemWall> walls = dem_walls(scene.container, scene.dimension);
  for (const auto& row : atoms.rows) {
    const double idv = row[c_id];
    if (idv < 1 || idv > static_cast<double>(n) || idv != std::floor(idv) || seen[static_cast<std::size_t>(idv) - 1])
      fail(final_path, "unexpected or repeated grain id " + std::to_string(idv));
    const std::size_t i = static_cast<std::size_t>(idv) - 1;
    seen[i] = 1;
    Grain& g = res.relaxed.grains[i];
    g.x = Vec3(row[c_x], row[c_y], row[c_z]);
    res.velocities[i] = Vec3(row[c_vx], row[c_vy], row[c_vz]);
    for (const DemWall& w : walls) {
      const std::string f = "f_force_" + liggghts_wall_id(w.name);
      double fn;
      if (w.kind == DemWall::Kind::Mesh) {  // the whole force of the mesh on the grain
        fn = std::sqrt(std::pow(row[atoms.column(f + "[1]", final_path)], 2) +
                       std::pow(row[atoms.column(f + "[2]", final_path)], 2) +
                       std::pow(row[atoms.column(f + "[3]", final_path)], 2));
      } else if (w.kind == DemWall::Kind::Cylinder) {
        const double fx = row[atoms.column(f + "[1]", final_path)], fy = row[atoms.column(f + "[2]", final_path)];
        const double rho = std::hypot(g.x.x(), g.x.y());
        fn = rho > 0 ? std::abs(fx * g.x.x() + fy * g.x.y()) / rho : std::hypot(fx, fy);
      } else {
        fn = std::abs(row[atoms.column(f + "[" + std::to_string(w.axis + 1) + "]", final_path)]);
      }
      if (fn > 0.0) res.contacts.push_back({static_cast<std::int64_t>(i) + 1, 0, fn});
    }
  }

  for (std::size_t i = 0; i < n; ++i)
    if (!seen[i]) res.removed.push_back(static_cast<std::int64_t>(i) + 1);  // only with a region (checked above)

  const std::string contacts_path = (fs::path(dir) / kLiggghtsContactsDump).string();
  const Dump pairs = read_dump(contacts_path);
  if (!pairs.rows.empty() && pairs.columns.size() != 7)
    fail(contacts_path, "expected 7 columns (id1 id2 periodic fn_x fn_y fn_z overlap), got " +
                            std::to_string(pairs.columns.size()));
  for (const auto& row : pairs.rows) {
    if (row[6] <= 0.0) continue;  // a neighbour pair not in contact
    auto a = static_cast<std::int64_t>(row[0]), b = static_cast<std::int64_t>(row[1]);
    if (a < 1 || b < 1 || a > static_cast<std::int64_t>(n) || b > static_cast<std::int64_t>(n))
      fail(contacts_path, "contact between unknown grain ids " + std::to_string(a) + " and " + std::to_string(b));
    if (a > b) std::swap(a, b);
    res.contacts.push_back({a, b, std::sqrt(row[3] * row[3] + row[4] * row[4] + row[5] * row[5])});
  }
  return res;
}

// The original's grains at the positions of a dump of every atom (id, x, y, z); throws EngineFailure for lost,
// unexpected or repeated ids.
static Grains grains_from_dump(const std::string& path, const Packing& original) {
  const Dump d = read_dump(path);
  const std::size_t n = original.grains.size();
  if (d.rows.size() != n)
    fail(path, "lost atoms: " + std::to_string(d.rows.size()) + " grains of " + std::to_string(n), FailureKind::LostGrains,
         {{"grains", n}, {"returned", d.rows.size()}});
  const int c_id = d.column("id", path), c_x = d.column("x", path), c_y = d.column("y", path), c_z = d.column("z", path);
  Grains out = original.grains;
  std::vector<char> seen(n, 0);
  for (const auto& row : d.rows) {
    const double idv = row[c_id];
    if (idv < 1 || idv > static_cast<double>(n) || idv != std::floor(idv) || seen[static_cast<std::size_t>(idv) - 1])
      fail(path, "unexpected or repeated grain id " + std::to_string(idv));
    const std::size_t i = static_cast<std::size_t>(idv) - 1;
    seen[i] = 1;
    out[i].x = Vec3(row[c_x], row[c_y], row[c_z]);
  }
  return out;
}

std::vector<TapSnapshot> read_liggghts_taps(const std::string& dir, const Packing& original, const RelaxPlan& plan) {
  namespace fs = std::filesystem;
  const std::string log_path = (fs::path(dir) / kLiggghtsLog).string();
  const long n_taps = plan.tap.taps;
  std::vector<TapSnapshot> taps(static_cast<std::size_t>(std::max(0L, n_taps)));
  std::vector<char> moved(taps.size(), 0), rested(taps.size(), 0);
  std::ifstream in(log_path);
  if (!in) fail(log_path, "missing: LIGGGHTS wrote no log");
  std::string line;
  // "BTR-TAP-MOVED k t = T kinetic = E", "BTR-TAP-RESTED k settled|max-rest t = T kinetic = E step = S"
  while (std::getline(in, line)) {
    const bool is_moved = line.rfind("BTR-TAP-MOVED ", 0) == 0, is_rested = line.rfind("BTR-TAP-RESTED ", 0) == 0;
    if (!is_moved && !is_rested) continue;
    const auto w = words_of(line);
    double k = 0, t = NAN, e = NAN, step = NAN;
    if (w.size() < 2 || !read_number(w[1], k) || k < 1 || k > n_taps || k != std::floor(k))
      fail(log_path, "unexpected tap line: " + line);
    for (std::size_t i = 0; i + 2 < w.size(); ++i) {
      if (w[i + 1] != "=") continue;
      if (w[i] == "t") read_number(w[i + 2], t);
      else if (w[i] == "kinetic") read_number(w[i + 2], e);
      else if (w[i] == "step") read_number(w[i + 2], step);
    }
    if (!std::isfinite(t) || !std::isfinite(e) || (is_rested && !std::isfinite(step)))
      fail(log_path, "non-finite or missing numbers in: " + line, FailureKind::NonFinite, {{"log_line", line}});
    const std::size_t i = static_cast<std::size_t>(k) - 1;
    TapSnapshot& snap = taps[i];
    snap.tap = static_cast<long>(k);
    if (is_moved) {
      snap.moved_time = t, snap.moved_kinetic = e, moved[i] = 1;
    } else {
      snap.rested_time = t, snap.rested_kinetic = e, snap.step = static_cast<long>(step), rested[i] = 1;
      snap.settled = w.size() > 2 && w[2] == "settled";
    }
  }
  for (std::size_t i = 0; i < taps.size(); ++i) {
    if (!moved[i] || !rested[i])
      fail(log_path, "tap " + std::to_string(i + 1) + " of " + std::to_string(n_taps) + " did not end (no BTR-TAP-" +
                         (moved[i] ? "RESTED" : "MOVED") + " line)");
    taps[i].grains = grains_from_dump((fs::path(dir) / liggghts_tap_dump(static_cast<long>(i) + 1)).string(), original);
  }
  return taps;
}

Grains read_liggghts_snapshot(const std::string& dir, std::size_t k, const Packing& original) {
  return grains_from_dump((std::filesystem::path(dir) / liggghts_snapshot_file(k)).string(), original);
}

}  // namespace btr
