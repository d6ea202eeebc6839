// Which lanes run on into a short road (core/lanes/carried_lanes.h): those of the mapped road that
// leads straight into it, else of the mapped road it leads straight into. One place for
// lanemap-offline and the lane mapper, so both carry the same.
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
// - The road after (when no road before qualifies: the car turned into the link, or the road
//   straight before it was not driven): the same rules at the short road's end, its through lanes
//   at the first station with the fewest lanes. It is mapped after the link (the car closes it
//   later), so the callers map a short road left with no lane again when a road meeting it gets
//   lanes (roadsAwaitingLanesFrom).
#pragma once

#include "core/lanes/carried_lanes.h"
#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <map>
#include <set>
#include <vector>

namespace lanemap::mapping {

// Whether `road` is short enough to take carried lanes: its stretch between its ROIs under
// carry_lanes_max_m.
bool isShortRoad(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& options);

// Empty when no mapped road leads straight into `road`, or when `road` is not short (its stretch
// between its ROIs at least carry_lanes_max_m: never carried, not worth looking). *from_road: the
// road before (-1 if none).
std::vector<lanes::CarriedLane> lanesLeadingInto(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                 const std::map<int64_t, map::LaneMap>& mapped,
                                                 const lanes::ExplorerOptions& options, int64_t* from_road = nullptr);

// The same from the road after: of the mapped roads starting at the short road's end, the one the
// short road runs into straightest (same rules), its through lanes at the first station with the
// fewest lanes. *to_road: that road (-1 if none).
std::vector<lanes::CarriedLane> lanesLeadingOutOf(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                  const std::map<int64_t, map::LaneMap>& mapped,
                                                  const lanes::ExplorerOptions& options, int64_t* to_road = nullptr);

// A short road's lanes as its own OSM way gives them, for a link no mapped road runs straight
// into or out of (the crossing between the two carriageways of a divided road, entered and left
// by turns): its lanes in this direction from the way's lanes:forward / lanes:backward, else
// lanes (halved on a two-way way, rounded up), else 1; each 2 x default_half_width_m wide with
// virtual bounds, side by side right of the way's line on a two-way way (left of it in left-hand
// traffic), centred on it on a one-way way. Nothing was seen of them: no particle supports them,
// which their confidence says. Empty for a road that is not short.
std::vector<lanes::CarriedLane> lanesFromOsmWay(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& options);

// What a short road takes: the lanes of the road before, else those of the road after (a link
// the car turned into from a side street still runs on straight into the road beyond it), else
// with options.lanes_from_osm_way those of its own OSM way (lanesFromOsmWay; *from_road is then
// the road itself). *from_road: the road they come from (-1 if none).
std::vector<lanes::CarriedLane> lanesRunningThrough(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                    const std::map<int64_t, map::LaneMap>& mapped,
                                                    const lanes::ExplorerOptions& options, int64_t* from_road = nullptr);

// The roads of `awaiting` (short roads mapped with no lane: nothing explored, nothing to carry
// yet) that meet `mapped_road` end to start, either way: now that it has lanes, they may take them.
// A road is mapped in the order the car closes it, so the road after a link is mapped after it;
// the callers map these again. Not the road itself nor its reverse.
std::vector<int64_t> roadsAwaitingLanesFrom(const skeleton::Skeleton& skeleton, int64_t mapped_road,
                                            const std::set<int64_t>& awaiting);

}  // namespace lanemap::mapping
