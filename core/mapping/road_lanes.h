// One atomic road's lanes from its BEV evidence, as lanemap-offline and the lane mapper both build
// them: the road explored over `geometry` (RoadGeometry::fromSkeleton, or drivenStretch for the
// road a drive ended on), the lanes as a LaneMap, each lane's confidence (lane_confidence.h), and
// then either the partial tag (no stop line where the car stopped) or the stop lines the BEV saw
// at the lanes' ends.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/geo/local_frame.h"
#include "core/lanes/carried_lanes.h"
#include "core/lanes/explorer.h"
#include "core/map/lane_map.h"

#include <optional>
#include <string>
#include <vector>

namespace lanemap::mapping {

struct RoadLanes {
  lanes::ExplorationResult result;
  map::LaneMap lanes;
  // The lanelets left out of `lanes` because Lanelet2's loader would misread them (their bounds
  // against each other or the left bound on the right: io::orientationProblem), one line each
  // naming the lanelet. The rest of the road is mapped: one bad lane costs that lane, not the map
  // (writeLanelet2 refuses a map holding one).
  std::vector<std::string> lanes_dropped;
  // The lanes are those of the road before, carried through this short one (carried_lanes.h).
  bool lanes_carried = false;
  // Explored lanes dropped as lying over a lane's width beyond those the road before runs on into
  // it (lanes::dropLanesApartFromCarried: across an island).
  int lanes_apart_dropped = 0;
  // Lanes the road before runs on into it that exploring missed, added (lanes::addCarriedLanesNotFound).
  int lanes_carried_added = 0;
};

// Removes from `lanes` every lanelet io::orientationProblem finds, with what referred to it: its
// bounds and stop line when no other lanelet uses them, successor links, regulatory elements' and
// crosswalks' references. Returns the problems, one per lanelet removed, in map order.
std::vector<std::string> dropMisreadLanelets(map::LaneMap& lanes);

// `carried`: the lanes of the road leading straight into this one (mapping::lanesLeadingInto);
// a short road takes them instead of what exploring it found when lanes::takesCarriedLanes says so
// (never a partial road), else drops the explored lanes apart from them
// (lanes::dropLanesApartFromCarried). Throws what lanes::exploreRoad throws (when nothing is carried).
RoadLanes exploreRoadLanes(const bev::BevGrid& grid, const lanes::RoadGeometry& geometry,
                           const std::optional<map::PartialRoad>& partial, const lanes::ExplorerOptions& options,
                           const geo::LatLonAlt& origin, const std::vector<lanes::CarriedLane>& carried = {});

}  // namespace lanemap::mapping
