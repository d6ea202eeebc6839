#include "core/mapping/two_way_links.h"

#include "core/geo/polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

namespace lanemap::mapping {

namespace {

using Points = std::vector<Eigen::Vector3d>;

std::vector<double> stations(const Points& pts, const skeleton::Skeleton& sk, int64_t on_road) {
  std::vector<double> s;
  s.reserve(pts.size());
  for (const auto& p : pts) s.push_back(sk.project(on_road, p.head<2>()).s);
  return s;
}

// The part of a polyline between stations lo and hi (its points' stations along the road, rising or
// falling), its ends interpolated there; the polyline as it was when under two points would remain.
Points cutPolyline(const Points& in, const skeleton::Skeleton& sk, int64_t on_road, double lo, double hi) {
  Points pts = in;
  std::vector<double> s = stations(pts, sk, on_road);
  const bool against = s.size() >= 2 && s.front() > s.back();
  if (against) {
    std::reverse(pts.begin(), pts.end());
    std::reverse(s.begin(), s.end());
  }
  Points out;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (i > 0 && s[i] > s[i - 1]) {
      for (const double c : {lo, hi}) {
        if (s[i - 1] < c && s[i] > c) {
          const double t = (c - s[i - 1]) / (s[i] - s[i - 1]);
          out.push_back(pts[i - 1] + t * (pts[i] - pts[i - 1]));
        }
      }
    }
    if (s[i] >= lo && s[i] <= hi) out.push_back(pts[i]);
  }
  if (out.size() < 2) return in;
  if (against) std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace

std::optional<std::pair<double, double>> laneletStretch(const map::LaneMap& lanes, const skeleton::Skeleton& sk,
                                                        int64_t road_id, int64_t on_road, const TwoWayLinkOptions& o) {
  if (lanes.lanelets.empty() || !sk.road(on_road)) return std::nullopt;
  std::vector<std::pair<double, double>> each;
  for (const auto& l : lanes.lanelets) {
    if (l.kind != map::LaneletKind::kRoad || l.road_id != road_id || l.partial || l.centre.size() < 2) return std::nullopt;
    if (geo::polylineLengthXy(l.centre) > o.max_length_m + o.piece_tolerance_m) return std::nullopt;  // no link: nothing to project
    const std::vector<double> s = stations(l.centre, sk, on_road);
    each.emplace_back(*std::min_element(s.begin(), s.end()), *std::max_element(s.begin(), s.end()));
  }
  double s0 = std::numeric_limits<double>::infinity(), s1 = -s0;
  for (const auto& [a, b] : each) {
    s0 = std::min(s0, a);
    s1 = std::max(s1, b);
  }
  if (s1 - s0 > o.max_length_m) return std::nullopt;
  for (const auto& [a, b] : each) {
    if (a - s0 > o.piece_tolerance_m || s1 - b > o.piece_tolerance_m) return std::nullopt;
  }
  return std::make_pair(s0, s1);
}

void cutToStretch(map::LaneMap& lanes, const skeleton::Skeleton& sk, int64_t on_road, double s0, double s1) {
  std::set<int64_t> bounds;
  for (const auto& l : lanes.lanelets) {
    bounds.insert(l.left_id);
    bounds.insert(l.right_id);
  }
  for (auto& line : lanes.lines) {
    if (bounds.count(line.id)) line.points = cutPolyline(line.points, sk, on_road, s0, s1);
  }
  for (auto& l : lanes.lanelets) {
    const Eigen::Vector3d end_before = l.centre.back();
    l.centre = cutPolyline(l.centre, sk, on_road, s0, s1);
    if (!l.stop_line_id) continue;
    const Eigen::Vector3d moved = l.centre.back() - end_before;
    for (auto& line : lanes.lines) {
      if (line.id != *l.stop_line_id || bounds.count(line.id)) continue;
      for (auto& p : line.points) p += moved;
    }
  }
}

bool mayMatchTwoWayLink(const map::LaneMap& lanes, const skeleton::Skeleton& sk, int64_t road_id,
                        const TwoWayLinkOptions& o) {
  const auto* road = sk.road(road_id);
  return road && road->reverse_id >= 0 && laneletStretch(lanes, sk, road_id, road_id, o).has_value();
}

bool matchTwoWayLink(map::LaneMap& a, int64_t road_a, map::LaneMap& b, int64_t road_b, const skeleton::Skeleton& sk,
                     const TwoWayLinkOptions& o) {
  const auto* ra = sk.road(road_a);
  if (!ra || ra->reverse_id != road_b) return false;
  const auto sa = laneletStretch(a, sk, road_a, road_a, o);
  const auto sb = laneletStretch(b, sk, road_b, road_a, o);
  if (!sa || !sb) return false;
  const double lo = std::max(sa->first, sb->first), hi = std::min(sa->second, sb->second);
  const double apart = std::max(std::abs(sa->first - sb->first), std::abs(sa->second - sb->second));
  if (hi - lo < o.min_shared_m || apart <= o.same_end_m || apart > o.max_difference_m) return false;
  bool cut = false;
  for (auto [lanes, stretch] : {std::make_pair(&a, *sa), std::make_pair(&b, *sb)}) {
    if (stretch.first < lo - o.same_end_m || stretch.second > hi + o.same_end_m) {
      cutToStretch(*lanes, sk, road_a, lo, hi);
      cut = true;
    }
  }
  return cut;
}

}  // namespace lanemap::mapping
