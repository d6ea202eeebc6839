// The road the car is on when a drive ends (issue 14): it never reached its end intersection, so it
// never closed; its evidence is explored on what was driven, and its lanes are written tagged
// partial with where they stop (map::PartialRoad). One place for lanemap-offline and the lane
// mapper, so both cut a partial road the same way.
// - The station: the car's last position projected on the road in the explorer's Frenet frame
//   (the road polyline, frame_spacing_m / frame_smoothing_m as exploreRoad builds it), so a station
//   and the explored lanes' s agree.
// - The driven stretch: the road's own [s_begin, s_end] (explorer.h explorationStretch) ending at
//   the station: the particles stop there, so no lane goes past where the car was (nothing is
//   extrapolated). Under partial_min_driven_m driven past s_begin there is nothing to map; under
//   short_road_min_m, the stretch starts that far behind the station, inside the start ROI (a
//   drive that ended just past a junction still gives the lanes the junction connects into).
#pragma once

#include "core/lanes/explorer.h"
#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"

#include <Eigen/Core>

namespace lanemap::mapping {

// Arc length along the road (the explorer's frame of it) of the point nearest to `p`, clamped to
// [0, length].
double roadStation(const skeleton::AtomicRoad& road, const Eigen::Vector2d& p, const lanes::ExplorerOptions& options);

// The explorer's frame length of the road (what road_length_m of a partial road is).
double roadFrameLength(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& options);

// The road's geometry for exploring it as far as `station_m`: s_end = min(s_end, station_m).
// When under options.short_road_min_m was driven past s_begin, s_begin moves back to that far
// before the station, but not before 0: a car stopped under short_road_min_m from the road's
// start node leaves a shorter stretch, which exploreRoad widens around its middle
// (explorationStretch), up to short_road_min_m - station past the car. Throws lanes::LanesError
// (naming the road and the metres driven) when under options.partial_min_driven_m of the road
// past s_begin was driven.
lanes::RoadGeometry drivenStretch(const skeleton::AtomicRoad& road, double station_m, const lanes::ExplorerOptions& options);

// Tags every road lanelet of `lanes` partial (station, road length); the explored lanes stop at
// station_m.
void markPartial(map::LaneMap& lanes, const map::PartialRoad& partial);

// Whether any road lanelet of the map is partial.
bool isPartial(const map::LaneMap& lanes);

}  // namespace lanemap::mapping
