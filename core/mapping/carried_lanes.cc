#include "core/mapping/carried_lanes.h"

#include "core/geo/polyline.h"
#include "core/lanes/frenet.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

namespace lanemap::mapping {

namespace {

double angleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::abs(std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)));
}

}  // namespace

std::vector<lanes::CarriedLane> lanesLeadingInto(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                                                 const std::map<int64_t, map::LaneMap>& mapped,
                                                 const lanes::ExplorerOptions& o, int64_t* from_road) {
  if (from_road) *from_road = -1;
  std::vector<lanes::CarriedLane> out;
  const skeleton::Intersection* start = skeleton.intersection(road.from);
  if (!start || road.polyline.size() < 2 || !(road.s_end - road.s_begin < o.carry_lanes_max_m)) return out;
  const lanes::FrenetFrame frame(road.polyline, o.frame_spacing_m, o.frame_smoothing_m);
  const Eigen::Vector2d heading = frame.tangent(std::clamp(road.s_begin, 0.0, frame.length()));
  const skeleton::AtomicRoad* before = nullptr;
  double best = o.carry_max_turn_rad;
  std::unique_ptr<lanes::FrenetFrame> before_frame;
  for (int64_t id : start->incoming) {
    const skeleton::AtomicRoad* r = skeleton.road(id);
    if (!r || r->id == road.reverse_id || r->polyline.size() < 2) continue;
    if ((r->reverse_id >= 0) != (road.reverse_id >= 0)) continue;
    auto it = mapped.find(r->id);
    if (it == mapped.end() || it->second.lanelets.empty()) continue;
    auto f = std::make_unique<lanes::FrenetFrame>(r->polyline, o.frame_spacing_m, o.frame_smoothing_m);
    const double turn = angleBetween(f->tangent(std::clamp(r->s_end, 0.0, f->length())), heading);
    if (turn <= best) {
      best = turn;
      before = r;
      before_frame = std::move(f);
    }
  }
  if (!before) return out;
  // Each road lanelet's centre as d(s) in the road before's frame.
  const map::LaneMap& lanes = mapped.at(before->id);
  struct Piece {
    const map::Lanelet* ll;
    std::vector<double> s, d;  // increasing s
  };
  std::vector<Piece> pieces;
  for (const auto& ll : lanes.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad || ll.centre.size() < 2) continue;
    Piece p{&ll, {}, {}};
    for (const auto& q : ll.centre) {
      const Eigen::Vector2d sd = before_frame->toFrenet(q.head<2>());
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
  // the junction, and the lanes beside it shift over: neither runs on), at the last station that
  // has that few.
  const double s0 = std::max(0.0, before->s_begin), s1 = std::min(before->s_end, before_frame->length());
  size_t fewest = 0;
  double last = 0.0;
  for (double st = s0; st <= s1; st += 2.0) {
    size_t n = 0;
    for (const auto& p : pieces) n += st >= p.s.front() && st <= p.s.back();
    if (n == 0) continue;
    if (fewest == 0 || n <= fewest) {
      fewest = n;
      last = st;
    }
  }
  if (fewest == 0) return out;
  const double st = last;
  for (const auto& p : pieces) {
    if (st < p.s.front() || st > p.s.back()) continue;
    const map::LineString* left = lanes.line(p.ll->left_id);
    const map::LineString* right = lanes.line(p.ll->right_id);
    if (!left || !right || left->points.empty() || right->points.empty()) continue;
    lanes::CarriedLane c;
    c.d = dAt(p, st);
    const Eigen::Vector2d at = before_frame->toEnu(st, c.d);
    c.half_left_m = geo::distanceToPolylineXy(left->points, at);
    c.half_right_m = geo::distanceToPolylineXy(right->points, at);
    c.left_type = left->type;
    c.right_type = right->type;
    if (!(c.half_left_m > 0.5 && c.half_left_m < 4.0 && c.half_right_m > 0.5 && c.half_right_m < 4.0)) continue;
    out.push_back(c);
  }
  if (from_road && !out.empty()) *from_road = before->id;
  return out;
}

}  // namespace lanemap::mapping
