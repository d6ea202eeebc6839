#include "processes/framework/share_dir.h"

#include <unistd.h>

#include <cstdlib>
#include <stdexcept>
#include <system_error>

namespace lanemap {

namespace fs = std::filesystem;

namespace {

bool hasConfig(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir / "config", ec);
}

}  // namespace

fs::path executableDir() {
  char exe[4096] = {0};
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
  return n > 0 ? fs::path(std::string(exe, static_cast<std::size_t>(n))).parent_path() : fs::path();
}

fs::path shareDir() {
  if (const char* env = std::getenv("LANEMAP_DATA_DIR"); env && *env) {
    if (!hasConfig(env)) {
      throw std::runtime_error(std::string("LANEMAP_DATA_DIR=") + env + " has no config/ folder");
    }
    return env;
  }
  const fs::path installed = executableDir().parent_path() / "share" / "lanemap";
  if (hasConfig(installed)) return installed;
#ifdef LANEMAP_SOURCE_DIR
  if (hasConfig(LANEMAP_SOURCE_DIR)) return LANEMAP_SOURCE_DIR;
#endif
  throw std::runtime_error("cannot find lanemap's shipped files (config/, models/, data/): looked in " +
                           installed.string() +
#ifdef LANEMAP_SOURCE_DIR
                           " and " LANEMAP_SOURCE_DIR +
#endif
                           std::string("; set LANEMAP_DATA_DIR"));
}

std::string shareFile(const std::string& relative) { return (shareDir() / relative).string(); }

std::string resolveShippedFile(const std::string& path) {
  std::error_code ec;
  if (path.empty() || fs::path(path).is_absolute() || fs::exists(path, ec)) return path;
  const fs::path shipped = shareDir() / path;
  return fs::exists(shipped, ec) ? shipped.string() : path;
}

}  // namespace lanemap
