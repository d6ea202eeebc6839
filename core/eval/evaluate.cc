// Map evaluation (see evaluate.h for every definition).
#include "core/eval/evaluate.h"
#include "core/io/lanelet2.h"

#include "core/eval/geometry.h"

#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace lanemap::eval {

double Ratio::value() const {
  return total == 0 ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(hits) / static_cast<double>(total);
}

namespace {

using Eigen::Vector2d;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Polyline xy(const std::vector<Eigen::Vector3d>& pts) {
  Polyline out;
  out.reserve(pts.size());
  for (const auto& p : pts) out.push_back(p.head<2>());
  return out;
}

void appendPolyline(Polyline& acc, const Polyline& more) {
  for (const auto& p : more) {
    if (acc.empty() || (p - acc.back()).norm() > 0.01) acc.push_back(p);
  }
}

double headingOf(const Polyline& c, bool at_end) {
  if (c.size() < 2) return 0.0;
  const Vector2d d = at_end ? Vector2d(c[c.size() - 1] - c[c.size() - 2]) : Vector2d(c[1] - c[0]);
  return std::atan2(d.y(), d.x());
}

double angleDiff(double a, double b) {
  double d = std::fmod(a - b, 2.0 * M_PI);
  if (d > M_PI) d -= 2.0 * M_PI;
  if (d < -M_PI) d += 2.0 * M_PI;
  return std::abs(d);
}

struct Box {
  Vector2d lo = Vector2d::Constant(std::numeric_limits<double>::infinity());
  Vector2d hi = Vector2d::Constant(-std::numeric_limits<double>::infinity());
  void add(const Polyline& pts) {
    for (const auto& p : pts) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  // Distance between two boxes (0 when they overlap): a lower bound of any point distance.
  double gap(const Box& o) const {
    const Vector2d d = (lo - o.hi).cwiseMax(o.lo - hi).cwiseMax(Vector2d::Zero());
    return d.norm();
  }
};

struct Instance {
  Polyline pts;  // chamfer_points resampled
  Box box;
  double score = 0.0;
};

struct Lane {
  LaneInfo info;
  Polyline centre, left, right;
  LanePolygon polygon;
  Box box;
};

// One map, prepared: lanes, intersection pairs, graph edges, Chamfer instances.
struct Prepared {
  std::vector<Lane> lanes;
  std::unordered_map<int64_t, int> lane_of;       // road lanelet id -> lane
  std::map<std::pair<int, int>, Polyline> pairs;  // (in lane, out lane) -> connection centre
  std::set<std::pair<int, int>> edges;            // lane graph
  std::vector<Instance> centres, bounds;
  size_t intersection_lanelets = 0;
  size_t repaired = 0;
};

class Preparer {
 public:
  Preparer(const map::LaneMap& m, const EvalOptions& o) : m_(m), o_(o) {
    for (size_t i = 0; i < m.lanelets.size(); ++i) pos_[m.lanelets[i].id] = i;
    for (const auto& l : m.lines) lines_[l.id] = &l;
  }

  Prepared run() {
    for (const auto& ll : m_.lanelets) {
      if (isIntersection(ll)) ++out_.intersection_lanelets;
    }
    chainLanes();
    findPairs();
    findEdges();
    makeInstances();
    return std::move(out_);
  }

 private:
  static bool isIntersection(const map::Lanelet& ll) { return ll.kind == map::LaneletKind::kIntersection; }
  const map::Lanelet* find(int64_t id) const {
    const auto it = pos_.find(id);
    return it == pos_.end() ? nullptr : &m_.lanelets[it->second];
  }
  Polyline centreOf(const map::Lanelet& ll) const {
    if (ll.centre.size() >= 2) return xy(ll.centre);
    const Polyline l = boundOf(ll, true), r = boundOf(ll, false);
    if (l.size() < 2 || r.size() < 2) return {};
    const size_t n = std::max(l.size(), r.size());
    const Polyline a = resampleCount(l, n), b = resampleCount(r, n);
    Polyline c(n);
    for (size_t i = 0; i < n; ++i) c[i] = 0.5 * (a[i] + b[i]);
    return c;
  }
  // A bound in the lanelet's driving direction.
  Polyline boundOf(const map::Lanelet& ll, bool left) const {
    const auto it = lines_.find(left ? ll.left_id : ll.right_id);
    if (it == lines_.end()) return {};
    Polyline pts = xy(it->second->points);
    if (ll.centre.size() >= 2 && pts.size() >= 2) {
      const Vector2d c0 = ll.centre.front().head<2>(), c1 = ll.centre.back().head<2>();
      const double same = (pts.front() - c0).norm() + (pts.back() - c1).norm();
      const double swapped = (pts.front() - c1).norm() + (pts.back() - c0).norm();
      if (swapped < same) std::reverse(pts.begin(), pts.end());
    }
    return pts;
  }

  bool linkable(const map::Lanelet& a, const map::Lanelet& b) const {
    if (isIntersection(a) || isIntersection(b)) return false;
    return a.road_id < 0 || b.road_id < 0 || a.road_id == b.road_id;
  }
  double score(size_t a, size_t b) const {
    const Polyline& ca = centres_[a];
    const Polyline& cb = centres_[b];
    if (ca.size() < 2 || cb.size() < 2) return std::numeric_limits<double>::infinity();
    return (ca.back() - cb.front()).norm() + angleDiff(headingOf(ca, true), headingOf(cb, false));
  }

  void chainLanes() {
    const size_t n = m_.lanelets.size();
    centres_.resize(n);
    for (size_t i = 0; i < n; ++i) centres_[i] = centreOf(m_.lanelets[i]);
    std::vector<long> best_succ(n, -1), best_pred(n, -1);
    std::vector<double> succ_score(n, std::numeric_limits<double>::infinity()), pred_score = succ_score;
    for (size_t a = 0; a < n; ++a) {
      const map::Lanelet& la = m_.lanelets[a];
      if (isIntersection(la)) continue;
      for (int64_t sid : la.successors) {
        const auto it = pos_.find(sid);
        if (it == pos_.end() || it->second == a) continue;
        const size_t b = it->second;
        if (!linkable(la, m_.lanelets[b])) continue;
        const double s = score(a, b);
        if (s < succ_score[a]) {
          succ_score[a] = s;
          best_succ[a] = static_cast<long>(b);
        }
        if (s < pred_score[b]) {
          pred_score[b] = s;
          best_pred[b] = static_cast<long>(a);
        }
      }
    }
    std::vector<long> next(n, -1);
    std::vector<bool> has_prev(n, false);
    for (size_t a = 0; a < n; ++a) {
      if (best_succ[a] >= 0 && best_pred[best_succ[a]] == static_cast<long>(a)) {
        next[a] = best_succ[a];
        has_prev[best_succ[a]] = true;
      }
    }
    std::vector<bool> used(n, false);
    const auto chainFrom = [&](size_t start) {
      Lane lane;
      for (long i = static_cast<long>(start); i >= 0 && !used[i]; i = next[i]) {
        used[i] = true;
        const map::Lanelet& ll = m_.lanelets[i];
        lane.info.lanelets.push_back(ll.id);
        appendPolyline(lane.centre, centres_[i]);
        appendPolyline(lane.left, boundOf(ll, true));
        appendPolyline(lane.right, boundOf(ll, false));
      }
      const map::Lanelet& first = m_.lanelets[start];
      lane.info.road_id = first.road_id;
      lane.info.from_node = first.from_node;
      lane.info.to_node = first.to_node;
      lane.info.length_m = polylineLength(lane.centre);
      lane.polygon = LanePolygon(lane.left, lane.right);
      if (lane.polygon.repaired()) ++out_.repaired;
      lane.box.add(lane.centre);
      lane.box.add(lane.left);
      lane.box.add(lane.right);
      const int idx = static_cast<int>(out_.lanes.size());
      for (int64_t id : lane.info.lanelets) out_.lane_of[id] = idx;
      out_.lanes.push_back(std::move(lane));
    };
    for (size_t i = 0; i < n; ++i) {
      if (!isIntersection(m_.lanelets[i]) && !has_prev[i] && !used[i]) chainFrom(i);
    }
    for (size_t i = 0; i < n; ++i) {  // cycles
      if (!isIntersection(m_.lanelets[i]) && !used[i]) chainFrom(i);
    }
  }

  // (in lane, out lane) pairs through chains of intersection lanelets.
  void findPairs() {
    for (const auto& ll : m_.lanelets) {
      if (isIntersection(ll)) continue;
      const auto in = out_.lane_of.find(ll.id);
      if (in == out_.lane_of.end()) continue;
      for (int64_t sid : ll.successors) {
        const map::Lanelet* s = find(sid);
        if (!s || !isIntersection(*s)) continue;
        std::set<int64_t> visited;
        walk(in->second, *s, {}, visited);
      }
    }
  }
  void walk(int in_lane, const map::Lanelet& x, Polyline path, std::set<int64_t>& visited) {
    if (!visited.insert(x.id).second || visited.size() > 16) return;
    appendPolyline(path, centres_[pos_.at(x.id)]);
    for (int64_t sid : x.successors) {
      const map::Lanelet* s = find(sid);
      if (!s) continue;
      if (isIntersection(*s)) {
        walk(in_lane, *s, path, visited);
      } else if (const auto out = out_.lane_of.find(sid); out != out_.lane_of.end()) {
        out_.pairs.emplace(std::make_pair(in_lane, out->second), path);
      }
    }
  }

  void findEdges() {
    for (const auto& [pair, path] : out_.pairs) out_.edges.insert(pair);
    for (const auto& ll : m_.lanelets) {
      const auto a = out_.lane_of.find(ll.id);
      if (a == out_.lane_of.end()) continue;
      for (int64_t sid : ll.successors) {
        const auto b = out_.lane_of.find(sid);
        if (b != out_.lane_of.end() && b->second != a->second) out_.edges.insert({a->second, b->second});
      }
    }
  }

  Instance instance(const Polyline& pts) const {
    Instance in;
    in.pts = resampleCount(pts, o_.chamfer_points);
    in.box.add(in.pts);
    in.score = polylineLength(pts);
    return in;
  }
  void makeInstances() {
    for (const auto& lane : out_.lanes) {
      if (lane.centre.size() >= 2) out_.centres.push_back(instance(lane.centre));
    }
    for (size_t i = 0; i < m_.lanelets.size(); ++i) {
      if (isIntersection(m_.lanelets[i]) && centres_[i].size() >= 2) out_.centres.push_back(instance(centres_[i]));
    }
    for (const auto& lane : out_.lanes) {
      for (const Polyline* b : {&lane.left, &lane.right}) {
        if (b->size() < 2) continue;
        Instance in = instance(*b);
        const bool dup = std::any_of(out_.bounds.begin(), out_.bounds.end(), [&](const Instance& k) {
          return k.box.gap(in.box) < o_.duplicate_chamfer_m && chamferDistance(k.pts, in.pts) < o_.duplicate_chamfer_m;
        });
        if (!dup) out_.bounds.push_back(std::move(in));
      }
    }
  }

  const map::LaneMap& m_;
  const EvalOptions& o_;
  std::unordered_map<int64_t, size_t> pos_;
  std::unordered_map<int64_t, const map::LineString*> lines_;
  std::vector<Polyline> centres_;
  Prepared out_;
};

// MapTR's AP for one class.
ApResult averagePrecision(const std::vector<Instance>& truth, const std::vector<Instance>& pred,
                          const std::vector<double>& thresholds) {
  ApResult r;
  r.truth_instances = truth.size();
  r.predictions = pred.size();
  std::vector<size_t> order(pred.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return pred[a].score > pred[b].score; });
  // Nearest truth instance of every prediction (independent of the threshold).
  std::vector<long> nearest(pred.size(), -1);
  std::vector<double> dist(pred.size(), std::numeric_limits<double>::infinity());
  for (size_t p = 0; p < pred.size(); ++p) {
    for (size_t g = 0; g < truth.size(); ++g) {
      if (pred[p].box.gap(truth[g].box) >= dist[p]) continue;
      const double cd = chamferDistance(pred[p].pts, truth[g].pts);
      if (cd < dist[p]) {
        dist[p] = cd;
        nearest[p] = static_cast<long>(g);
      }
    }
  }
  for (double thr : thresholds) {
    if (truth.empty()) {
      r.ap[thr] = kNaN;
      continue;
    }
    std::vector<bool> covered(truth.size(), false);
    std::vector<double> rec, prec;
    size_t tp = 0, fp = 0;
    for (size_t p : order) {
      if (nearest[p] >= 0 && dist[p] < thr && !covered[nearest[p]]) {
        covered[nearest[p]] = true;
        ++tp;
      } else {
        ++fp;
      }
      rec.push_back(static_cast<double>(tp) / static_cast<double>(truth.size()));
      prec.push_back(static_cast<double>(tp) / static_cast<double>(tp + fp));
    }
    std::vector<double> mrec{0.0}, mpre{0.0};
    mrec.insert(mrec.end(), rec.begin(), rec.end());
    mpre.insert(mpre.end(), prec.begin(), prec.end());
    mrec.push_back(1.0);
    mpre.push_back(0.0);
    for (size_t i = mpre.size() - 1; i > 0; --i) mpre[i - 1] = std::max(mpre[i - 1], mpre[i]);
    double ap = 0.0;
    for (size_t i = 0; i + 1 < mrec.size(); ++i) {
      if (mrec[i + 1] != mrec[i]) ap += (mrec[i + 1] - mrec[i]) * mpre[i + 1];
    }
    r.ap[thr] = ap;
  }
  return r;
}

double meanOf(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

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

EvalReport evaluate(const map::LaneMap& truth_map, const map::LaneMap& built_map, const EvalOptions& o) {
  const Prepared truth = Preparer(truth_map, o).run();
  const Prepared built = Preparer(built_map, o).run();
  EvalReport r;
  for (const auto& l : truth.lanes) r.truth_lanes.push_back(l.info);
  for (const auto& l : built.lanes) r.built_lanes.push_back(l.info);
  r.truth_intersection_lanelets = truth.intersection_lanelets;
  r.built_intersection_lanelets = built.intersection_lanelets;
  r.repaired_polygons = truth.repaired + built.repaired;

  // ---- lanes: candidates, greedy one-to-one matching
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

  // ---- intersections: (in lane, out lane) pairs through the matching
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

  // ---- lane graph
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

  // ---- Chamfer AP
  r.ap_centre = averagePrecision(truth.centres, built.centres, o.chamfer_thresholds);
  r.ap_boundary = averagePrecision(truth.bounds, built.bounds, o.chamfer_thresholds);
  for (double thr : o.chamfer_thresholds) {
    std::vector<double> v;
    for (const ApResult* a : {&r.ap_centre, &r.ap_boundary}) {
      if (std::isfinite(a->ap.at(thr))) v.push_back(a->ap.at(thr));
    }
    r.chamfer_ap[thr] = meanOf(v);
  }

  // ---- per road (truth road id; untagged lanes together under -1)
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
  r.regulatory = scoreRegulatory(truth_map, built_map, o.regulatory);
  return r;
}

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
  std::vector<const LaneMatch*> by_truth(r.truth_lanes.size(), nullptr);
  for (const auto& m : r.matches) by_truth[m.truth] = &m;
  json lanes = json::array();
  for (size_t t = 0; t < r.truth_lanes.size(); ++t) {
    const LaneInfo& li = r.truth_lanes[t];
    json l = {{"road_id", li.road_id}, {"length_m", li.length_m}, {"lanelets", li.lanelets}};
    if (const LaneMatch* m = by_truth[t]) {
      l["built_lanelets"] = r.built_lanes[m->built].lanelets;
      l["iou"] = num(m->iou);
      l["rms_m"] = num(m->rms_m);
      l["coverage"] = num(m->coverage);
      l["detected"] = m->detected;
    } else {
      l["built_lanelets"] = json::array();
      l["detected"] = false;
    }
    lanes.push_back(l);
  }
  j["lanes_detail"] = lanes;
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

geo::LatLonAlt lanelet2Origin(const std::string& path) {
  // lanemap's files: the writer's origin, from the map's sidecar (core/io/lanelet2.h).
  if (const auto o = io::lanelet2WriterOrigin(path)) return {o->lat, o->lon, 0.0};
  osmium::io::Reader reader(path, osmium::osm_entity_bits::node);
  while (osmium::memory::Buffer buffer = reader.read()) {
    for (const auto& node : buffer.select<osmium::Node>()) {
      if (!node.location().valid()) continue;
      const double lat = node.location().lat(), lon = node.location().lon();
      const char* lx_tag = node.tags()["local_x"];
      const char* ly_tag = node.tags()["local_y"];
      const std::string lx = lx_tag ? lx_tag : "", ly = ly_tag ? ly_tag : "";
      reader.close();
      geo::LatLonAlt o{lat, lon, 0.0};
      if (lx.empty() || ly.empty()) return o;
      char* ex = nullptr;
      char* ey = nullptr;
      const Vector2d target(std::strtod(lx.c_str(), &ex), std::strtod(ly.c_str(), &ey));
      if (*ex != '\0' || *ey != '\0' || !target.allFinite()) return o;
      // The origin whose ENU frame puts this node at (local_x, local_y): a few fixed-point steps.
      for (int it = 0; it < 5; ++it) {
        const geo::LocalFrame f(o);
        const Vector2d p = f.toEnu(lat, lon, 0.0).head<2>();
        const Vector2d err = p - target;
        if (err.norm() < 1e-4) break;
        o = f.toWgs84(Eigen::Vector3d(err.x(), err.y(), 0.0));
        o.alt = 0.0;
      }
      return o;
    }
  }
  reader.close();
  throw std::runtime_error("no node with a location in '" + path + "'");
}

}  // namespace lanemap::eval
