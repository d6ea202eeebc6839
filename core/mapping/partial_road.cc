#include "core/mapping/partial_road.h"

#include "core/lanes/frenet.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace lanemap::mapping {

namespace {
lanes::FrenetFrame explorerFrame(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& o) {
  return lanes::FrenetFrame(road.polyline, o.frame_spacing_m, o.frame_smoothing_m);
}
}  // namespace

double roadStation(const skeleton::AtomicRoad& road, const Eigen::Vector2d& p, const lanes::ExplorerOptions& o) {
  const auto frame = explorerFrame(road, o);
  return std::clamp(frame.toFrenet(p).x(), 0.0, frame.length());
}

double roadFrameLength(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& o) {
  return explorerFrame(road, o).length();
}

lanes::RoadGeometry drivenStretch(const skeleton::AtomicRoad& road, double station_m, const lanes::ExplorerOptions& o) {
  lanes::RoadGeometry g = lanes::RoadGeometry::fromSkeleton(road);
  const double driven = std::min(station_m, g.s_end) - g.s_begin;
  if (!(driven >= o.partial_min_driven_m)) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "road %lld: only %.1f m driven past its start intersection (under %.1f m): not mapped",
                  static_cast<long long>(road.id), std::max(0.0, driven), o.partial_min_driven_m);
    throw lanes::LanesError(buf);
  }
  g.s_end = std::min(g.s_end, station_m);
  // A few metres driven: the camera saw them from the road (and ahead of the car), but exploring
  // needs a stretch of short_road_min_m. Take it from behind the car, into the start ROI, where
  // explorationStretch would centre it on the driven metres and run past where the car stopped.
  if (g.s_end - g.s_begin < o.short_road_min_m) g.s_begin = std::max(0.0, g.s_end - o.short_road_min_m);
  return g;
}

void markPartial(map::LaneMap& lanes, const map::PartialRoad& partial) {
  for (auto& l : lanes.lanelets) {
    if (l.kind == map::LaneletKind::kRoad) l.partial = partial;
  }
}

bool isPartial(const map::LaneMap& lanes) {
  return std::any_of(lanes.lanelets.begin(), lanes.lanelets.end(), [](const map::Lanelet& l) { return l.partial.has_value(); });
}

}  // namespace lanemap::mapping
