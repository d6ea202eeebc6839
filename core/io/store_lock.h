// One writer per part of the map store: a process that writes into a store (the BEV builder its
// bev/, the lane mapper its lanes/ and lane_map.osm) holds <store>/.lock-<role> with flock() for
// its whole life. A second one started on the same store gets a StoreInUseError naming the holder
// (process, pid, host, since when) instead of two writers interleaving their files. The kernel
// drops the lock when the holder exits or is killed (kill -9, a crash), so a stale lock file never
// blocks a restart. Taking the lock is also where a store that cannot be written (read-only, no
// permission, full disk) is found: a StoreError with the reason, before any work.
#pragma once

#include "core/io/atomic_file.h"

#include <string>

namespace lanemap::io {

// The store cannot be used (cannot be created, opened or written).
class StoreError : public IoError {
 public:
  using IoError::IoError;
};
// Another process holds the store's lock for this role.
class StoreInUseError : public StoreError {
 public:
  using StoreError::StoreError;
};

// Exit codes of the processes for these (documented in docs/robustness.md). 3 is the framework's
// "cannot open LCM", which a restart may cure; a store held by another process is 4, which
// lanemap-launch never restarts (it would only fail again).
inline constexpr int kExitStoreError = 2;
inline constexpr int kExitStoreInUse = 4;

class StoreLock {
 public:
  // Creates the store folder if needed and takes <store>/.lock-<role>. Throws StoreInUseError or
  // StoreError.
  StoreLock(const std::string& store, const std::string& role);
  ~StoreLock();
  StoreLock(const StoreLock&) = delete;
  StoreLock& operator=(const StoreLock&) = delete;

  const std::string& path() const { return path_; }
  // What the lock file says about its holder ("bev_builder, pid 123 on car1, since 2026-...").
  static std::string describeHolder(const std::string& lock_path);

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace lanemap::io
