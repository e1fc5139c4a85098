#pragma once
// Numbers as text for the engine inputs and messages: full round-trip precision, or 6 significant digits.
#include <cstdio>
#include <string>

namespace btr {

inline std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

inline std::string g6(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace btr
