#pragma once
// Small pieces of the hand-written CSV readers of scene inputs (drop lists, cluster lists): fields of a
// line, and numbers parsed in full (std::from_chars: locale-independent, no partial matches).
#include <string>
#include <vector>

namespace btr::csv {

std::string trim(const std::string& s);
// The comma-separated fields of a line, each trimmed.
std::vector<std::string> split(const std::string& line);
std::string join(const std::vector<std::string>& fields);
// The whole string as a finite double (a leading '+' allowed); false otherwise.
bool parse_double(const std::string& s, double& out);
bool parse_int(const std::string& s, int& out);

}  // namespace btr::csv
