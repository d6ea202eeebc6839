#include "core/mapping/carried_lanes.h"

#include "core/geo/polyline.h"
#include "core/lanes/frenet.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>

namespace lanemap::mapping {

namespace {

double angleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::abs(std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)));
}

// The lanes of the mapped road beside `road` at one of its ends (kBefore: ending at its start,
// kAfter: starting at its end) that runs on straight from or into it.
enum class Side { kBefore, kAfter };

std::vector<lanes::CarriedLane> lanesBeside(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road, Side side,
                                            const std::map<int64_t, map::LaneMap>& mapped, const lanes::ExplorerOptions& o,
                                            int64_t* from_road) {
  if (from_road) *from_road = -1;
  std::vector<lanes::CarriedLane> out;
  const bool before_it = side == Side::kBefore;
  const skeleton::Intersection* junction = skeleton.intersection(before_it ? road.from : road.to);
  if (!junction || road.polyline.size() < 2 || !isShortRoad(road, o)) return out;
  const lanes::FrenetFrame frame(road.polyline, o.frame_spacing_m, o.frame_smoothing_m);
  const Eigen::Vector2d heading = frame.tangent(std::clamp(before_it ? road.s_begin : road.s_end, 0.0, frame.length()));
  const skeleton::AtomicRoad* beside = nullptr;
  double best = o.carry_max_turn_rad;
  std::unique_ptr<lanes::FrenetFrame> beside_frame;
  for (int64_t id : before_it ? junction->incoming : junction->outgoing) {
    const skeleton::AtomicRoad* r = skeleton.road(id);
    if (!r || r->id == road.reverse_id || r->id == road.id || r->polyline.size() < 2) continue;
    if ((r->reverse_id >= 0) != (road.reverse_id >= 0)) continue;
    auto it = mapped.find(r->id);
    if (it == mapped.end() || it->second.lanelets.empty()) continue;
    auto f = std::make_unique<lanes::FrenetFrame>(r->polyline, o.frame_spacing_m, o.frame_smoothing_m);
    const double turn = angleBetween(f->tangent(std::clamp(before_it ? r->s_end : r->s_begin, 0.0, f->length())), heading);
    if (turn <= best) {
      best = turn;
      beside = r;
      beside_frame = std::move(f);
    }
  }
  if (!beside) return out;
  // Each road lanelet's centre as d(s) in the road beside's frame.
  const map::LaneMap& lanes = mapped.at(beside->id);
  struct Piece {
    const map::Lanelet* ll;
    std::vector<double> s, d;  // increasing s
  };
  std::vector<Piece> pieces;
  for (const auto& ll : lanes.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad || ll.centre.size() < 2) continue;
    Piece p{&ll, {}, {}};
    for (const auto& q : ll.centre) {
      const Eigen::Vector2d sd = beside_frame->toFrenet(q.head<2>());
      if (!p.s.empty() && sd.x() <= p.s.back()) continue;
      p.s.push_back(sd.x());
      p.d.push_back(sd.y());
    }
    if (p.s.size() >= 2) pieces.push_back(std::move(p));
  }
  const auto dAt = [](const Piece& p, double s) {
    const size_t i = std::upper_bound(p.s.begin(), p.s.end(), s) - p.s.begin();
    if (i == 0 || i >= p.s.size()) return p.d[i == 0 ? 0 : p.s.size() - 1];
    const double t = (s - p.s[i - 1]) / (p.s[i] - p.s[i - 1]);
    return p.d[i - 1] + t * (p.d[i] - p.d[i - 1]);
  };
  // The road's through lanes: the fewest lanes any of its stations has (a turn pocket opens before
  // the junction, and the lanes beside it shift over: neither runs on), at the station with that
  // few nearest the short road (the last one of the road before, the first of the road after).
  const double s0 = std::max(0.0, beside->s_begin), s1 = std::min(beside->s_end, beside_frame->length());
  size_t fewest = 0;
  double nearest = 0.0;
  for (double st = s0; st <= s1; st += 2.0) {
    size_t n = 0;
    for (const auto& p : pieces) n += st >= p.s.front() && st <= p.s.back();
    if (n == 0) continue;
    if (fewest == 0 || n < fewest || (n == fewest && before_it)) {
      fewest = n;
      nearest = st;
    }
  }
  if (fewest == 0) return out;
  const double st = nearest;
  for (const auto& p : pieces) {
    if (st < p.s.front() || st > p.s.back()) continue;
    const map::LineString* left = lanes.line(p.ll->left_id);
    const map::LineString* right = lanes.line(p.ll->right_id);
    if (!left || !right || left->points.empty() || right->points.empty()) continue;
    lanes::CarriedLane c;
    c.d = dAt(p, st);
    const Eigen::Vector2d at = beside_frame->toEnu(st, c.d);
    c.half_left_m = geo::distanceToPolylineXy(left->points, at);
    c.half_right_m = geo::distanceToPolylineXy(right->points, at);
    c.left_type = left->type;
    c.right_type = right->type;
    if (!(c.half_left_m > 0.5 && c.half_left_m < 4.0 && c.half_right_m > 0.5 && c.half_right_m < 4.0)) continue;
    out.push_back(c);
  }
  if (from_road && !out.empty()) *from_road = beside->id;
  return out;
}

}  // namespace

bool isShortRoad(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& o) {
  return road.s_end - road.s_begin < o.carry_lanes_max_m;
}

std::vector<lanes::CarriedLane> lanesLeadingInto(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                 const std::map<int64_t, map::LaneMap>& mapped,
                                                 const lanes::ExplorerOptions& o, int64_t* from_road) {
  return lanesBeside(skeleton, road, Side::kBefore, mapped, o, from_road);
}

std::vector<lanes::CarriedLane> lanesLeadingOutOf(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                  const std::map<int64_t, map::LaneMap>& mapped,
                                                  const lanes::ExplorerOptions& o, int64_t* to_road) {
  return lanesBeside(skeleton, road, Side::kAfter, mapped, o, to_road);
}

std::vector<lanes::CarriedLane> lanesRunningThrough(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                    const std::map<int64_t, map::LaneMap>& mapped,
                                                    const lanes::ExplorerOptions& o, int64_t* from_road) {
  auto carried = lanesLeadingInto(skeleton, road, mapped, o, from_road);
  if (carried.empty()) carried = lanesLeadingOutOf(skeleton, road, mapped, o, from_road);
  if (carried.empty() && o.lanes_from_osm_way) {
    carried = lanesFromOsmWay(road, o);
    if (from_road && !carried.empty()) *from_road = road.id;
  }
  return carried;
}

std::vector<lanes::CarriedLane> lanesFromOsmWay(const skeleton::AtomicRoad& road, const lanes::ExplorerOptions& o) {
  std::vector<lanes::CarriedLane> out;
  if (!isShortRoad(road, o)) return out;
  const bool two_way = road.reverse_id >= 0;
  const auto count = [&](const std::string& key) {
    const auto it = road.tags.find(key);
    if (it == road.tags.end()) return 0;
    try {
      return std::max(0, std::stoi(it->second));
    } catch (const std::exception&) {
      return 0;  // "2;3" and the like: not a count
    }
  };
  int n = two_way ? count(road.along_way ? "lanes:forward" : "lanes:backward") : 0;
  if (n == 0) n = two_way ? (count("lanes") + 1) / 2 : count("lanes");
  n = std::clamp(n, 1, 8);
  const double w = 2.0 * o.default_half_width_m;
  for (int k = 0; k < n; ++k) {  // left to right
    lanes::CarriedLane l;
    l.seen = false;
    l.half_left_m = l.half_right_m = o.default_half_width_m;
    if (!two_way) {
      l.d = (0.5 * (n - 1) - k) * w;
    } else if (o.right_hand_traffic) {
      l.d = -(k + 0.5) * w;          // right of the line, the lane next to it first
    } else {
      l.d = (n - k - 0.5) * w;       // left of the line, the outermost first
    }
    out.push_back(l);
  }
  return out;
}

std::vector<int64_t> roadsAwaitingLanesFrom(const skeleton::Skeleton& skeleton, int64_t mapped_road,
                                            const std::set<int64_t>& awaiting) {
  std::vector<int64_t> out;
  const skeleton::AtomicRoad* r = skeleton.road(mapped_road);
  if (!r) return out;
  for (int64_t id : awaiting) {
    const skeleton::AtomicRoad* a = skeleton.road(id);
    if (!a || id == mapped_road || id == r->reverse_id) continue;
    if (a->from == r->to || a->to == r->from) out.push_back(id);
  }
  return out;
}

}  // namespace lanemap::mapping
