// Speed limits of the atomic roads from their OSM ways' `maxspeed` (for Lanelet2's `speed_limit`,
// Lanelet2WriteOptions::speed_limit_kmh_by_road). A direction's own `maxspeed:forward` /
// `maxspeed:backward` wins over `maxspeed`; roads without a value that parses are left out (the
// writer then uses its documented default).
#pragma once

#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <map>

namespace lanemap::io {

std::map<int64_t, double> speedLimitsKmh(const skeleton::Skeleton& sk);

}  // namespace lanemap::io
