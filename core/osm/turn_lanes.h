// OSM `turn:lanes` (https://wiki.openstreetmap.org/wiki/Key:turn): one entry per lane, left to
// right in the driving direction, separated by '|'; an entry lists the lane's movements separated
// by ';' (left, slight_left, sharp_left, through, right, ..., merge_to_left, reverse, none).
// One reader of the tag for the mapper's lane pairing (core/intersections) and the simulator's
// world (core/sim/world_builder): both read the same OSM tag the same way; what they do with it
// (the mapper's pairing inference, the world's richer junction rules) stays apart.
#pragma once

#include <string>
#include <vector>

namespace lanemap::osm {

// The movements one lane's entry allows. Unspecified for "" and "none" (the tag says nothing of
// the lane). Any left (slight, sharp) or right movement counts as a turn that way; through and the
// merge_to_* entries (the lane ends by merging, going on straight) as straight; reverse a U-turn.
struct LaneMovements {
  bool specified = false;
  bool left = false, straight = false, right = false, reverse = false;
};

LaneMovements parseTurnLane(const std::string& entry);

// A turn:lanes value split at '|', left to right, empty entries kept ("left||right": 3 lanes).
std::vector<std::string> splitTurnLanes(const std::string& value);

// Number of lanes a turn:lanes value names, -1 for an empty value.
int turnLaneCount(const std::string& value);

}  // namespace lanemap::osm
