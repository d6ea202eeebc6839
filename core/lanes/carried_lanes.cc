#include "core/lanes/carried_lanes.h"

#include "core/lanes/frenet.h"

#include <algorithm>
#include <cmath>

namespace lanemap::lanes {

bool takesCarriedLanes(const RoadGeometry& road, const ExplorationResult& explored, size_t carried,
                       const ExplorerOptions& o) {
  return carried > 0 && road.s_end - road.s_begin < o.carry_lanes_max_m && explored.lanes.empty();
}

ExplorationResult carryLanesThrough(const RoadGeometry& road_in, std::vector<CarriedLane> carried,
                                    const ExplorerOptions& o) {
  if (carried.empty()) throw LanesError("road " + std::to_string(road_in.road_id) + ": no lanes to carry through");
  RoadGeometry road;
  ExplorationResult res = startExploration(road_in, o, &road);
  const FrenetFrame* frame = res.frame.get();
  if (!(road.s_end - road.s_begin > 1.0)) {
    throw LanesError("road " + std::to_string(road.road_id) + " has no length to carry lanes through");
  }
  // Left to right; of two lanes closer than same_lane_m (one lane twice) the left one stays.
  std::sort(carried.begin(), carried.end(), [](const CarriedLane& a, const CarriedLane& b) { return a.d > b.d; });
  std::vector<CarriedLane> kept;
  for (const auto& c : carried) {
    if (kept.empty() || kept.back().d - c.d >= o.same_lane_m) kept.push_back(c);
  }
  const double len = road.s_end - road.s_begin;
  const int n = std::max(2, static_cast<int>(std::ceil(len / o.waypoint_spacing_m)) + 1);
  for (size_t k = 0; k < kept.size(); ++k) {
    const CarriedLane& c = kept[k];
    Lane lane;
    lane.id = static_cast<int>(k);
    lane.index_from_left = static_cast<int>(k);
    lane.s_begin = road.s_begin;
    lane.s_end = road.s_end;
    PiecewiseLinearFit fit;
    fit.knots = {road.s_begin, road.s_end};
    fit.values = {c.d, c.d};
    lane.centre = CentreLine(fit, road.s_begin, road.s_end);
    for (int i = 0; i < n; ++i) {
      const double s = road.s_begin + len * i / (n - 1);
      lane.waypoint_s.push_back(s);
      lane.waypoints.push_back(frame->toEnu(s, c.d));
      lane.left.d.push_back(c.d + c.half_left_m);
      lane.left.points.push_back(frame->toEnu(s, c.d + c.half_left_m));
      lane.right.d.push_back(c.d - c.half_right_m);
      lane.right.points.push_back(frame->toEnu(s, c.d - c.half_right_m));
    }
    lane.left.type = c.left_type;
    lane.right.type = c.right_type;
    res.lanes.push_back(std::move(lane));
  }
  return res;
}

}  // namespace lanemap::lanes
