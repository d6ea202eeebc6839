// One atomic road's lanes from its BEV evidence, as lanemap-offline and the lane mapper both build
// them: the road explored over `geometry` (RoadGeometry::fromSkeleton, or drivenStretch for the
// road a drive ended on), the lanes as a LaneMap, each lane's confidence (lane_confidence.h), and
// then either the partial tag (no stop line where the car stopped) or the stop lines the BEV saw
// at the lanes' ends.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/geo/local_frame.h"
#include "core/lanes/explorer.h"
#include "core/map/lane_map.h"

#include <optional>

namespace lanemap::mapping {

struct RoadLanes {
  lanes::ExplorationResult result;
  map::LaneMap lanes;
};

// Throws what lanes::exploreRoad throws.
RoadLanes exploreRoadLanes(const bev::BevGrid& grid, const lanes::RoadGeometry& geometry,
                           const std::optional<map::PartialRoad>& partial, const lanes::ExplorerOptions& options,
                           const geo::LatLonAlt& origin);

}  // namespace lanemap::mapping
