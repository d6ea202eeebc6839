// The wall clock as LCM utimes count time: microseconds since the Unix epoch (system_clock). The
// one place lanemap reads it: receive times of drivers, STATUS times, latencies. (Intervals that
// must not jump with the clock use std::chrono::steady_clock instead.)
#pragma once

#include <chrono>
#include <cstdint>

namespace lanemap::geo {

inline int64_t wallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace lanemap::geo
