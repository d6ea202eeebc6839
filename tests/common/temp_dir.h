// The tests' one temporary folder: a fresh folder under the system's temporary directory, named
// lanemap-<tag>-<pid>-<n>, removed (with what is in it) at destruction. A test makes one on its
// stack; a test file whose tests share scratch files makes one at file scope (removed at exit).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace lanemap::testing {

class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    path_ = std::filesystem::temp_directory_path() /
            ("lanemap-" + tag + "-" + std::to_string(getpid()) + "-" + std::to_string(counter()++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  // The folder, or a path inside it.
  std::string str(const std::string& rel = "") const { return rel.empty() ? path_.string() : (path_ / rel).string(); }
  // Writes `text` to the file `name` inside the folder; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::string p = str(name);
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

 private:
  static int& counter() {
    static int c = 0;
    return c;
  }
  std::filesystem::path path_;
};

}  // namespace lanemap::testing
