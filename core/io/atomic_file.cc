// Atomic file writing: temp file in the same folder + fsync + rename + fsync of the folder (see
// atomic_file.h).
#include "core/io/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <string>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace lanemap::io {
namespace {

std::atomic<WriteStepHook> g_hook{nullptr};

void step(WriteStep s, const std::string& path) {
  if (WriteStepHook h = g_hook.load(std::memory_order_relaxed)) h(s, path);
}

std::string errnoText(int e) { return std::strerror(e); }

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

std::string folderOf(const std::string& path) {
  std::string folder = std::filesystem::path(path).parent_path().string();
  return folder.empty() ? "." : folder;
}

// Flushes a folder (its entries: a rename, a new file, a removal) to disk. Throws IoError when
// the folder cannot be opened or flushed; file systems that cannot fsync a folder (EINVAL) are
// taken as flushed.
void syncFolder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw IoError("cannot open folder '" + folder + "' to flush it: " + errnoText(errno));
  const int rc = ::fsync(fd);
  const int e = errno;
  ::close(fd);
  if (rc != 0 && e != EINVAL) throw IoError("cannot flush folder '" + folder + "': " + errnoText(e));
  step(WriteStep::kFolderSynced, folder);
}

}  // namespace

void setWriteStepHook(WriteStepHook hook) { g_hook.store(hook); }

void writeFileAtomically(const std::string& path, const void* data, size_t size) {
  if (path.empty()) throw IoError("writeFileAtomically: empty path");
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw IoError("cannot create temporary file '" + tmp + "' for '" + path + "': " + errnoText(errno));
  }
  const auto fail = [&](const std::string& what) {
    const std::string reason = errnoText(errno);
    ::close(fd);
    ::unlink(tmp.c_str());
    throw IoError(what + " '" + path + "': " + reason);
  };
  step(WriteStep::kTemporaryCreated, path);
  const char* bytes = static_cast<const char*>(data);
  const size_t half = size / 2;
  if (!writeAll(fd, bytes, half)) fail("cannot write");
  step(WriteStep::kHalfWritten, path);
  if (!writeAll(fd, bytes + half, size - half)) fail("cannot write");
  step(WriteStep::kWritten, path);
  if (::fsync(fd) != 0) fail("cannot fsync");
  step(WriteStep::kFileSynced, path);
  if (::close(fd) != 0) {
    const std::string reason = errnoText(errno);
    ::unlink(tmp.c_str());
    throw IoError("cannot close '" + tmp + "': " + reason);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string reason = errnoText(errno);
    ::unlink(tmp.c_str());
    throw IoError("cannot rename '" + tmp + "' to '" + path + "': " + reason);
  }
  step(WriteStep::kRenamed, path);
  syncFolder(folderOf(path));
}

void writeFileAtomically(const std::string& path, std::string_view content) {
  writeFileAtomically(path, content.data(), content.size());
}

void createDirectories(const std::string& dir_in) {
  std::string dir = dir_in;
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  if (dir.empty()) throw IoError("createDirectories: empty path");
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) return;
  const std::filesystem::path p(dir);
  if (p.has_parent_path() && p.parent_path() != p) createDirectories(p.parent_path().string());
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) {
    throw IoError("cannot create folder '" + dir + "': " + errnoText(errno));
  }
  if (!std::filesystem::is_directory(dir, ec)) throw IoError("'" + dir + "' exists and is not a folder");
  syncFolder(folderOf(dir));
}

bool removeFileDurably(const std::string& path) {
  if (::unlink(path.c_str()) != 0) {
    if (errno == ENOENT) return false;
    throw IoError("cannot remove '" + path + "': " + errnoText(errno));
  }
  step(WriteStep::kRemoved, path);
  syncFolder(folderOf(path));
  return true;
}

void renameFileDurably(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0) {
    throw IoError("cannot rename '" + from + "' to '" + to + "': " + errnoText(errno));
  }
  step(WriteStep::kRenamed, to);
  syncFolder(folderOf(to));
}

int removeStaleTemporaries(const std::string& dir) {
  int removed = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const size_t at = name.rfind(".tmp.");
    if (at == std::string::npos || at == 0) continue;
    const std::string pid_text = name.substr(at + 5);
    if (pid_text.empty() || pid_text.size() > 9 || pid_text.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(pid_text));
    if (pid <= 0 || (::kill(pid, 0) != 0 && errno == ESRCH)) {  // EPERM: someone else's, running
      std::error_code rm;
      if (std::filesystem::remove(it->path(), rm)) ++removed;
    }
  }
  return removed;
}

}  // namespace lanemap::io
