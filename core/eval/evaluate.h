// Map evaluation (METHOD.md section 6 + issue 6): a built lane map against a ground-truth one, both
// map::LaneMap in one ENU frame (read from any two Lanelet2 files with readLanelet2 and the origin
// of lanelet2Origin).
//
// Definitions (all in the xy plane):
// - Lanes. Lanelets are cut differently by different mappers (turn pockets, pieces), so a *lane*
//   is a chain of road lanelets joined along successors: a -> b are one lane when b is a's best
//   continuing successor and a is b's best continuing predecessor (score: gap between a's centre
//   end and b's centre start + 1 m per radian of heading change), both on the same road when both
//   carry lanemap:road_id. A split-off turn pocket therefore starts a lane of its own and the lane it
//   left runs on through the split. Intersection lanelets (kind kIntersection, or tagged
//   turn_direction) are not lanes. A lane's centre, bounds and polygon are its lanelets' joined.
// - Per (truth lane, built lane): IoU of the two polygons (Boost.Geometry clipping); RMS = the
//   built centre line's distance to the truth centre line over their overlap (geometry.h
//   overlapDistance, samples every sample_step_m); coverage = fraction of the truth centre line
//   that overlap covers.
// - Matching: one-to-one, greedy over candidate pairs (polygons overlapping, IoU > 0; with
//   match_by_road_tags and both lanes tagged, the same (from_node, to_node)), detections first,
//   then by IoU, then by RMS. A matched pair is a *detection* when IoU > iou_threshold or
//   (RMS < rms_threshold_m and coverage >= min_coverage: a short sliver is no detection).
//   lanes.precision = detections / built lanes, lanes.recall = detections / truth lanes,
//   lanes.rms_m = mean RMS and lanes.miou = mean IoU over the matched pairs (also over detections).
// - Intersections: the (in lane, out lane) pairs that intersection lanelets join (through chains
//   of intersection lanelets). A built pair is correct when its two lanes are matched to two truth
//   lanes that truth joins. intersections.precision = correct built pairs / built pairs (a pair with
//   an unmatched lane counts as wrong); recall = truth pairs found / truth pairs.
//   intersections.rms_m = mean over correct pairs of the built connection's centre RMS to the
//   truth connection's centre (as for lanes).
// - Lane graph: lane -> lane edges, through intersections (the pairs above) and inside roads
//   (a lanelet's successor in another lane: splits, merges); precision/recall as for pairs.
// - Chamfer AP (MapTR): instances of two classes, centre lines (lanes and intersection lanelets)
//   and boundaries (each lane's left and right bound, duplicates within a map - Chamfer distance
//   below 5 cm, e.g. a shared bound - counted once), each resampled to chamfer_points points.
//   Predictions ranked by score = instance length (our maps have no confidence); each prediction in
//   that order takes the truth instance nearest to it by Chamfer distance: a true positive when
//   nearer than the threshold and that instance not yet taken, else a false positive. AP is the
//   area under the precision envelope (VOC "area" mode, as MapTR's mmdet code). chamfer_ap at a
//   threshold is the mean over the classes that have truth instances.
// Ratios with a zero denominator are NaN (JSON null).
#pragma once

#include "core/eval/regulatory.h"
#include "core/geo/local_frame.h"
#include "core/map/lane_map.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lanemap::eval {

struct EvalOptions {
  double iou_threshold = 0.7;     // METHOD.md section 6
  double rms_threshold_m = 0.2;   // METHOD.md section 6
  double min_coverage = 0.5;      // the RMS criterion needs this much of the truth lane covered
  double sample_step_m = 0.5;     // centre line samples for RMS
  bool match_by_road_tags = true; // candidate pairs need the same (from_node, to_node) when tagged
  size_t chamfer_points = 100;    // MapTR
  std::vector<double> chamfer_thresholds{0.5, 1.0, 1.5};
  double duplicate_chamfer_m = 0.05;
  RegulatoryOptions regulatory;  // stop lines, crosswalks, rules, lane change (regulatory.h)
};

// One lane (a chain of road lanelets) of either map.
struct LaneInfo {
  std::vector<int64_t> lanelets;  // in driving order
  int64_t road_id = -1, from_node = -1, to_node = -1;
  double length_m = 0.0;
};

struct LaneMatch {
  int truth = -1, built = -1;     // indices into EvalReport::truth_lanes / built_lanes
  double iou = 0.0;
  double rms_m = 0.0;             // +inf when the centre lines do not overlap
  double coverage = 0.0;
  bool detected = false;
};

struct Ratio {
  size_t hits = 0, total = 0;
  double value() const;  // hits / total, NaN when total == 0
};

struct RoadDetail {
  int64_t road_id = -1, from_node = -1, to_node = -1;  // of the truth lanes (-1: untagged)
  size_t truth_lanes = 0;
  size_t built_lanes = 0;   // built lanes carrying the same road id (0 for untagged maps)
  size_t matched = 0, detected = 0;
  double mean_iou = 0.0, mean_rms_m = 0.0;  // over the matched lanes (NaN when none)
};

// One (in lane, out lane) pair of an intersection; lanes are indices into the report's
// truth_lanes (truth pairs) or built_lanes (built pairs).
struct PairDetail {
  int in_lane = -1, out_lane = -1;
  bool correct = false;  // truth: found in the built map; built: a truth pair
  double rms_m = 0.0;    // built and correct: its trajectory against the truth's (NaN otherwise)
};

struct ApResult {
  size_t truth_instances = 0, predictions = 0;
  std::map<double, double> ap;  // threshold -> AP (NaN without truth instances)
};

struct EvalReport {
  std::vector<LaneInfo> truth_lanes, built_lanes;
  std::vector<LaneMatch> matches;  // one per matched pair
  Ratio lane_precision, lane_recall;
  double lane_rms_m = 0.0, lane_miou = 0.0;                    // over matched pairs
  double lane_rms_detected_m = 0.0, lane_miou_detected = 0.0;  // over detections
  size_t truth_intersection_lanelets = 0, built_intersection_lanelets = 0;
  Ratio intersection_precision, intersection_recall;
  double intersection_rms_m = 0.0;  // NaN when no correct pair
  std::vector<PairDetail> truth_pairs, built_pairs;
  Ratio graph_precision, graph_recall;
  ApResult ap_centre, ap_boundary;
  std::map<double, double> chamfer_ap;  // mean over classes
  std::vector<RoadDetail> roads;
  size_t repaired_polygons = 0;  // lane polygons that needed the quadrilateral fallback
  RegulatoryScores regulatory;   // stop lines, crosswalks, rules, lane-change permission
};

EvalReport evaluate(const map::LaneMap& truth, const map::LaneMap& built, const EvalOptions& options = {});

// The report as JSON: lanes.{precision, recall, rms_m, miou, ...}, intersections.{precision,
// recall, rms_m, ...}, lane_graph.{precision, recall}, chamfer_ap.{"0.5", "1.0", "1.5", centre,
// boundary}, roads[] (per-road detail), lanes_detail[] (per truth lane), built_lanes_detail[]
// (per built lane: the truth lane it matched, IoU, RMS, coverage, detected), and stop_lines,
// crosswalks, rules, lane_change (regulatory.h toJson). NaN -> null.
nlohmann::json toJson(const EvalReport& report);
// A few human-readable lines.
std::string summary(const EvalReport& report);

// The ENU origin to read a Lanelet2 file with: the origin its writer used when its nodes carry
// local_x/local_y (Autoware's tags, lanemap writes them), recovered from the first node, so the
// reader takes the mm-precise local coordinates; otherwise the first node's lat/lon. Throws
// std::runtime_error when the file has no node.
geo::LatLonAlt lanelet2Origin(const std::string& path);

}  // namespace lanemap::eval
