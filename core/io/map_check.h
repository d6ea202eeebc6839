// lanemap-check: the requirements of Autoware's Lanelet2 map format that Lanelet2's validator does
// not check, on any Lanelet2 OSM file (read as it is stored, with libosmium; lanemap's sidecar,
// when there is one, says which lanelets are intersection lanelets). Each requirement passes or
// fails with the ids that break it:
//   ele               every node has `ele` (Autoware: ellipsoidal height on every point)
//   lanelet_tags      every lanelet has subtype, location, one_way and (but crosswalks and
//                     walkways) a numeric speed_limit
//   lane_change       every line string that is the right bound of one lanelet and the left bound of
//                     another (two lanes of one direction) has lane_change=yes|no, yes exactly on
//                     dashed lines (line_thin/line_thick subtype dashed)
//   shared_borders    neighbouring lanelets share their border: no two different line strings of
//                     two lanelets run on top of each other (within 0.1 m for 90 % of the shorter);
//                     crosswalk and walkway lanelets are not lanes' neighbours and do not count,
//                     nor are two lanelets that merge (both bounds end at the same two nodes) or
//                     split (start at the same two nodes): their bounds converge there
//   bounds_apart      a lanelet's left and right bound share no node
//   centerline_inside every point of a lanelet's centerline lies inside its lanelet (0.1 m slack)
//   one_lanelet_per_intersection_path  (lanemap sidecar) no intersection lanelet is followed by
//                     another intersection lanelet of the same intersection
//   turn_direction    (Autoware layout only) every intersection lanelet has turn_direction
//                     straight|left|right; intersection lanelets: the sidecar's, else those with
//                     a turn_direction tag
//   stop_line_refs    (Autoware layout only) every stop_line line string is referenced by a
//                     regulatory element: as its ref_line (traffic light, traffic sign, right of
//                     way) or as the `refers` of Autoware's road_marking
//   regulatory_elements every traffic_sign / traffic_light / right_of_way element is referenced by
//                     a lanelet and has at most one ref_line, a stop_line; a light refers a
//                     type=traffic_light way, a sign has sign_type (or a sign), a right of way has
//                     yield and right_of_way lanelets
//   crosswalk_refs    (Autoware layout only) every crosswalk lanelet is the `refers` of a crosswalk
//                     regulatory element that a road lanelet references
//   projector_info    (Autoware layout only) map_projector_info.yaml beside the map
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace lanemap::io {

struct CheckResult {
  std::string name;
  bool passed = true;
  bool applicable = true;       // false: skipped (the map has nothing this rule is about)
  std::string what;             // the requirement, one line
  std::vector<int64_t> offenders;  // OSM ids (nodes, ways or relations, as `what` says)
};

struct MapCheckOptions {
  bool autoware = false;  // also turn_direction, stop_line_refs and map_projector_info.yaml
};

// Throws IoError (with the path) for a missing or unreadable file.
std::vector<CheckResult> checkLanelet2Map(const std::string& path, const MapCheckOptions& options = {});

}  // namespace lanemap::io
