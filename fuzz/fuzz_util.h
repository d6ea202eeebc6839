// Shared by the harnesses: a checked property (abort, so libFuzzer and the replay test both fail),
// and a scratch file for readers that take a path.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#define FUZZ_CHECK(cond)                                                                  \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "%s:%d: FUZZ_CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)

namespace lanemap::fuzz {

// The scratch files this process wrote; removed when it exits normally (a crash leaves them, with
// the input that caused it, for whoever investigates).
class ScratchFiles {
 public:
  ~ScratchFiles() {
    for (const std::string& path : paths_) {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
  }
  void add(const std::string& path) { paths_.insert(path); }

 private:
  std::set<std::string> paths_;
};

// Writes the input to $TMPDIR/lanemap-fuzz-<pid>-<tag><suffix> (rewritten on every input).
inline std::string scratchFile(const uint8_t* data, size_t size, const std::string& tag, const std::string& suffix) {
  static const std::filesystem::path dir = std::filesystem::temp_directory_path();
  static ScratchFiles written;
  const std::string path =
      (dir / ("lanemap-fuzz-" + std::to_string(getpid()) + "-" + tag + suffix)).string();
  written.add(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  FUZZ_CHECK(out.good());
  return path;
}

}  // namespace lanemap::fuzz
