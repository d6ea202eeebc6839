// What part of the truth a drive could have mapped. A drive covers a few atomic roads of a city;
// scoring it against every lane of the city's truth measures the route, not the mapper. The paper
// scores the blocks it drove.
// - restrictToRoads keeps the truth's road lanelets of the given directed atomic roads (by their
//   lanemap:from_node/to_node) and the truth's intersection lanelets that lead from one kept road
//   lanelet to another.
// - restrictToDrivenRoads (lanemap-eval --driven): the roads the car drove to their end
//   intersection, from the drive's route (drivenRoads*). A driven road the map has no lanes on
//   still counts: its true lanes are missed (recall), which restrictToMappedRoads cannot see.
// - restrictToMappedRoads (lanemap-eval --mapped-roads-only): the roads the built map has lanes
//   on; optimistic, a road the mapper dropped does not count against it.
#pragma once

#include "core/map/lane_map.h"

#include <cstdint>
#include <set>
#include <string>
#include <utility>

namespace lanemap::eval {

// A directed atomic road by its end intersections (OSM node ids): (from_node, to_node).
using RoadKey = std::pair<int64_t, int64_t>;

map::LaneMap restrictToRoads(const map::LaneMap& truth, const std::set<RoadKey>& roads);
map::LaneMap restrictToMappedRoads(const map::LaneMap& truth, const map::LaneMap& built);
// The lanelets `keep` with their successors among them, their bound and stop lines, and the rules
// and crosswalks over them (restricted to them; one over none of them is dropped).
map::LaneMap restrictToLanelets(const map::LaneMap& truth, const std::set<int64_t>& keep);

// The directed roads the map has road lanelets on.
std::set<RoadKey> mappedRoads(const map::LaneMap& built);

// The roads a simulated drive drove to their end intersection, from lanemap-sim's scenario.json
// ("route": [{from, to, left_utime}, ...]; a road with left_utime null, where the drive ended,
// was not closed and is not counted). Throws std::runtime_error naming the file on a missing file
// or a file without a route.
std::set<RoadKey> drivenRoadsFromScenario(const std::string& scenario_json_path);

}  // namespace lanemap::eval
