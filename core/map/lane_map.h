// The lane-level map model of lanemap: Lanelet2's vocabulary (line strings typed by marking,
// lanelets made of a left and a right boundary) in local ENU metres. The simulator's ground truth,
// the mapper's output and the evaluator's input are all a LaneMap; core/io reads and writes it as
// Lanelet2 OSM and GeoJSON.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::map {

enum class LineType : uint8_t {
  kDashed,    // Lanelet2 type=line_thin subtype=dashed
  kSolid,     // type=line_thin subtype=solid
  kSolidSolid,// type=line_thin subtype=solid_solid (e.g. the double line between directions)
  kCurb,      // type=curbstone
  kVirtual,   // type=virtual (intersection lanelets, lanes with no marking)
  kStopLine,  // type=stop_line
};

enum class LaneletKind : uint8_t { kRoad, kIntersection };
enum class TurnDirection : uint8_t { kNone, kStraight, kLeft, kRight };

struct LineString {
  int64_t id = 0;
  LineType type = LineType::kVirtual;
  std::vector<Eigen::Vector3d> points;  // ENU metres
};

struct Lanelet {
  int64_t id = 0;
  LaneletKind kind = LaneletKind::kRoad;
  // LineString ids of the bounds. A bound normally runs in the driving direction; a line shared
  // with a lane of the opposite direction runs against it for one of the two, as in Lanelet2
  // (whose loader aligns bounds by geometry). The centre line always gives the driving direction.
  int64_t left_id = 0;
  int64_t right_id = 0;
  std::vector<Eigen::Vector3d> centre;  // in the driving direction
  std::vector<int64_t> successors;      // lanelet ids
  TurnDirection turn = TurnDirection::kNone;  // intersection lanelets
  // Where it came from: the atomic road E_ij (OSM node ids of I_i, I_j) or the intersection.
  int64_t road_id = -1;
  int64_t from_node = -1;
  int64_t to_node = -1;
  int64_t intersection_id = -1;         // OSM node id of the intersection (intersection lanelets)
  int index_from_left = -1;             // 0 = left-most lane of its road direction
  std::optional<int64_t> stop_line_id;  // LineString at the lanelet's end, if any
};

struct LaneMap {
  double origin_lat = 0.0;  // ENU origin (degrees, metres)
  double origin_lon = 0.0;
  double origin_alt = 0.0;
  std::vector<LineString> lines;
  std::vector<Lanelet> lanelets;

  const LineString* line(int64_t id) const;
  const Lanelet* lanelet(int64_t id) const;
};

const char* toString(LineType t);
const char* toString(TurnDirection t);

}  // namespace lanemap::map
