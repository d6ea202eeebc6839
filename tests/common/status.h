// The counters of a STATUS message (status_t, processes/framework/process.h) for tests: one value
// by name, or all of them by name. A message whose arrays disagree with num_counters (a hostile
// or damaged one) is read as far as all three agree.
#pragma once

#include "lanemap/status_t.hpp"

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>

namespace lanemap::testing {

inline size_t statusCounterCount(const status_t& s) {
  return std::min({static_cast<size_t>(std::max(0, s.num_counters)), s.counter_names.size(), s.counter_values.size()});
}

// The counter `name` of `s`, `none` when it has no such counter.
inline int64_t statusCounter(const status_t& s, const std::string& name, int64_t none = -1) {
  for (size_t i = 0; i < statusCounterCount(s); ++i) {
    if (s.counter_names[i] == name) return s.counter_values[i];
  }
  return none;
}

// Every counter of `s` by name.
inline std::map<std::string, int64_t> statusCounters(const status_t& s) {
  std::map<std::string, int64_t> out;
  for (size_t i = 0; i < statusCounterCount(s); ++i) out[s.counter_names[i]] = s.counter_values[i];
  return out;
}

}  // namespace lanemap::testing
