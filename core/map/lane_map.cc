#include "core/map/lane_map.h"

namespace lanemap::map {

const LineString* LaneMap::line(int64_t id) const {
  for (const auto& l : lines) {
    if (l.id == id) return &l;
  }
  return nullptr;
}

const Lanelet* LaneMap::lanelet(int64_t id) const {
  for (const auto& l : lanelets) {
    if (l.id == id) return &l;
  }
  return nullptr;
}

const char* toString(LineType t) {
  switch (t) {
    case LineType::kDashed: return "dashed";
    case LineType::kSolid: return "solid";
    case LineType::kSolidSolid: return "solid_solid";
    case LineType::kCurb: return "curbstone";
    case LineType::kVirtual: return "virtual";
    case LineType::kStopLine: return "stop_line";
  }
  return "?";
}

const char* toString(TurnDirection t) {
  switch (t) {
    case TurnDirection::kNone: return "none";
    case TurnDirection::kStraight: return "straight";
    case TurnDirection::kLeft: return "left";
    case TurnDirection::kRight: return "right";
  }
  return "?";
}

const char* toString(RegulatoryKind k) {
  switch (k) {
    case RegulatoryKind::kStopSign: return "stop_sign";
    case RegulatoryKind::kGiveWay: return "give_way";
    case RegulatoryKind::kTrafficLight: return "traffic_light";
  }
  return "?";
}

}  // namespace lanemap::map
