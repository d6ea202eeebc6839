// Map evaluation: the greedy one-to-one lane matching, and the intersection pairs, lane graph edges
// and per-road detail scored through it (see evaluate.h for the definitions).
#include "core/eval/evaluate_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>

namespace lanemap::eval::internal {

double meanOf(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

std::vector<int> matchLanes(const Prepared& truth, const Prepared& built, const EvalOptions& o, EvalReport& r) {
  std::vector<LaneMatch> cand;
  for (size_t t = 0; t < truth.lanes.size(); ++t) {
    const Lane& lt = truth.lanes[t];
    for (size_t b = 0; b < built.lanes.size(); ++b) {
      const Lane& lb = built.lanes[b];
      if (o.match_by_road_tags && lt.info.from_node >= 0 && lt.info.to_node >= 0 && lb.info.from_node >= 0 &&
          lb.info.to_node >= 0 && (lt.info.from_node != lb.info.from_node || lt.info.to_node != lb.info.to_node)) {
        continue;
      }
      if (lt.box.gap(lb.box) > 0.0) continue;
      LaneMatch m;
      m.truth = static_cast<int>(t);
      m.built = static_cast<int>(b);
      m.iou = lt.polygon.iou(lb.polygon);
      if (m.iou <= 0.0) continue;
      const OverlapDistance od = overlapDistance(lb.centre, lt.centre, o.sample_step_m);
      m.rms_m = od.rms;
      m.coverage = lt.info.length_m > 0.0 ? std::min(1.0, od.covered_m / lt.info.length_m) : 0.0;
      m.detected = m.iou > o.iou_threshold ||
                   (od.samples > 0 && m.rms_m < o.rms_threshold_m && m.coverage >= o.min_coverage);
      cand.push_back(m);
    }
  }
  std::stable_sort(cand.begin(), cand.end(), [](const LaneMatch& a, const LaneMatch& b) {
    if (a.detected != b.detected) return a.detected;
    if (a.iou != b.iou) return a.iou > b.iou;
    return a.rms_m < b.rms_m;
  });
  std::vector<int> match_of_truth(truth.lanes.size(), -1), match_of_built(built.lanes.size(), -1);
  for (const LaneMatch& m : cand) {
    if (match_of_truth[m.truth] >= 0 || match_of_built[m.built] >= 0) continue;
    match_of_truth[m.truth] = m.built;
    match_of_built[m.built] = m.truth;
    r.matches.push_back(m);
  }
  std::sort(r.matches.begin(), r.matches.end(), [](const LaneMatch& a, const LaneMatch& b) { return a.truth < b.truth; });
  size_t detected = 0;
  std::vector<double> rms_all, iou_all, rms_det, iou_det;
  for (const LaneMatch& m : r.matches) {
    if (std::isfinite(m.rms_m)) rms_all.push_back(m.rms_m);
    iou_all.push_back(m.iou);
    if (m.detected) {
      ++detected;
      if (std::isfinite(m.rms_m)) rms_det.push_back(m.rms_m);
      iou_det.push_back(m.iou);
    }
  }
  r.lane_precision = {detected, built.lanes.size()};
  r.lane_recall = {detected, truth.lanes.size()};
  r.lane_rms_m = meanOf(rms_all);
  r.lane_miou = meanOf(iou_all);
  r.lane_rms_detected_m = meanOf(rms_det);
  r.lane_miou_detected = meanOf(iou_det);
  return match_of_built;
}

void scorePairs(const Prepared& truth, const Prepared& built, const std::vector<int>& match_of_built,
                const EvalOptions& o, EvalReport& r) {
  std::vector<double> pair_rms;
  std::set<std::pair<int, int>> found_truth_pairs;
  for (const auto& [pair, path] : built.pairs) {
    const int ti = match_of_built[pair.first], to = match_of_built[pair.second];
    const auto tp = truth.pairs.find({ti, to});
    PairDetail d{pair.first, pair.second, false, std::numeric_limits<double>::quiet_NaN()};
    if (ti >= 0 && to >= 0 && tp != truth.pairs.end()) {
      ++r.intersection_precision.hits;
      found_truth_pairs.insert({ti, to});
      const OverlapDistance od = overlapDistance(path, tp->second, o.sample_step_m);
      if (od.samples > 0) pair_rms.push_back(od.rms);
      d.correct = true;
      if (od.samples > 0) d.rms_m = od.rms;
    }
    r.built_pairs.push_back(d);
  }
  for (const auto& [pair, path] : truth.pairs) {
    r.truth_pairs.push_back({pair.first, pair.second, found_truth_pairs.count(pair) > 0,
                             std::numeric_limits<double>::quiet_NaN()});
  }
  r.intersection_precision.total = built.pairs.size();
  r.intersection_recall = {found_truth_pairs.size(), truth.pairs.size()};
  r.intersection_rms_m = meanOf(pair_rms);
}

void scoreGraph(const Prepared& truth, const Prepared& built, const std::vector<int>& match_of_built, EvalReport& r) {
  std::set<std::pair<int, int>> found_truth_edges;
  for (const auto& [a, b] : built.edges) {
    const int ta = match_of_built[a], tb = match_of_built[b];
    if (ta >= 0 && tb >= 0 && truth.edges.count({ta, tb})) {
      ++r.graph_precision.hits;
      found_truth_edges.insert({ta, tb});
    }
  }
  r.graph_precision.total = built.edges.size();
  r.graph_recall = {found_truth_edges.size(), truth.edges.size()};
}

void scoreRoads(const Prepared& truth, const Prepared& built, EvalReport& r) {
  std::map<int64_t, RoadDetail> roads;
  std::map<int64_t, std::vector<double>> road_iou, road_rms;
  for (size_t t = 0; t < truth.lanes.size(); ++t) {
    const LaneInfo& li = truth.lanes[t].info;
    RoadDetail& d = roads[li.road_id];
    d.road_id = li.road_id;
    d.from_node = li.from_node;
    d.to_node = li.to_node;
    ++d.truth_lanes;
  }
  for (const auto& l : built.lanes) {
    const auto it = roads.find(l.info.road_id);
    if (l.info.road_id >= 0 && it != roads.end()) ++it->second.built_lanes;
  }
  for (const LaneMatch& m : r.matches) {
    const int64_t id = truth.lanes[m.truth].info.road_id;
    RoadDetail& d = roads[id];
    ++d.matched;
    if (m.detected) ++d.detected;
    road_iou[id].push_back(m.iou);
    if (std::isfinite(m.rms_m)) road_rms[id].push_back(m.rms_m);
  }
  for (auto& [id, d] : roads) {
    d.mean_iou = meanOf(road_iou[id]);
    d.mean_rms_m = meanOf(road_rms[id]);
    r.roads.push_back(d);
  }
}

}  // namespace lanemap::eval::internal
