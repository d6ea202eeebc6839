// What part of the truth a drive could have mapped. A drive covers a few atomic roads of a city;
// scoring it against every lane of the city's truth measures the route, not the mapper. The paper
// scores the blocks it drove. restrictToMappedRoads keeps the truth's road lanelets of the atomic
// roads the built map has (same lanemap:from_node/to_node), and the truth's intersection lanelets
// that lead from one kept road lanelet to another.
#pragma once

#include "core/map/lane_map.h"

namespace lanemap::eval {

map::LaneMap restrictToMappedRoads(const map::LaneMap& truth, const map::LaneMap& built);

}  // namespace lanemap::eval
