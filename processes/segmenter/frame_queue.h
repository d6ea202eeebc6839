// A bounded hand-over queue between the LCM thread and a worker that keeps the NEWEST items: when
// full, push() drops the oldest (and says how many it dropped), so a slow consumer always works on
// recent frames and memory stays bounded. Header-only so tests can exercise it directly.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace lanemap::segmenter {

template <typename T>
class DropOldestQueue {
 public:
  explicit DropOldestQueue(size_t capacity) : capacity_(capacity) {
    if (capacity_ == 0) throw std::invalid_argument("DropOldestQueue: capacity must be >= 1");
  }

  // Adds an item; returns the number of old items dropped to make room (0 or 1).
  size_t push(T item) {
    size_t dropped = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      while (items_.size() >= capacity_) {
        items_.pop_front();
        ++dropped;
      }
      items_.push_back(std::move(item));
      max_depth_ = std::max(max_depth_, items_.size());
    }
    cv_.notify_one();
    return dropped;
  }

  // Waits up to `timeout` for an item; nullopt on timeout or after close() once empty.
  std::optional<T> pop(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, timeout, [this] { return !items_.empty() || closed_; });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }

  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }

  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  size_t maxDepth() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return max_depth_;
  }
  size_t capacity() const { return capacity_; }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<T> items_;
  size_t max_depth_ = 0;
  bool closed_ = false;
};

}  // namespace lanemap::segmenter
