// Reading an LCM log that may be damaged: a recording cut short (the logger killed, the power
// lost, the disk full) or bytes overwritten. lcm::LogFile skips garbage up to the next event's sync
// word and stops at the first event it cannot read whole; LogReader notes both, so a tool that
// maps what it could read can say what it could not: events read, bytes skipped between events,
// bytes left after the last whole event.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

namespace lanemap {

class LogReader {
 public:
  // Throws std::runtime_error naming the file when it cannot be opened.
  explicit LogReader(const std::string& path) : path_(path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw std::runtime_error("no such log file: " + path);
    size_ = static_cast<int64_t>(std::filesystem::file_size(path, ec));
    log_ = std::make_unique<lcm::LogFile>(path, "r");
    if (!log_->good()) throw std::runtime_error("cannot read LCM log: " + path);
  }

  // The next whole event, nullptr at the end (of the file or of what is readable). Where lcm
  // cannot read an event (a bad sync word or header, a cut event) the reader goes on from the next
  // sync word that starts a readable event; the bytes passed over count as skipped.
  const lcm::LogEvent* next() {
    std::FILE* f = log_->getFilePtr();
    for (;;) {
      const lcm::LogEvent* ev = log_->readNextEvent();
      const int64_t pos = std::ftell(f);
      if (ev) {
        // sync word, event number, timestamp, channel length, data length, channel, data
        const int64_t bytes = 4 + 8 + 8 + 4 + 4 + static_cast<int64_t>(ev->channel.size()) + ev->datalen;
        skipped_ += std::max<int64_t>(0, pos - bytes - end_);
        end_ = pos;
        ++events_;
        return ev;
      }
      const int64_t sync = findSync(f, std::max(end_, resync_from_ + 1));
      if (sync < 0) {
        unread_ = std::max<int64_t>(0, size_ - end_);
        return nullptr;
      }
      resync_from_ = sync;
      std::fseek(f, static_cast<long>(sync), SEEK_SET);
    }
  }

  const std::string& path() const { return path_; }
  int64_t fileSize() const { return size_; }
  int64_t position() const { return std::ftell(log_->getFilePtr()); }
  int64_t events() const { return events_; }
  int64_t bytesSkipped() const { return skipped_; }  // garbage between whole events
  int64_t bytesUnread() const { return unread_; }    // after the last whole event (once next() gave nullptr)
  int64_t lastEventEnd() const { return end_; }
  bool damaged() const { return skipped_ > 0 || unread_ > 0; }
  // "1234 events read; 56 bytes of garbage skipped between events; the last 789 bytes (from byte
  // 10000 of 10789) are not a whole event: the log is cut short or corrupt there"
  std::string damageReport() const {
    std::string s = std::to_string(events_) + " events read";
    if (skipped_ > 0) s += "; " + std::to_string(skipped_) + " bytes of garbage skipped between events";
    if (unread_ > 0) {
      s += "; the last " + std::to_string(unread_) + " bytes (from byte " + std::to_string(end_) + " of " +
           std::to_string(size_) + ") are not a whole event: the log is cut short or corrupt there";
    }
    return s;
  }

 private:
  // The offset of the first sync word (0xEDA1DA01, big-endian) at or after `from`, -1 if none.
  int64_t findSync(std::FILE* f, int64_t from) const {
    if (from >= size_ || std::fseek(f, static_cast<long>(from), SEEK_SET) != 0) return -1;
    uint32_t window = 0;
    int64_t at = from;
    int n = 0;
    for (int c; (c = std::fgetc(f)) != EOF; ++at) {
      window = (window << 8) | static_cast<uint32_t>(c);
      if (++n >= 4 && window == 0xEDA1DA01u) return at - 3;
    }
    return -1;
  }

  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t size_ = 0, end_ = 0, events_ = 0, skipped_ = 0, unread_ = 0;
  int64_t resync_from_ = -1;
};

}  // namespace lanemap
