#include "core/mapping/road_lanes.h"

#include "core/lanes/stop_lines.h"
#include "core/mapping/lane_confidence.h"
#include "core/mapping/partial_road.h"

namespace lanemap::mapping {

RoadLanes exploreRoadLanes(const bev::BevGrid& grid, const lanes::RoadGeometry& geometry,
                           const std::optional<map::PartialRoad>& partial, const lanes::ExplorerOptions& options,
                           const geo::LatLonAlt& origin) {
  RoadLanes out;
  out.result = lanes::exploreRoad(grid, geometry, options);
  out.lanes = lanes::toLaneMap(out.result, origin.lat, origin.lon, origin.alt);
  setConfidence(out.lanes, out.result, laneConfidences(grid, out.result, options));  // per lane, 0..1
  if (partial) {
    markPartial(out.lanes, *partial);  // its lanes end where the car stopped: no stop line there
  } else {
    lanes::addStopLines(grid, out.lanes);  // stop lines the BEV saw at the lanes' ends
  }
  return out;
}

}  // namespace lanemap::mapping
