// Map evaluation, step 1: a map's lanes, chains of road lanelets joined along successors (see
// evaluate.h for the definitions), the (in lane, out lane) pairs intersection lanelets join, the
// lane graph's edges and the Chamfer instances.
#include "core/eval/evaluate_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <unordered_map>

namespace lanemap::eval::internal {

namespace {

using Eigen::Vector2d;

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

  void makeInstances() {
    std::vector<Polyline> intersection_centres;
    for (size_t i = 0; i < m_.lanelets.size(); ++i) {
      if (isIntersection(m_.lanelets[i])) intersection_centres.push_back(centres_[i]);
    }
    makeChamferInstances(out_, intersection_centres, o_);
  }

  const map::LaneMap& m_;
  const EvalOptions& o_;
  std::unordered_map<int64_t, size_t> pos_;
  std::unordered_map<int64_t, const map::LineString*> lines_;
  std::vector<Polyline> centres_;
  Prepared out_;
};

}  // namespace

Prepared prepareMap(const map::LaneMap& m, const EvalOptions& o) { return Preparer(m, o).run(); }

}  // namespace lanemap::eval::internal
