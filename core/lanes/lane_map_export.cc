// toLaneMap (explorer.h): the explored lanes of one road as Lanelet2 lanelets.
#include "core/lanes/explorer.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace lanemap::lanes {

namespace {

double interp(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
  if (xs.size() == 1) return ys[0];
  auto it = std::upper_bound(xs.begin(), xs.end(), x);
  size_t i = std::clamp<size_t>(it - xs.begin(), 1, xs.size() - 1) - 1;
  const double t = std::clamp((x - xs[i]) / std::max(1e-9, xs[i + 1] - xs[i]), 0.0, 1.0);
  return ys[i] + t * (ys[i + 1] - ys[i]);
}

}  // namespace

map::LaneMap toLaneMap(const ExplorationResult& r, double lat, double lon, double alt) {
  map::LaneMap out;
  out.origin_lat = lat;
  out.origin_lon = lon;
  out.origin_alt = alt;
  const int64_t base = (r.road_id + 1) * 100000;
  int64_t next = base + 1;
  // Cut points of every lane: where a lane splits off it or merges into it.
  std::vector<std::vector<double>> cuts(r.lanes.size());
  for (size_t i = 0; i < r.lanes.size(); ++i) cuts[i] = {r.lanes[i].s_begin, r.lanes[i].s_end};
  auto addCut = [&](int lane, double s) {
    const Lane& l = r.lanes[lane];
    if (s > l.s_begin + 1.0 && s < l.s_end - 1.0) cuts[lane].push_back(s);
  };
  for (const Lane& l : r.lanes) {
    if (l.split_from >= 0) addCut(l.split_from, l.s_begin);
    if (l.merges_into >= 0) addCut(l.merges_into, l.s_end);
  }
  // piece ids per lane: (start s, lanelet id)
  std::vector<std::vector<std::pair<double, int64_t>>> pieces(r.lanes.size());
  std::map<int64_t, size_t> pos;
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    const Lane& l = r.lanes[i];
    auto& c = cuts[i];
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end(), [](double a, double b) { return std::abs(a - b) < 1.0; }), c.end());
    if (c.size() < 2) c = {l.s_begin, l.s_end};
    for (size_t k = 0; k + 1 < c.size(); ++k) {
      const double a = c[k], b = c[k + 1];
      std::vector<double> ss{a};
      for (double s : l.waypoint_s) if (s > a + 0.2 && s < b - 0.2) ss.push_back(s);
      ss.push_back(b);
      map::LineString left, right;
      left.id = next++;
      right.id = next++;
      left.type = l.left.type;
      right.type = l.right.type;
      map::Lanelet ll;
      ll.id = next++;
      ll.kind = map::LaneletKind::kRoad;
      ll.road_id = r.road_id;
      ll.from_node = r.from_node;
      ll.to_node = r.to_node;
      ll.index_from_left = l.index_from_left;
      ll.left_id = left.id;
      ll.right_id = right.id;
      for (double s : ss) {
        const double dl = interp(l.waypoint_s, l.left.d, s), dr = interp(l.waypoint_s, l.right.d, s);
        const Eigen::Vector2d pl = r.frame->toEnu(s, dl), pr = r.frame->toEnu(s, dr), pc = r.frame->toEnu(s, l.centre.d(s));
        left.points.emplace_back(pl.x(), pl.y(), 0.0);
        right.points.emplace_back(pr.x(), pr.y(), 0.0);
        ll.centre.emplace_back(pc.x(), pc.y(), 0.0);
      }
      pieces[i].push_back({a, ll.id});
      out.lines.push_back(std::move(left));
      out.lines.push_back(std::move(right));
      pos[ll.id] = out.lanelets.size();
      out.lanelets.push_back(std::move(ll));
    }
  }
  auto lanelet = [&](int64_t id) -> map::Lanelet& { return out.lanelets[pos.at(id)]; };
  // The piece of lane i that ends at s (or starts at s).
  auto pieceEnding = [&](int i, double s) -> int64_t {
    const auto& p = pieces[i];
    for (size_t k = 0; k < p.size(); ++k) {
      const double end = k + 1 < p.size() ? p[k + 1].first : r.lanes[i].s_end;
      if (std::abs(end - s) < 1.0) return p[k].second;
    }
    return -1;
  };
  auto pieceStarting = [&](int i, double s) -> int64_t {
    for (const auto& [a, id] : pieces[i]) if (std::abs(a - s) < 1.0) return id;
    return -1;
  };
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    for (size_t k = 0; k + 1 < pieces[i].size(); ++k) lanelet(pieces[i][k].second).successors.push_back(pieces[i][k + 1].second);
    const Lane& l = r.lanes[i];
    if (l.split_from >= 0) {
      const int64_t from = pieceEnding(l.split_from, l.s_begin);
      if (from >= 0) lanelet(from).successors.push_back(pieces[i].front().second);
    }
    if (l.merges_into >= 0) {
      const int64_t to = pieceStarting(l.merges_into, l.s_end);
      if (to >= 0) lanelet(pieces[i].back().second).successors.push_back(to);
    }
  }
  return out;
}

}  // namespace lanemap::lanes
