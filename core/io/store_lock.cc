#include "core/io/store_lock.h"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace lanemap::io {
namespace {

std::string nowIso() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string hostName() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof(buf) - 1) != 0) return "?";
  return buf;
}

}  // namespace

std::string StoreLock::describeHolder(const std::string& lock_path) {
  std::ifstream in(lock_path);
  std::string role, pid, host, since;
  std::string line;
  while (std::getline(in, line)) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string k = line.substr(0, eq), v = line.substr(eq + 1);
    if (k == "process") role = v;
    if (k == "pid") pid = v;
    if (k == "host") host = v;
    if (k == "since") since = v;
  }
  if (pid.empty()) return "another process (the lock file names none)";
  return (role.empty() ? "a process" : role) + ", pid " + pid + " on " + (host.empty() ? "?" : host) +
         (since.empty() ? "" : ", since " + since);
}

StoreLock::StoreLock(const std::string& store, const std::string& role) {
  if (store.empty()) throw StoreError("no map store folder given");
  try {
    createDirectories(store);
  } catch (const IoError& e) {
    throw StoreError(std::string("cannot use map store: ") + e.what());
  }
  path_ = (std::filesystem::path(store) / (".lock-" + role)).string();
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    const int e = errno;
    throw StoreError("map store '" + store + "' cannot be written (" + std::strerror(e) + "): cannot create its lock file " + path_);
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    if (e == EWOULDBLOCK) {
      throw StoreInUseError("map store '" + store + "' is in use by " + describeHolder(path_) + " (lock file " + path_ +
                            "): stop that process or give this one another --store");
    }
    throw StoreError("cannot lock map store '" + store + "' (" + path_ + "): " + std::strerror(e));
  }
  std::ostringstream who;
  who << "process=" << role << "\npid=" << ::getpid() << "\nhost=" << hostName() << "\nsince=" << nowIso() << "\n";
  const std::string text = who.str();
  // The lock file is written in place (it is only read to name the holder); a full disk shows here.
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, text.data(), text.size(), 0) != static_cast<ssize_t>(text.size()) ||
      ::fsync(fd_) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw StoreError("map store '" + store + "' cannot be written (" + std::strerror(e) + "): " + path_);
  }
}

StoreLock::~StoreLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock; the file stays (a later holder rewrites it)
}

}  // namespace lanemap::io
