// Regulatory elements of a lane map from OpenStreetMap's junction controls: a stop line of the
// map (the simulator's, or one the mapper found) at the end of an approach to an intersection
// becomes a map::RegulatoryElement according to the OSM nodes of that approach:
//   highway=stop            -> kStopSign
//   highway=give_way        -> kGiveWay (priority: the approaches into the same intersection that
//                              have no control of their own)
//   highway=traffic_signals -> kTrafficLight, with the light's position estimated (light_estimated)
// A control node counts for an approach when it is one of the intersection's junction nodes (all
// approaches), or lies on the approach's own road within kApproachSearchM of its end and in its
// second half, and its `direction` (or traffic_signals:direction / stop direction) is empty,
// `both`, or names the road's direction of travel relative to the way (forward / backward).
// A stop line whose approach has no control stays a plain stop line (no element).
#pragma once

#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <string>
#include <unordered_map>

namespace lanemap::intersections {

inline constexpr double kApproachSearchM = 30.0;
// The estimated traffic light: a 0.4 m bottom edge centred above the middle of the stop line,
// 5 m above it (a typical mast arm clearance), 1 m high (three 30 cm lamps).
inline constexpr double kLightClearanceM = 5.0;
inline constexpr double kLightWidthM = 0.4;
inline constexpr double kLightHeightM = 1.0;

enum class Control : uint8_t { kNone, kStop, kGiveWay, kTrafficSignals };
const char* toString(Control c);

struct ControlNode {
  int64_t id = 0;
  double lat = 0.0, lon = 0.0;
  Control control = Control::kNone;
  std::string direction;  // forward, backward, both or empty
};

// The nodes of an OSM file (XML or PBF) tagged highway=stop|give_way|traffic_signals, by id.
// Throws osm::OsmError when the file cannot be read.
std::unordered_map<int64_t, ControlNode> readControlNodes(const std::string& osm_path);

// The control of the approach along atomic road `road_id` into its intersection, and the node
// that gives it (-1 if none).
struct ApproachControl {
  Control control = Control::kNone;
  int64_t node = -1;
};
ApproachControl approachControl(const skeleton::Skeleton& sk, int64_t road_id,
                                const std::unordered_map<int64_t, ControlNode>& controls);

// Replaces map.regulatory_elements by one element per stop line of a controlled approach (ids
// from above every id of the map). Lanelets: the road lanelets whose stop_line_id it is. Returns
// how many it made.
size_t addRegulatoryElements(map::LaneMap& map, const skeleton::Skeleton& sk,
                             const std::unordered_map<int64_t, ControlNode>& controls);

}  // namespace lanemap::intersections
