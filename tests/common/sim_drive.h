// Test helpers: run a binary of build/bin and capture its output; make one short simulated drive
// per test binary (shared by its tests) in a temporary folder.
#pragma once

#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

namespace lanemap::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

inline CommandResult runCommand(const std::string& cmd) {
  CommandResult r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline std::string binPath(const std::string& name) { return std::string(LANEMAP_BIN_DIR) + "/" + name; }
inline std::string dataPath(const std::string& rel) { return std::string(LANEMAP_DATA_DIR) + "/" + rel; }

// A simulated drive made once and shared by every test process that asks for the same one
// (ctest runs each test case in its own process). Kept under build/test-data/, keyed by the
// arguments and the lanemap-sim binary's modification time, so a rebuilt simulator makes a new
// drive; a file lock makes concurrent test processes wait for the first one. Returns the drive's
// folder; fails the calling test if the simulator fails.
inline std::string sharedSimDrive(const std::string& osm_rel, double duration_s, uint64_t seed,
                                  const std::string& extra_args = "") {
  const std::string sim = binPath("lanemap-sim");
  struct stat st {};
  if (stat(sim.c_str(), &st) != 0) {
    ADD_FAILURE() << "no simulator at " << sim;
    return "";
  }
  std::string key = std::filesystem::path(osm_rel).stem().string() + "-d" + std::to_string(static_cast<int>(duration_s * 10)) +
                    "-s" + std::to_string(seed) + "-" + std::to_string(std::hash<std::string>{}(extra_args)) + "-" +
                    std::to_string(static_cast<long long>(st.st_mtime));
  const std::filesystem::path dir = std::filesystem::path(LANEMAP_BIN_DIR).parent_path() / "test-data";
  std::filesystem::create_directories(dir);
  const std::string out = (dir / key).string();
  const int lock = open((out + ".lock").c_str(), O_CREAT | O_RDWR, 0644);
  if (lock >= 0) flock(lock, LOCK_EX);
  if (!std::filesystem::exists(out + "/scenario.json")) {
    const auto r = runCommand(sim + " -q --force --osm " + dataPath(osm_rel) + " --out " + out + " --duration " +
                              std::to_string(duration_s) + " --seed " + std::to_string(seed) + " " + extra_args);
    if (r.exit_code != 0) ADD_FAILURE() << "lanemap-sim failed: " << r.output;
  }
  if (lock >= 0) {
    flock(lock, LOCK_UN);
    close(lock);
  }
  return out;
}

}  // namespace lanemap::testing
