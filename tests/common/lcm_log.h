// Reading LCM log files in tests: every event (channel, payload bytes, timestamp), grouped by
// channel, and a tolerant reader for a log another process is still writing.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lanemap::testing {

struct LogMessage {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t timestamp = 0;  // when it was logged (microseconds since the epoch)
};

// Every complete event of the log (a half-written last event is left out). Empty when the file
// cannot be opened.
inline std::vector<LogMessage> readLcmLog(const std::string& path) {
  std::vector<LogMessage> out;
  lcm::LogFile log(path, "r");
  if (!log.good()) return out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.push_back({ev->channel, std::vector<uint8_t>(p, p + ev->datalen), ev->timestamp});
  }
  return out;
}

// The payloads of each channel, in log order.
inline std::map<std::string, std::vector<std::vector<uint8_t>>> byChannel(const std::vector<LogMessage>& log) {
  std::map<std::string, std::vector<std::vector<uint8_t>>> out;
  for (const auto& m : log) out[m.channel].push_back(m.data);
  return out;
}

inline std::size_t countChannel(const std::vector<LogMessage>& log, const std::string& channel) {
  std::size_t n = 0;
  for (const auto& m : log) n += m.channel == channel;
  return n;
}

}  // namespace lanemap::testing
