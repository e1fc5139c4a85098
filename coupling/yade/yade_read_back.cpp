// Reads what relax_yade.py wrote into a run folder and turns it into a RelaxResult, or an EngineFailure
// when the run failed: no or failed status, missing or malformed outputs, NaN, lost grains, grains outside
// the container, grains sunk into each other (a contact YADE missed), a stop reason the outputs contradict.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "coupling/dem/compaction_lines.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/overlap.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/yade/yade_script.h"

namespace btr {
namespace {

namespace fs = std::filesystem;

class Reader {
 public:
  explicit Reader(std::string dir) : dir_(std::move(dir)) {}

  // relax.cpp adds the tail of the log to the message.
  [[noreturn]] void fail(const std::string& what, FailureKind kind = FailureKind::BadOutput,
                         const nlohmann::json& values = nlohmann::json::object()) const {
    throw EngineFailure(kind, "YADE run in " + dir_ + ": " + what, values);
  }

  // Rows of numbers of a CSV output with exactly this header.
  std::vector<std::vector<double>> csv(const char* name, const std::string& header) const {
    const fs::path p = fs::path(dir_) / name;
    std::ifstream f(p);
    if (!f) fail("missing output " + p.string());
    std::string line;
    if (!std::getline(f, line) || line != header)
      fail(p.string() + ": line 1 is \"" + line + "\", expected \"" + header + "\"");
    const std::size_t columns = static_cast<std::size_t>(std::count(header.begin(), header.end(), ',')) + 1;
    std::vector<std::vector<double>> rows;
    for (std::size_t n = 2; std::getline(f, line); ++n) {
      if (line.empty()) continue;
      std::vector<double> row;
      std::stringstream ss(line);
      std::string cell;
      while (std::getline(ss, cell, ',')) {
        char* end = nullptr;
        const double v = std::strtod(cell.c_str(), &end);
        if (cell.empty() || *end != '\0') fail(p.string() + " line " + std::to_string(n) + ": \"" + cell + "\" is not a number");
        if (!std::isfinite(v))
          fail(p.string() + " line " + std::to_string(n) + ": non-finite value " + cell, FailureKind::NonFinite);
        row.push_back(v);
      }
      if (row.size() != columns)
        fail(p.string() + " line " + std::to_string(n) + ": " + std::to_string(row.size()) + " values, expected " +
             std::to_string(columns));
      rows.push_back(std::move(row));
    }
    return rows;
  }

  nlohmann::json status() const {
    const fs::path p = fs::path(dir_) / yade_files::kStatus;
    std::ifstream f(p);
    if (!f) fail("no status file " + p.string() + ": the script did not run to its end");
    try {
      return nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception& e) {
      fail(p.string() + " is not valid JSON: " + e.what());
    }
  }

 private:
  std::string dir_;
};

// Why a grain centre is outside the container (beyond one of its walls: an overlap larger than the radius,
// the grain went through), or "" if it is inside.
std::string outside(const std::vector<DemWall>& walls, int dimension, const Vec3& x) {
  char buf[160];
  for (const DemWall& w : walls) {
    const double d = w.distance(x);
    if (d < 0) {
      std::snprintf(buf, sizeof buf, "its centre is %.6g m beyond the %s wall", -d, w.name.c_str());
      return buf;
    }
  }
  if (dimension == 2 && x.y() != 0.0) {
    std::snprintf(buf, sizeof buf, "off the x-z plane (y = %.6g m)", x.y());
    return buf;
  }
  return "";
}

// An overlap this large (relative to the smaller radius; the grain's radius against a wall) is no contact
// the law could hold: the engine missed the contact and one grain went into the other.
constexpr double kMissedContactOverlap = 0.5;

// The last (time, kinetic energy) row of the script's kinetic history, read leniently (a failed run may
// end on "nan"); std::nullopt if there is none.
std::optional<std::pair<double, double>> last_kinetic_row(const std::string& dir) {
  std::ifstream f(fs::path(dir) / yade_files::kKinetic);
  std::string line, last;
  while (std::getline(f, line))
    if (!line.empty() && line.rfind("time", 0) != 0) last = line;
  const std::size_t comma = last.find(',');
  if (comma == std::string::npos) return std::nullopt;
  char* end = nullptr;
  const double t = std::strtod(last.c_str(), &end);
  const double e = std::strtod(last.c_str() + comma + 1, &end);
  return std::make_pair(t, e);
}

}  // namespace

EngineFailure yade_status_failure(const std::string& dir, const nlohmann::json& status, const Packing& original,
                                  const Scene& scene) {
  const std::string kind_name = status.value("failure_kind", "");
  const FailureKind kind = failure_kind_from_name(kind_name).value_or(FailureKind::EngineError);
  nlohmann::json values = nlohmann::json::object();
  if (kind == FailureKind::BlowUp || kind == FailureKind::NonFinite) {
    if (const auto row = last_kinetic_row(dir)) {
      values["time"] = std::isfinite(row->first) ? nlohmann::json(row->first) : nlohmann::json(nullptr);
      values["kinetic_energy"] = std::isfinite(row->second) ? nlohmann::json(row->second) : nlohmann::json(nullptr);
    }
    values["bound"] = kinetic_energy_bound(original.grains, scene);
  }
  if (status.contains("time") && status["time"].is_number()) values["engine_time"] = status["time"];
  if (status.contains("steps") && status["steps"].is_number()) values["steps"] = status["steps"];
  return EngineFailure(kind, "YADE run in " + dir + ": the script reports status \"" + status.value("status", "") +
                                 "\": " + status.value("message", "(no message)"),
                       values);
}

std::optional<EngineFailure> yade_failure_after_exit(const std::string& dir, const Packing& original,
                                                     const Scene& scene) {
  std::ifstream f(fs::path(dir) / yade_files::kStatus);
  if (!f) return std::nullopt;
  const nlohmann::json st = nlohmann::json::parse(f, nullptr, false);
  if (!st.is_object() || st.value("status", "") == "ok") return std::nullopt;
  return yade_status_failure(dir, st, original, scene);
}

RelaxResult yade_read_back(const std::string& dir, const Packing& original, const Scene& scene,
                           const RelaxPlan& plan) {
  const Reader in(dir);
  const nlohmann::json st = in.status();
  const std::string status = st.value("status", "");
  if (status != "ok") throw yade_status_failure(dir, st, original, scene);
  const std::string reason = st.value("stop_reason", "");
  if (plan.tap.enabled && reason != "taps")  // tapping ends after its last tap (yade_library.py tap())
    in.fail("stop reason \"" + reason + "\" in " + yade_files::kStatus + " is not \"taps\" (a tapping run)");
  if (!plan.tap.enabled && reason != "max-time" && reason != plan.stop_rule)
    in.fail("stop reason \"" + reason + "\" in " + yade_files::kStatus + " is neither the scene's rule \"" + plan.stop_rule +
            "\" nor max-time");

  RelaxResult result;
  result.stop_reason = reason;
  result.simulated_time = st.value("time", 0.0);
  result.wall_seconds = st.value("wall_seconds", 0.0);

  // Grains removed on an open floor (left the region): packing ids, each once.
  const std::size_t n = original.grains.size();
  std::vector<char> removed(n, 0);
  if (st.contains("removed") && st["removed"].is_array()) {
    for (const auto& v : st["removed"]) {
      const std::int64_t id = v.is_number_integer() ? v.get<std::int64_t>() : 0;
      if (id < 1 || id > static_cast<std::int64_t>(n) || removed[id - 1])
        in.fail("removed grain " + v.dump() + " in " + yade_files::kStatus + " is unknown or repeated");
      if (!plan.has_region)
        in.fail("grains were removed, but only an open floor removes grains", FailureKind::LostGrains);
      removed[id - 1] = 1;
      result.removed.push_back(id);
    }
  }
  if (reason != "max-time" && st.contains("stop_value") && st["stop_value"].is_number())
    result.stop_value = st["stop_value"].get<double>();
  if (st.contains("final_unbalanced_force") && st["final_unbalanced_force"].is_number())
    result.final_unbalanced_force = st["final_unbalanced_force"].get<double>();
  if (st.contains("compaction") && st["compaction"].is_object()) {
    const nlohmann::json& c = st["compaction"];
    result.compaction.ran = true;
    result.compaction.reached = c.value("reached", false);
    result.compaction.friction_scale = c.value("friction_scale", 0.0);
    result.compaction.time = c.value("time", 0.0);
    result.compaction.packing_fraction = c.value("packing_fraction", 0.0);
  }
  if (plan.compaction.enabled && !result.compaction.ran)
    in.fail("the compaction to the target packing fraction did not end (no compaction record)");
  if (plan.compaction.enabled && !plan.compaction.slabs.empty()) {
    // Each slab's end is a line of the log, in the LIGGGHTS script's format (compaction_lines.h).
    RelaxResult::Compaction logged;
    std::ifstream log(fs::path(dir) / yade_files::kLog);
    for (std::string line; std::getline(log, line);) read_compaction_line(line, logged);
    if (logged.slabs.size() != plan.compaction.slabs.size())
      in.fail(std::string(yade_files::kLog) + " has " + std::to_string(logged.slabs.size()) +
              " BTR-COMPACTION-SLAB lines, the plan " + std::to_string(plan.compaction.slabs.size()) + " slabs");
    result.compaction.slabs = logged.slabs;
  }

  // Final state: one row per grain still in the run, in id order.
  const auto rows = in.csv(yade_files::kFinal, "id,x,y,z,vx,vy,vz");
  const std::vector<DemWall> walls = dem_walls(scene.container, scene.dimension);
  if (rows.size() != n - result.removed.size())
    in.fail("lost grains: " + std::string(yade_files::kFinal) + " has " + std::to_string(rows.size()) +
                " grains, the packing " + std::to_string(n) + " (" + std::to_string(result.removed.size()) + " removed)",
            FailureKind::LostGrains, {{"grains", n}, {"returned", rows.size()}, {"removed", result.removed.size()}});
  result.relaxed.grains = original.grains;
  result.velocities.assign(n, Vec3::Zero());
  double max_speed = 0.0;
  std::size_t row = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (removed[i]) continue;
    const auto& r = rows[row++];
    if (r[0] != static_cast<double>(i + 1))
      in.fail(std::string(yade_files::kFinal) + " row " + std::to_string(row) + " has id " + std::to_string(r[0]) +
              ", expected " + std::to_string(i + 1));
    const Vec3 x(r[1], r[2], r[3]);
    const std::string why = outside(walls, scene.dimension, x);
    if (!why.empty())
      in.fail("grain " + std::to_string(i + 1) + " left the container: " + why, FailureKind::OutsideContainer,
              {{"grain", i + 1}});
    result.relaxed.grains[i].x = x;
    result.velocities[i] = Vec3(r[4], r[5], r[6]);
    max_speed = std::max(max_speed, result.velocities[i].norm());
  }
  // Nearest periodic image, as YADE should have seen each pair.
  Grains present;
  for (std::size_t i = 0; i < n; ++i)
    if (!removed[i]) present.push_back(result.relaxed.grains[i]);
  const OverlapReport overlap = largest_overlap(present, scene.dimension, scene.container);
  if (overlap.largest > kMissedContactOverlap)
    in.fail("grains went into each other: overlap " + overlap.describe() + " (YADE missed the contact)",
            FailureKind::MissedContact, {{"largest_overlap", overlap.largest}});

  for (const auto& r : in.csv(yade_files::kKinetic, "time,kinetic_energy")) result.kinetic_history.emplace_back(r[0], r[1]);
  if (result.kinetic_history.empty()) in.fail(std::string(yade_files::kKinetic) + " is empty");
  const double final_ke = result.kinetic_history.back().second;
  if (reason == "kinetic-energy" && !(final_ke < plan.kinetic_threshold))
    in.fail("stop reason is kinetic-energy but the last kinetic energy " + std::to_string(final_ke) +
            " J is not below the threshold " + std::to_string(plan.kinetic_threshold) + " J");
  if (reason == "max-time" && result.simulated_time < plan.max_time - 1.5 * plan.timestep)
    in.fail("stop reason is max-time but the run ended at t = " + std::to_string(result.simulated_time) + " s < " +
            std::to_string(plan.max_time) + " s");

  for (const auto& r : in.csv(yade_files::kContacts, "i,j,fn,overlap")) {
    const auto i = static_cast<std::int64_t>(r[0]), j = static_cast<std::int64_t>(r[1]);
    if (i < 1 || i > static_cast<std::int64_t>(n) || j < 0 || j > static_cast<std::int64_t>(n))
      in.fail(std::string(yade_files::kContacts) + ": contact " + std::to_string(i) + "-" + std::to_string(j) +
              " names a grain that does not exist");
    result.contacts.push_back({i, j, r[2]});
  }

  result.relaxed.meta = original.meta;
  result.relaxed.meta["relax"] = {
      {"engine", "yade"},
      {"model", scene.relax.model},
      {"stop_reason", reason},
      {"simulated_time", result.simulated_time},
      {"steps", st.value("steps", 0)},
      {"timestep", plan.timestep},
      {"timestep_rule", plan.timestep_rule},
      {"kinetic_threshold", plan.kinetic_threshold},
      {"final_kinetic_energy", final_ke},
      {"max_speed", max_speed},
      {"contacts", result.contacts.size()},
      {"wall_seconds", result.wall_seconds},
      {"steps_per_second", st.value("steps_per_second", 0.0)},            // whole script
      {"loop_steps_per_second", st.value("loop_steps_per_second", 0.0)},  // time stepping alone
      {"threads", st.value("threads", 0)},
      {"yade_version", st.value("yade_version", "")},
  };
  return result;
}

std::string yade_snapshot_file(std::size_t k) { return "yade_rot_" + std::to_string(k) + ".csv"; }

std::string yade_tap_file(long k) { return "yade_tap_" + std::to_string(k) + ".csv"; }

namespace {

// original's grains at the positions of dir/name (id,x,y,z, one row per grain, any order).
Grains read_positions(const Reader& in, const std::string& name, const Packing& original) {
  const auto rows = in.csv(name.c_str(), "id,x,y,z");
  const std::size_t n = original.grains.size();
  if (rows.size() != n)
    in.fail("lost grains: " + name + " has " + std::to_string(rows.size()) + " grains, the packing " + std::to_string(n),
            FailureKind::LostGrains, {{"grains", n}, {"returned", rows.size()}});
  Grains out = original.grains;
  std::vector<char> seen(n, 0);
  for (const auto& r : rows) {
    const double id = r[0];
    if (id < 1 || id > static_cast<double>(n) || id != std::floor(id) || seen[static_cast<std::size_t>(id) - 1])
      in.fail(name + ": unexpected or repeated grain id " + std::to_string(id));
    const std::size_t i = static_cast<std::size_t>(id) - 1;
    seen[i] = 1;
    out[i].x = Vec3(r[1], r[2], r[3]);
  }
  return out;
}

}  // namespace

Grains yade_read_snapshot(const std::string& dir, std::size_t k, const Packing& original) {
  return read_positions(Reader(dir), yade_snapshot_file(k), original);
}

std::vector<TapSnapshot> yade_read_taps(const std::string& dir, const Packing& original, const RelaxPlan& plan) {
  const Reader in(dir);
  const fs::path p = fs::path(dir) / yade_files::kTaps;
  std::ifstream f(p);
  if (!f) in.fail("missing output " + p.string() + ": no tap ended");
  const nlohmann::json records = nlohmann::json::parse(f, nullptr, false);
  if (!records.is_array()) in.fail(p.string() + " is not a JSON array of tap records");
  if (static_cast<long>(records.size()) != plan.tap.taps)
    in.fail(p.string() + " has " + std::to_string(records.size()) + " tap records, expected " +
            std::to_string(plan.tap.taps));
  std::vector<TapSnapshot> taps;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const nlohmann::json& r = records[i];
    const std::string where = p.string() + " record " + std::to_string(i + 1);
    auto number = [&](const char* key) {
      if (!r.is_object() || !r.contains(key) || !r[key].is_number())
        in.fail(where + ": missing or non-numeric \"" + key + "\"");
      const double v = r[key].get<double>();
      if (!std::isfinite(v)) in.fail(where + ": non-finite \"" + key + "\"", FailureKind::NonFinite);
      return v;
    };
    TapSnapshot t;
    t.tap = static_cast<long>(number("tap"));
    if (t.tap != static_cast<long>(i) + 1) in.fail(where + ": tap " + std::to_string(t.tap) + ", expected " + std::to_string(i + 1));
    t.moved_time = number("moved_time");
    t.moved_kinetic = number("moved_kinetic");
    t.rested_time = number("rested_time");
    t.rested_kinetic = number("rested_kinetic");
    t.step = static_cast<long>(number("step"));
    if (!r.contains("settled") || !r["settled"].is_boolean()) in.fail(where + ": missing \"settled\"");
    t.settled = r["settled"].get<bool>();
    t.floor_highest = number("floor_highest");
    t.floor_lowest = number("floor_lowest");
    t.floor_peak_speed = number("floor_peak_speed");
    t.floor_end = number("floor_end");
    t.grains = read_positions(in, yade_tap_file(t.tap), original);
    taps.push_back(std::move(t));
  }
  return taps;
}

}  // namespace btr
