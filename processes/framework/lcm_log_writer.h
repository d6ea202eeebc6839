// Writes an LCM log file (what lcm-logger writes and lcm-logplayer plays) one event at a time:
// numbers the events in order and encodes lcmtypes messages. Used where lanemap writes logs itself
// (lanemap-sim's drive.lcmlog, lanemap-segmenter --log-out, tests that build a log).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap {

class LcmLogWriter {
 public:
  // Throws std::runtime_error when the file cannot be opened for writing.
  explicit LcmLogWriter(const std::string& path) : path_(path), log_(path, "w") {
    if (!log_.good()) throw std::runtime_error("cannot write LCM log '" + path + "'");
  }

  // One event of `size` bytes on `channel`, stamped `timestamp` (microseconds). Throws
  // std::runtime_error when the write fails.
  void write(const std::string& channel, int64_t timestamp, const void* data, size_t size) {
    lcm::LogEvent ev;
    ev.eventnum = events_;
    ev.timestamp = timestamp;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(size);
    ev.data = const_cast<void*>(data);
    if (log_.writeEvent(&ev) != 0) throw std::runtime_error("writing LCM log '" + path_ + "' failed (disk full?)");
    ++events_;
  }

  // An lcmtypes message (anything with getEncodedSize/encode), encoded.
  template <typename T>
  void message(const std::string& channel, int64_t timestamp, const T& msg) {
    buf_.resize(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(buf_.data(), 0, static_cast<int>(buf_.size()));
    write(channel, timestamp, buf_.data(), buf_.size());
  }

  int64_t events() const { return events_; }

 private:
  std::string path_;
  lcm::LogFile log_;
  int64_t events_ = 0;
  std::vector<uint8_t> buf_;
};

}  // namespace lanemap
