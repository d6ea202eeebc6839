// Which lanes run on into a short road (core/lanes/carried_lanes.h): those of the mapped road that
// leads straight into it. One place for lanemap-offline and the lane mapper, so both carry the same.
// - The road before: of the roads ending at the short road's start intersection that are mapped
//   (have road lanelets) and have the same number of directions (one-way or two-way: the OSM line
//   is then where the lanes' offsets were measured from on both), the one whose heading at its end
//   turns least into the short road's heading at its start, if by at most carry_max_turn_rad. Not
//   its own reverse (a U-turn).
// - Its lanes: its through lanes, not the cross-section at its very end (a turn pocket opens
//   before the junction, and the lanes beside it shift over: neither runs on). Over its stations
//   every 2 m between its ROIs, the fewest lanes a station has; at the last station with that few,
//   each road lanelet there as its centre's lateral offset d in that road's Frenet frame, its two
//   bounds' distances from the centre and their types. (A lane gained mid-road that runs on through
//   the junction is missed: one lane too few, rather than a turn pocket carried straight on.)
#pragma once

#include "core/lanes/carried_lanes.h"
#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <map>
#include <vector>

namespace lanemap::mapping {

// Empty when no mapped road leads straight into `road`, or when `road` is not short (its stretch
// between its ROIs at least carry_lanes_max_m: never carried, not worth looking). *from_road: the
// road before (-1 if none).
std::vector<lanes::CarriedLane> lanesLeadingInto(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                 const std::map<int64_t, map::LaneMap>& mapped,
                                                 const lanes::ExplorerOptions& options, int64_t* from_road = nullptr);

}  // namespace lanemap::mapping
