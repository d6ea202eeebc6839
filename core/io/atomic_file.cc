// Atomic file writing: temp file in the same folder + fsync + rename (see atomic_file.h).
#include "core/io/atomic_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <unistd.h>

namespace lanemap::io {
namespace {

std::string errnoText() { return std::strerror(errno); }

// Writes all bytes, retrying on short writes and EINTR. Returns false on error (errno set).
bool writeAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// Flushes the folder entry of `path` so the rename itself survives a power loss. Best effort.
void syncParentFolder(const std::string& path) {
  std::filesystem::path folder = std::filesystem::path(path).parent_path();
  if (folder.empty()) folder = ".";
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void writeFileAtomically(const std::string& path, const void* data, size_t size) {
  if (path.empty()) throw IoError("writeFileAtomically: empty path");
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw IoError("cannot create temporary file '" + tmp + "' for '" + path + "': " + errnoText());
  }
  const auto fail = [&](const std::string& what) {
    const std::string reason = errnoText();
    ::close(fd);
    ::unlink(tmp.c_str());
    throw IoError(what + " '" + path + "': " + reason);
  };
  if (!writeAll(fd, static_cast<const char*>(data), size)) fail("cannot write");
  if (::fsync(fd) != 0) fail("cannot fsync");
  if (::close(fd) != 0) {
    const std::string reason = errnoText();
    ::unlink(tmp.c_str());
    throw IoError("cannot close '" + tmp + "': " + reason);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string reason = errnoText();
    ::unlink(tmp.c_str());
    throw IoError("cannot rename '" + tmp + "' to '" + path + "': " + reason);
  }
  syncParentFolder(path);
}

void writeFileAtomically(const std::string& path, std::string_view content) {
  writeFileAtomically(path, content.data(), content.size());
}

}  // namespace lanemap::io
