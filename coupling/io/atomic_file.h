#pragma once
// Files written whole or not at all: each is written under a unique temporary name in its final folder
// and renamed over the final name only when complete, so a failure or a crash never leaves a half-written
// file, and two runs writing into the same folder never share a temporary file.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace btr {

// A file being written under a unique temporary name beside its final path; removed unless committed.
class TempFile {
 public:
  // Creates the temporary file (empty, exclusively, with the permissions a new file gets). Throws
  // std::runtime_error naming the final path.
  explicit TempFile(const std::filesystem::path& final_path);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  const std::filesystem::path& temp() const { return temp_; }
  const std::filesystem::path& final_path() const { return final_; }
  void commit();  // renames the temporary file over the final one; throws std::runtime_error

 private:
  std::filesystem::path final_, temp_;
  bool committed_ = false;
};

// Writes `content` to path through a TempFile. Throws std::runtime_error naming the file.
void write_text_file(const std::string& path, const std::string& content);

// Size and CRC-32 (zlib's) of a file's bytes, the record that ties a packing's files to its JSON.
struct FileDigest {
  std::uint64_t bytes = 0;
  std::uint32_t crc32 = 0;  // of no bytes: 0
  bool operator==(const FileDigest& o) const { return bytes == o.bytes && crc32 == o.crc32; }
  // The digest of the bytes so far followed by data[0, n): a writer digests what it writes as it goes.
  void add(const void* data, std::size_t n);
};
// Throws std::runtime_error naming the file if it cannot be read.
FileDigest digest_file(const std::filesystem::path& path);

}  // namespace btr
