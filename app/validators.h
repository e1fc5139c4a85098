#pragma once
// Command-line validators whose refusals a person can read: "--np: expected a positive integer, got 0"
// (CLI11's own say "Value 0 not in range 0.000000 to 1.797...e308").
#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace btr_app {

// What CLI11 passes is the option's text; an empty return accepts it.
inline CLI::Validator number_check(const char* name, bool integer, double lo, bool lo_open, double hi,
                                   const std::string& expected) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        const bool whole = !integer || (std::isfinite(v) && v == std::floor(v) && text.find_first_of(".eE") == std::string::npos);
        if (used != text.size() || !std::isfinite(v) || !whole || (lo_open ? !(v > lo) : !(v >= lo)) || !(v <= hi))
          return "expected " + expected + ", got " + text;
        return "";
      },
      "", name);
}

inline CLI::Validator positive_number() { return number_check("POSITIVE", false, 0.0, true, HUGE_VAL, "a positive number"); }
inline CLI::Validator non_negative_number() {
  return number_check("NONNEGATIVE", false, 0.0, false, HUGE_VAL, "a number >= 0");
}
inline CLI::Validator positive_integer() { return number_check("POSITIVE", true, 0.0, true, HUGE_VAL, "a positive integer"); }
inline CLI::Validator non_negative_integer() {
  return number_check("NONNEGATIVE", true, 0.0, false, HUGE_VAL, "an integer >= 0");
}
// A number in [lo, hi], named by `expected` (e.g. "a damping in [0, 1)").
inline CLI::Validator number_in(double lo, double hi, const std::string& expected) {
  return number_check("RANGE", false, lo, false, hi, expected);
}

}  // namespace btr_app
