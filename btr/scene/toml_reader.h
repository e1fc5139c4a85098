#pragma once
// Typed access to the tables of a TOML file, each failure a SceneError naming file, line, key and
// what was expected. Internal to btr_core (toml++ is a private dependency): include only from btr/*.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <toml++/toml.h>
#include <vector>

#include "btr/scene/scene_toml.h"

namespace btr::toml_reader {

inline std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

inline std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// How a node is shown after "got".
inline std::string describe(const toml::node& n) {
  if (auto v = n.as_integer()) return std::to_string(v->get());
  if (auto v = n.as_floating_point()) return fmt(v->get());
  if (auto v = n.as_string()) return "the string " + quoted(v->get());
  if (auto v = n.as_boolean()) return v->get() ? "true" : "false";
  if (n.is_array()) return "an array";
  if (n.is_table()) return "a table";
  return "a date/time";
}

inline std::string join(const std::vector<std::string>& v, const std::string& sep = ", ") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

// One table of the file being read, with the dotted path used in messages.
struct Section {
  const toml::table* tbl = nullptr;
  std::string path;     // "grains.radius", "grains.component#2"
  std::string display;  // how unknown-key messages name it: "[container]", "grains.radius"
  int line = 0;
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(int line, const std::string& msg) const {
    throw SceneError(file_ + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + msg);
  }
  static int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

  [[noreturn]] void bad_value(const Section& s, const std::string& key, const toml::node& n,
                              const std::string& expect) const {
    fail(line_of(n), s.path + "." + key + ": expected " + expect + ", got " + describe(n));
  }
  [[noreturn]] void missing(const Section& s, const std::string& key, const std::string& expect) const {
    fail(s.line, s.path + "." + key + ": missing; expected " + expect);
  }

  void check_keys(const Section& s, const std::vector<std::string>& allowed) const {
    for (auto&& [k, v] : *s.tbl) {
      (void)v;
      if (std::find(allowed.begin(), allowed.end(), std::string(k.str())) == allowed.end())
        fail(static_cast<int>(k.source().begin.line),
             "unknown key '" + std::string(k.str()) + "' in " + s.display + "; allowed: " + join(allowed));
    }
  }

  const toml::node* get(const Section& s, const std::string& key) const { return s.tbl->get(key); }

  // A key that must be absent for this kind of thing.
  void forbid(const Section& s, const std::string& key, const std::string& why) const {
    if (auto n = get(s, key)) fail(line_of(*n), s.path + "." + key + ": not used " + why);
  }

  std::optional<double> number(const Section& s, const std::string& key, const std::function<bool(double)>& ok,
                               const std::string& expect) const {
    auto n = get(s, key);
    if (!n) return std::nullopt;
    double v;
    if (auto i = n->as_integer()) v = static_cast<double>(i->get());
    else if (auto f = n->as_floating_point()) v = f->get();
    else bad_value(s, key, *n, expect);
    if (!std::isfinite(v) || !ok(v)) bad_value(s, key, *n, expect);
    return v;
  }
  bool boolean_or(const Section& s, const std::string& key, bool def) const {
    auto n = get(s, key);
    if (!n) return def;
    if (auto b = n->as_boolean()) return b->get();
    bad_value(s, key, *n, "true or false");
  }
  double number_or(const Section& s, const std::string& key, double def, const std::function<bool(double)>& ok,
                   const std::string& expect) const {
    return number(s, key, ok, expect).value_or(def);
  }
  double required_number(const Section& s, const std::string& key, const std::function<bool(double)>& ok,
                         const std::string& expect) const {
    auto v = number(s, key, ok, expect);
    if (!v) missing(s, key, expect);
    return *v;
  }

  std::optional<std::int64_t> integer(const Section& s, const std::string& key,
                                      const std::function<bool(std::int64_t)>& ok, const std::string& expect) const {
    auto n = get(s, key);
    if (!n) return std::nullopt;
    auto i = n->as_integer();
    if (!i || !ok(i->get())) bad_value(s, key, *n, expect);
    return i->get();
  }

  std::optional<std::string> choice(const Section& s, const std::string& key,
                                    const std::vector<std::string>& options) const {
    auto n = get(s, key);
    if (!n) return std::nullopt;
    std::vector<std::string> q;
    for (const auto& o : options) q.push_back(quoted(o));
    const std::string expect = "one of " + join(q);
    auto str = n->as_string();
    if (!str || std::find(options.begin(), options.end(), str->get()) == options.end())
      bad_value(s, key, *n, expect);
    return str->get();
  }
  std::string required_choice(const Section& s, const std::string& key, const std::vector<std::string>& options) const {
    auto v = choice(s, key, options);
    if (!v) {
      std::vector<std::string> q;
      for (const auto& o : options) q.push_back(quoted(o));
      missing(s, key, "one of " + join(q));
    }
    return *v;
  }

  std::optional<std::string> string(const Section& s, const std::string& key, const std::string& expect) const {
    auto n = get(s, key);
    if (!n) return std::nullopt;
    auto str = n->as_string();
    if (!str || str->get().empty()) bad_value(s, key, *n, expect);
    return str->get();
  }

  // An array of numbers; `length` 0 means any non-empty length.
  std::optional<std::vector<double>> numbers(const Section& s, const std::string& key, std::size_t length,
                                             const std::function<bool(double)>& ok, const std::string& expect) const {
    auto n = get(s, key);
    if (!n) return std::nullopt;
    auto arr = n->as_array();
    if (!arr || arr->empty() || (length && arr->size() != length)) {
      if (arr) fail(line_of(*n), s.path + "." + key + ": expected " + expect + ", got an array of " +
                                     std::to_string(arr->size()));
      bad_value(s, key, *n, expect);
    }
    std::vector<double> out;
    for (const auto& e : *arr) {
      double v;
      if (auto i = e.as_integer()) v = static_cast<double>(i->get());
      else if (auto f = e.as_floating_point()) v = f->get();
      else fail(line_of(e), s.path + "." + key + ": expected " + expect + ", got an element " + describe(e));
      if (!std::isfinite(v) || !ok(v))
        fail(line_of(e), s.path + "." + key + ": expected " + expect + ", got an element " + describe(e));
      out.push_back(v);
    }
    return out;
  }

  std::optional<Section> table(const Section& s, const std::string& key, const std::string& display) const {
    auto n = get(s, key);
    if (!n) return std::nullopt;
    auto t = n->as_table();
    if (!t) bad_value(s, key, *n, "a table");
    return Section{t, s.path.empty() ? key : s.path + "." + key, display, line_of(*n)};
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

}  // namespace btr::toml_reader
