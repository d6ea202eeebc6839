#include "core/bev/checkpoint_writer.h"

#include "core/bev/bev_store.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <optional>

namespace lanemap::bev {

CheckpointWriter::CheckpointWriter(std::string store) : store_(std::move(store)), thread_([this] { loop(); }) {}

CheckpointWriter::~CheckpointWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void CheckpointWriter::write(RoadBev road, int64_t last_frame_utime) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const int64_t id = road.road_id;
    const auto it = std::find_if(queue_.begin(), queue_.end(), [&](const Job& j) { return j.road.road_id == id; });
    if (it != queue_.end()) {
      it->road = std::move(road);  // keeps its place in the order
      it->last_frame_utime = last_frame_utime;
      ++stats_.replaced;
      return;
    }
    queue_.push_back(Job{std::move(road), last_frame_utime});
  }
  cv_.notify_all();
}

void CheckpointWriter::cancel(int64_t road_id) {
  std::unique_lock<std::mutex> lock(mutex_);
  queue_.erase(std::remove_if(queue_.begin(), queue_.end(), [&](const Job& j) { return j.road.road_id == road_id; }),
               queue_.end());
  cv_.wait(lock, [&] { return writing_ != road_id; });
}

void CheckpointWriter::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] { return queue_.empty() && writing_ < 0; });
}

CheckpointWriter::Stats CheckpointWriter::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

std::vector<std::string> CheckpointWriter::takeErrors() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> out;
  out.swap(errors_);
  return out;
}

void CheckpointWriter::setBeforeWriteHook(std::function<void(int64_t)> hook) {
  std::lock_guard<std::mutex> lock(mutex_);
  before_write_ = std::move(hook);
}

void CheckpointWriter::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stop_, nothing waiting
    std::optional<Job> job(std::move(queue_.front()));
    queue_.pop_front();
    writing_ = job->road.road_id;
    const auto hook = before_write_;
    lock.unlock();
    if (hook) hook(job->road.road_id);
    const auto t0 = std::chrono::steady_clock::now();
    std::string error;
    try {
      storeCheckpoint(store_, job->road, job->last_frame_utime);
    } catch (const std::exception& e) {
      error = "road " + std::to_string(job->road.road_id) + ": " + e.what();
    }
    const int64_t us =
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0).count();
    const int64_t kb = static_cast<int64_t>(job->road.grid.memoryBytes() / 1024);
    job.reset();  // the grid freed outside the lock
    lock.lock();
    if (error.empty()) {
      ++stats_.written;
      stats_.us_total += us;
      stats_.us_max = std::max(stats_.us_max, us);
      stats_.kb = kb;
    } else {
      ++stats_.failed;
      errors_.push_back(error);
    }
    writing_ = -1;
    cv_.notify_all();
  }
}

}  // namespace lanemap::bev
