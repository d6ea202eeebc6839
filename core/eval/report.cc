// Map evaluation: the report as JSON and as a few human-readable lines.
#include "core/eval/evaluate_internal.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace lanemap::eval {

using internal::kNaN;

namespace {

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

std::string fmt(double v, int digits = 3) {
  if (!std::isfinite(v)) return "n/a";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

std::string thresholdKey(double t) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f", t);
  return buf;
}

}  // namespace

nlohmann::json toJson(const EvalReport& r) {
  using nlohmann::json;
  json j;
  j["lanes"] = {{"precision", num(r.lane_precision.value())},
                {"recall", num(r.lane_recall.value())},
                {"rms_m", num(r.lane_rms_m)},
                {"miou", num(r.lane_miou)},
                {"rms_detected_m", num(r.lane_rms_detected_m)},
                {"miou_detected", num(r.lane_miou_detected)},
                {"truth", r.truth_lanes.size()},
                {"built", r.built_lanes.size()},
                {"matched", r.matches.size()},
                {"detected", r.lane_recall.hits},
                {"repaired_polygons", r.repaired_polygons}};
  j["intersections"] = {{"precision", num(r.intersection_precision.value())},
                        {"recall", num(r.intersection_recall.value())},
                        {"rms_m", num(r.intersection_rms_m)},
                        {"truth_pairs", r.intersection_recall.total},
                        {"built_pairs", r.intersection_precision.total},
                        {"correct_pairs", r.intersection_precision.hits},
                        {"truth_lanelets", r.truth_intersection_lanelets},
                        {"built_lanelets", r.built_intersection_lanelets}};
  // Every pair, its lanes named by road and first lanelet: which connections were missed or wrong.
  const auto pairsJson = [&](const std::vector<PairDetail>& pairs, const std::vector<LaneInfo>& lanes) {
    nlohmann::json out = nlohmann::json::array();
    const auto lane = [&](int i) {
      const LaneInfo& l = lanes.at(static_cast<size_t>(i));
      return nlohmann::json{{"road_id", l.road_id}, {"from_node", l.from_node}, {"to_node", l.to_node},
                            {"lanelet", l.lanelets.empty() ? -1 : l.lanelets.front()}};
    };
    for (const auto& p : pairs) {
      out.push_back({{"in", lane(p.in_lane)}, {"out", lane(p.out_lane)}, {"correct", p.correct}, {"rms_m", num(p.rms_m)}});
    }
    return out;
  };
  j["intersections"]["truth_pair_detail"] = pairsJson(r.truth_pairs, r.truth_lanes);
  j["intersections"]["built_pair_detail"] = pairsJson(r.built_pairs, r.built_lanes);
  j["lane_graph"] = {{"precision", num(r.graph_precision.value())},
                     {"recall", num(r.graph_recall.value())},
                     {"truth_edges", r.graph_recall.total},
                     {"built_edges", r.graph_precision.total},
                     {"correct_edges", r.graph_precision.hits}};
  json ap = json::object();
  for (const auto& [thr, v] : r.chamfer_ap) ap[thresholdKey(thr)] = num(v);
  for (const auto& [name, a] : {std::pair<const char*, const ApResult*>{"centre", &r.ap_centre}, {"boundary", &r.ap_boundary}}) {
    json c = {{"truth_instances", a->truth_instances}, {"predictions", a->predictions}};
    for (const auto& [thr, v] : a->ap) c[thresholdKey(thr)] = num(v);
    ap[name] = c;
  }
  j["chamfer_ap"] = ap;
  json roads = json::array();
  for (const auto& d : r.roads) {
    roads.push_back({{"road_id", d.road_id},
                     {"from_node", d.from_node},
                     {"to_node", d.to_node},
                     {"truth_lanes", d.truth_lanes},
                     {"built_lanes", d.built_lanes},
                     {"matched", d.matched},
                     {"detected", d.detected},
                     {"recall", num(d.truth_lanes ? static_cast<double>(d.detected) / d.truth_lanes : kNaN)},
                     {"mean_iou", num(d.mean_iou)},
                     {"mean_rms_m", num(d.mean_rms_m)}});
  }
  j["roads"] = roads;
  // Per lane of either map, the lane of the other map it matched (one to one) and how well:
  // lanes_detail every truth lane (one not detected lowers recall), built_lanes_detail every built
  // lane (one that detects nothing lowers precision, and can be found on the map by its lanelets).
  auto laneDetail = [&](bool truth_side) {
    const std::vector<LaneInfo>& own = truth_side ? r.truth_lanes : r.built_lanes;
    const std::vector<LaneInfo>& other = truth_side ? r.built_lanes : r.truth_lanes;
    const char* other_key = truth_side ? "built_lanelets" : "truth_lanelets";
    std::vector<const LaneMatch*> match(own.size(), nullptr);
    for (const auto& m : r.matches) match[truth_side ? m.truth : m.built] = &m;
    json out = json::array();
    for (size_t i = 0; i < own.size(); ++i) {
      const LaneInfo& li = own[i];
      json l = {{"road_id", li.road_id}, {"length_m", li.length_m}, {"lanelets", li.lanelets}};
      if (const LaneMatch* m = match[i]) {
        l[other_key] = other[truth_side ? m->built : m->truth].lanelets;
        l["iou"] = num(m->iou);
        l["rms_m"] = num(m->rms_m);
        l["coverage"] = num(m->coverage);
        l["detected"] = m->detected;
      } else {
        l[other_key] = json::array();
        l["detected"] = false;
      }
      out.push_back(l);
    }
    return out;
  };
  j["lanes_detail"] = laneDetail(true);
  j["built_lanes_detail"] = laneDetail(false);
  const json regulatory = toJson(r.regulatory);
  for (auto it = regulatory.begin(); it != regulatory.end(); ++it) j[it.key()] = it.value();
  return j;
}

std::string summary(const EvalReport& r) {
  std::ostringstream s;
  s << "lanes:         truth " << r.truth_lanes.size() << ", built " << r.built_lanes.size() << ", matched "
    << r.matches.size() << ", detected " << r.lane_recall.hits << "\n";
  s << "               precision " << fmt(r.lane_precision.value()) << "  recall " << fmt(r.lane_recall.value())
    << "  RMS " << fmt(r.lane_rms_m) << " m  mIoU " << fmt(r.lane_miou) << "\n";
  s << "intersections: truth pairs " << r.intersection_recall.total << ", built pairs "
    << r.intersection_precision.total << ", correct " << r.intersection_precision.hits << "\n";
  s << "               precision " << fmt(r.intersection_precision.value()) << "  recall "
    << fmt(r.intersection_recall.value()) << "  RMS " << fmt(r.intersection_rms_m) << " m\n";
  s << "lane graph:    precision " << fmt(r.graph_precision.value()) << "  recall " << fmt(r.graph_recall.value())
    << " (" << r.graph_recall.total << " truth edges, " << r.graph_precision.total << " built)\n";
  s << "Chamfer AP:   ";
  for (const auto& [thr, v] : r.chamfer_ap) s << " @" << fmt(thr, 1) << " m " << fmt(v);
  s << "  (centre";
  for (const auto& [thr, v] : r.ap_centre.ap) s << " " << fmt(v);
  s << ", boundary";
  for (const auto& [thr, v] : r.ap_boundary.ap) s << " " << fmt(v);
  s << ")\n";
  const RegulatoryScores& g = r.regulatory;
  s << "stop lines:    truth " << g.stop_lines.truth << ", built " << g.stop_lines.built << ", matched "
    << g.stop_lines.matched << "  precision " << fmt(g.stop_lines.precision()) << "  recall "
    << fmt(g.stop_lines.recall()) << "  error " << fmt(g.stop_lines.error_m()) << " m  rules agree "
    << g.rules_agreeing << "/" << g.rules_compared << "\n";
  s << "crosswalks:    truth " << g.crosswalks.truth << ", built " << g.crosswalks.built << ", matched "
    << g.crosswalks.matched << "  precision " << fmt(g.crosswalks.precision()) << "  recall "
    << fmt(g.crosswalks.recall()) << "  error " << fmt(g.crosswalks.error_m()) << " m\n";
  s << "lane change:   accuracy " << fmt(g.laneChangeAccuracy()) << " (" << g.lane_change_correct << " of "
    << g.lane_change_matched << " matched shared lines; " << g.lane_change_truth << " in the truth)\n";
  return s.str();
}

}  // namespace lanemap::eval
