#include "coupling/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <algorithm>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

namespace btr {
namespace fs = std::filesystem;

namespace {

// The permissions open(..., 0666) would give a new file: mkstemp makes it 0600.
mode_t new_file_mode() {
  static const mode_t mode = [] {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    return static_cast<mode_t>(0666 & ~mask);
  }();
  return mode;
}

}  // namespace

TempFile::TempFile(const fs::path& final_path) : final_(final_path) {
  // Hidden, and unique by mkstemp: concurrent runs into one folder never write the same temporary file.
  std::string pattern = (final_.parent_path() / ("." + final_.filename().string() + ".XXXXXX.tmp")).string();
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  const int fd = ::mkstemps(name.data(), 4);
  if (fd < 0)
    throw std::runtime_error(final_.string() + ": cannot create a temporary file beside it: " + std::strerror(errno));
  ::fchmod(fd, new_file_mode());
  ::close(fd);
  temp_ = fs::path(name.data());
}

TempFile::~TempFile() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void TempFile::commit() {
  if (std::rename(temp_.c_str(), final_.c_str()) != 0)
    throw std::runtime_error(final_.string() + ": cannot rename " + temp_.string() + " to it: " + std::strerror(errno));
  committed_ = true;
}

void write_text_file(const std::string& path, const std::string& content) {
  TempFile file{fs::path(path)};
  std::FILE* f = std::fopen(file.temp().c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot open " + file.temp().string() + ": " + std::strerror(errno));
  const bool written = std::fwrite(content.data(), 1, content.size(), f) == content.size();
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) throw std::runtime_error(path + ": write error: " + std::strerror(errno));
  file.commit();
}

void FileDigest::add(const void* data, std::size_t n) {
  const auto* p = static_cast<const Bytef*>(data);
  for (std::size_t done = 0; done < n;) {  // zlib takes at most uInt bytes at a time
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(n - done, 1u << 30));
    crc32 = static_cast<std::uint32_t>(::crc32(crc32, p + done, chunk));
    done += chunk;
  }
  bytes += n;
}

FileDigest digest_file(const fs::path& path) {
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, Closer> f(std::fopen(path.c_str(), "rb"));
  if (!f) throw std::runtime_error(path.string() + ": cannot open: " + std::strerror(errno));
  FileDigest d;
  std::vector<unsigned char> buffer(1 << 20);
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), f.get())) > 0) d.add(buffer.data(), n);
  if (std::ferror(f.get())) throw std::runtime_error(path.string() + ": read error: " + std::strerror(errno));
  return d;
}

}  // namespace btr
