// map::LaneMap as JSON, losslessly: every field, every coordinate as the double it is (a round trip
// gives the same map, bit for bit). Not a map format for anyone else (Lanelet2 and GeoJSON are):
// the intermediate a sharded fusion hands from its shard tasks to its assembly
// (lanemap-offline --shard / --assemble), where a Lanelet2 file would merge nodes within 5 cm and
// keep coordinates to the millimetre, and the assembled map would depend on how it was sharded.
#pragma once

#include "core/map/lane_map.h"

#include <nlohmann/json.hpp>

#include <string>

namespace lanemap::io {

nlohmann::json laneMapToJson(const map::LaneMap& map);
// Throws IoError (core/io/atomic_file.h) on JSON that is not laneMapToJson's.
map::LaneMap laneMapFromJson(const nlohmann::json& j);

// Files: written atomically; read back with the path in any error.
void writeLaneMapJson(const map::LaneMap& map, const std::string& path);
map::LaneMap readLaneMapJson(const std::string& path);

}  // namespace lanemap::io
