// Checkpoints of open roads (bev_store.h storeCheckpoint) written in a thread of their own, so the
// caller, the BEV builder's LCM thread, never waits for a disk: a checkpoint is written atomically
// and durably (fsync), which took 100-150 ms a time on a shared VM's disk, once a second, and
// frames queued behind it (the live graph's frame-to-BEV p99: 140 ms with checkpoints inline, 12 ms
// without them; issue 17).
//
// Writes happen in the order asked. A write asked while an earlier one of the same road is still
// waiting replaces it (the newer grid holds everything the older one did). cancel(road) is the
// barrier the store's crash rules need: when it returns, no write of that road is waiting or in
// progress, so the caller can store the road (storeRoad) and remove its checkpoint knowing no
// older checkpoint lands after them (loadCheckpoints would then take a stored road for an open one).
#pragma once

#include "core/bev/road_bev.h"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace lanemap::bev {

class CheckpointWriter {
 public:
  explicit CheckpointWriter(std::string store);
  ~CheckpointWriter();  // writes what is waiting, then stops
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;

  // Queues the road's checkpoint (a copy of it: the caller goes on changing its own); returns at
  // once. last_frame_utime: the newest frame projected into it.
  void write(RoadBev road, int64_t last_frame_utime);
  // Drops the road's waiting writes and waits for one in progress to end.
  void cancel(int64_t road_id);
  // Returns when every write asked so far is done (or failed).
  void drain();

  struct Stats {
    int64_t written = 0, failed = 0, replaced = 0;  // replaced: dropped for a newer write of the road
    int64_t us_total = 0, us_max = 0;               // time to write one (grid + JSON, durable)
    int64_t kb = 0;                                 // the last written grid's memory
  };
  Stats stats() const;
  // Errors since the last call ("road N: why"), for the caller to print and count.
  std::vector<std::string> takeErrors();

  // Tests only: called in the writer's thread before each write, with the road id.
  void setBeforeWriteHook(std::function<void(int64_t)> hook);

 private:
  struct Job {
    RoadBev road;
    int64_t last_frame_utime = 0;
  };
  void loop();

  const std::string store_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> queue_;
  int64_t writing_ = -1;  // the road being written, -1: none
  bool stop_ = false;
  Stats stats_;
  std::vector<std::string> errors_;
  std::function<void(int64_t)> before_write_;
  std::thread thread_;  // last: starts once the rest is made
};

}  // namespace lanemap::bev
