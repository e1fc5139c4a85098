#pragma once
// Writing a text file under a temporary name in its folder, then renaming it over the final name,
// so a failure never leaves a half-written file (or destroys the previous one).
#include <string>

namespace btr {

// Throws std::runtime_error naming the file.
void write_text_file(const std::string& path, const std::string& content);

}  // namespace btr
