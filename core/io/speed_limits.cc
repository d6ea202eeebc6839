#include "core/io/speed_limits.h"

#include "core/io/lanelet2.h"

namespace lanemap::io {

std::map<int64_t, double> speedLimitsKmh(const skeleton::Skeleton& sk) {
  std::map<int64_t, double> out;
  for (const auto& road : sk.roads()) {
    const auto value = [&](const char* key) -> std::optional<double> {
      const auto it = road.tags.find(key);
      return it == road.tags.end() ? std::nullopt : parseMaxspeedKmh(it->second);
    };
    auto v = value(road.along_way ? "maxspeed:forward" : "maxspeed:backward");
    if (!v) v = value("maxspeed");
    if (v) out[road.id] = *v;
  }
  return out;
}

}  // namespace lanemap::io
