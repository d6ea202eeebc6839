// Intersection topology and lanelets (see intersections.h).
#include "core/intersections/intersections.h"

#include "core/config/yaml_reader.h"
#include "core/geo/polyline.h"
#include "core/io/lanelet2_orientation.h"
#include "core/skeleton/road_direction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <unordered_map>

namespace lanemap::intersections {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using map::TurnDirection;

using geo::cross;  // core/geo/polyline.h
using geo::unit;

// Of the indices first..count-1, the one with the least dist(k), that distance and the next least
// (how clearly it is the nearest); best -1 and both INFINITY when there is none.
struct NearestTwo {
  int best = -1;
  double best_d = INFINITY, second_d = INFINITY;
};
template <class Dist>
NearestTwo nearestTwo(int first, int count, Dist dist) {
  NearestTwo n;
  for (int k = first; k < count; ++k) {
    const double e = dist(k);
    if (e < n.best_d) {
      n.second_d = n.best_d;
      n.best_d = e;
      n.best = k;
    } else {
      n.second_d = std::min(n.second_d, e);
    }
  }
  return n;
}

// Closest point of a polyline: arc length and signed lateral offset (left positive).
struct Projection {
  double s = 0.0, d = 0.0, distance = 0.0;
};
Projection project(const std::vector<Vector2d>& line, const Vector2d& p) {
  Projection best;
  best.distance = std::numeric_limits<double>::infinity();
  double s0 = 0.0;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Vector2d ab = line[i + 1] - line[i];
    const double len = ab.norm();
    const double t = len > 1e-12 ? std::clamp((p - line[i]).dot(ab) / (len * len), 0.0, 1.0) : 0.0;
    const Vector2d q = line[i] + t * ab;
    const double dist = (p - q).norm();
    if (dist < best.distance) {
      best.distance = dist;
      best.s = s0 + t * len;
      best.d = len > 1e-12 ? cross(ab / len, p - line[i]) : 0.0;
    }
    s0 += len;
  }
  return best;
}

// Direction of a lane at its end (or start) over the last (first) `length` metres.
Vector2d laneTangent(const std::vector<Vector3d>& c, bool at_end, double length) {
  const size_t n = c.size();
  const Vector2d p = (at_end ? c[n - 1] : c[0]).head<2>();
  Vector2d q = p;
  for (size_t k = 1; k < n; ++k) {
    q = (at_end ? c[n - 1 - k] : c[k]).head<2>();
    if ((q - p).norm() >= length) break;
  }
  return unit(at_end ? Vector2d(p - q) : Vector2d(q - p), Vector2d::UnitX());
}

// One lane where a road meets the intersection.
struct LaneEnd {
  int64_t lanelet = -1;
  Vector3d centre = Vector3d::Zero();  // end (incoming) or start (outgoing) of the centre line
  Vector2d tangent = Vector2d::UnitX();
  Vector3d left = Vector3d::Zero(), right = Vector3d::Zero();  // bound end points
  double lateral = 0.0;  // signed offset from the road polyline (left positive)
  bool pocket = false;
  double starts_at = 0.0;  // incoming: arc length where its lane starts on the road (chainStart)
  Movements moves;
};

struct Approach {
  const skeleton::AtomicRoad* road = nullptr;
  Vector2d tangent = Vector2d::UnitX();  // road direction at the intersection
  std::vector<LaneEnd> lanes;            // left to right
};

Vector3d boundEnd(const map::LaneMap& m, int64_t line_id, const Vector3d& near) {
  const map::LineString* l = m.line(line_id);
  if (!l || l->points.empty()) return near;
  const Vector3d& a = l->points.front();
  const Vector3d& b = l->points.back();
  return (a - near).head<2>().norm() <= (b - near).head<2>().norm() ? a : b;
}

class Builder {
 public:
  Builder(const skeleton::Skeleton& sk, const skeleton::Intersection& in,
          const std::map<int64_t, map::LaneMap>& roads, const IntersectionOptions& o,
          const std::vector<osm::Restriction>& restrictions, const std::vector<DrivenPassage>& passages, int64_t id_base)
      : sk_(sk), in_(in), roads_(roads), o_(o), restrictions_(restrictions), passages_(passages), next_id_(id_base + 1) {}

  IntersectionResult build() {
    result_.intersection_id = in_.id;
    const map::LaneMap* any = nullptr;
    for (int64_t rid : in_.incoming) {
      Approach a;
      if (approach(rid, true, &a, &any)) ins_.push_back(std::move(a));
    }
    for (int64_t rid : in_.outgoing) {
      Approach a;
      if (approach(rid, false, &a, &any)) outs_.push_back(std::move(a));
    }
    if (any) {
      result_.map.origin_lat = any->origin_lat;
      result_.map.origin_lon = any->origin_lon;
      result_.map.origin_alt = any->origin_alt;
    }
    for (const Approach& a : ins_) connectApproach(a);
    return std::move(result_);
  }

 private:
  // A road's direction at the intersection: over road_tangent_m past its ROI edge.
  Vector2d roadTangent(const skeleton::AtomicRoad& road, bool incoming) const {
    return skeleton::directionAtJunction(sk_, road, incoming, o_.road_tangent_m);
  }

  bool approach(int64_t road_id, bool incoming, Approach* out, const map::LaneMap** any) {
    const skeleton::AtomicRoad* road = sk_.road(road_id);
    const auto it = roads_.find(road_id);
    if (!road || it == roads_.end() || road->polyline.size() < 2) return false;
    const map::LaneMap& m = it->second;
    out->road = road;
    out->tangent = roadTangent(*road, incoming);
    std::set<int64_t> ids;
    std::set<int64_t> has_pred;
    for (const auto& ll : m.lanelets) ids.insert(ll.id);
    for (const auto& ll : m.lanelets) {
      for (int64_t s : ll.successors) has_pred.insert(s);
    }
    // Lane ends at this intersection: lanelets with no successor (incoming) or no predecessor
    // (outgoing) within end_tolerance_m of the road's end; when none is, those within
    // end_tolerance_m of the nearest one, if that is at most unseen_end_m away (the drive did not
    // see the road's first or last metres, e.g. right after a turn).
    std::vector<std::pair<const map::Lanelet*, Projection>> candidates;
    double nearest = std::numeric_limits<double>::infinity();  // distance of a lane end from the edge
    double first_lane = std::numeric_limits<double>::infinity();  // incoming: where its first lane starts
    for (const auto& ll : m.lanelets) {
      if (ll.kind != map::LaneletKind::kRoad || ll.centre.empty()) continue;
      if (ll.road_id >= 0 && ll.road_id != road_id) continue;
      if (incoming) first_lane = std::min(first_lane, project(road->polyline, ll.centre.front().head<2>()).s);
      if (ll.centre.size() < 2) continue;
      if (incoming) {
        const bool continues = std::any_of(ll.successors.begin(), ll.successors.end(),
                                           [&](int64_t s) { return ids.count(s) > 0; });
        if (continues) continue;
      } else if (has_pred.count(ll.id)) {
        continue;
      }
      const Projection pr = project(road->polyline, (incoming ? ll.centre.back() : ll.centre.front()).head<2>());
      candidates.emplace_back(&ll, pr);
      nearest = std::min(nearest, std::max(0.0, incoming ? road->s_end - pr.s : pr.s - road->s_begin));
    }
    const double reach =
        o_.end_tolerance_m + (nearest > o_.end_tolerance_m && nearest <= o_.unseen_end_m ? nearest : 0.0);
    for (const auto& [llp, pr] : candidates) {
      const map::Lanelet& ll = *llp;
      if (incoming ? pr.s < road->s_end - reach : pr.s > road->s_begin + reach) continue;
      const Vector3d c = incoming ? ll.centre.back() : ll.centre.front();
      LaneEnd e;
      e.lanelet = ll.id;
      e.centre = c;
      e.tangent = laneTangent(ll.centre, incoming, o_.lane_tangent_m);
      e.left = boundEnd(m, ll.left_id, c);
      e.right = boundEnd(m, ll.right_id, c);
      e.lateral = pr.d;
      if (incoming) e.starts_at = chainStart(m, ll, road);
      out->lanes.push_back(e);
    }
    if (out->lanes.empty()) return false;
    // A pocket opens beside the road's other lanes: it starts pocket_min_m after the first of its
    // road's lanes (those that end before the intersection too), not merely after the road's start:
    // a road first seen some way in, where a drive began, has its lanes start there, and none of
    // them is a pocket for it.
    if (incoming) {
      for (auto& e : out->lanes) e.pocket = e.starts_at > std::max(first_lane, road->s_begin) + o_.pocket_min_m;
    }
    std::stable_sort(out->lanes.begin(), out->lanes.end(),
                     [](const LaneEnd& a, const LaneEnd& b) { return a.lateral > b.lateral; });
    if (incoming) assignMovements(out);
    if (!*any) *any = &m;
    return true;
  }

  // Arc length where the lane of `ll` starts: back through predecessors that continue it (their
  // centre ends where this one's starts), not through a split.
  double chainStart(const map::LaneMap& m, const map::Lanelet& ll, const skeleton::AtomicRoad* road) const {
    const map::Lanelet* cur = &ll;
    for (size_t guard = 0; guard < m.lanelets.size(); ++guard) {
      const map::Lanelet* prev = nullptr;
      for (const auto& q : m.lanelets) {
        if (q.centre.empty() || &q == cur) continue;
        if (std::find(q.successors.begin(), q.successors.end(), cur->id) == q.successors.end()) continue;
        if ((q.centre.back() - cur->centre.front()).head<2>().norm() < 0.5) prev = &q;
      }
      if (!prev) break;
      cur = prev;
    }
    return project(road->polyline, cur->centre.front().head<2>()).s;
  }

  void assignMovements(Approach* a) const {
    auto& lanes = a->lanes;
    if (o_.use_turn_lanes) {
      const std::vector<Movements> tags = turnLanes(*a->road);
      if (!tags.empty()) {
        if (tags.size() == lanes.size()) {
          for (size_t i = 0; i < lanes.size(); ++i) lanes[i].moves = tags[i];
        } else {
          std::vector<size_t> regular;
          for (size_t i = 0; i < lanes.size(); ++i) {
            if (!lanes[i].pocket) regular.push_back(i);
          }
          if (tags.size() == regular.size()) {
            for (size_t j = 0; j < regular.size(); ++j) lanes[regular[j]].moves = tags[j];
          }
        }
      }
    }
    if (o_.pockets_are_turn_lanes && lanes.size() > 1) {
      for (size_t i = 0; i < lanes.size(); ++i) {
        LaneEnd& l = lanes[i];
        if (!l.pocket || l.moves.specified) continue;
        if (i == 0) l.moves.left = l.moves.specified = true;
        if (i + 1 == lanes.size()) l.moves.right = l.moves.specified = true;
      }
    }
  }

  static bool isUturn(const skeleton::AtomicRoad& a, const skeleton::AtomicRoad& d) {
    return d.id == a.reverse_id || (d.way_id == a.way_id && d.from == a.to && d.to == a.from &&
                                    d.osm_nodes.size() == a.osm_nodes.size() &&
                                    std::equal(d.osm_nodes.begin(), d.osm_nodes.end(), a.osm_nodes.rbegin()));
  }

  // The movement a restriction value names: kNone for no_entry/no_exit and unknown values.
  static TurnDirection restrictionMovement(const std::string& r, bool* uturn) {
    *uturn = r.find("u_turn") != std::string::npos;
    if (r.find("left_turn") != std::string::npos) return TurnDirection::kLeft;
    if (r.find("right_turn") != std::string::npos) return TurnDirection::kRight;
    if (r.find("straight_on") != std::string::npos) return TurnDirection::kStraight;
    return TurnDirection::kNone;
  }

  bool viaHere(int64_t node) const {
    return node == in_.id || std::find(in_.osm_nodes.begin(), in_.osm_nodes.end(), node) != in_.osm_nodes.end();
  }

  bool isWayOut(int64_t way) const {
    return std::any_of(in_.outgoing.begin(), in_.outgoing.end(), [&](int64_t rid) {
      const skeleton::AtomicRoad* r = sk_.road(rid);
      return r && r->way_id == way;
    });
  }

  // The ways out of here an `only_` restriction leads to: its to_way when a road out of here lies on
  // it. In a junction merged from several nodes (the crossing of dual carriageways) the way it
  // names may be a link between two of them: then the ways the `only_` restrictions from that link
  // lead to, in turn (up to three links). Empty: it leads to no way out that it names (a link with
  // no restriction of its own, from where several ways out may be reached).
  std::set<int64_t> onlyWaysOut(const osm::Restriction& r, int depth = 0) const {
    if (isWayOut(r.to_way)) return {r.to_way};
    std::set<int64_t> out;
    if (depth >= 3) return out;
    for (const auto& q : restrictions_) {
      if (q.from_way != r.to_way || !viaHere(q.via_node) || !q.mandatory()) continue;
      const std::set<int64_t> w = onlyWaysOut(q, depth + 1);
      if (w.empty()) return {};  // one link leads on unrestricted: anywhere from there
      out.insert(w.begin(), w.end());
    }
    return out;
  }

  // True when the OSM turn restrictions forbid a -> d. A restriction into a link inside a merged
  // junction: an `only_` one allows the ways out it leads to (onlyWaysOut; when it leads on
  // unrestricted it says nothing here), a `no_` one says nothing here (the link may be one way of
  // several to the same way out).
  bool restricted(const Approach& a, const Approach& d, TurnDirection movement, bool uturn) const {
    if (!o_.use_restrictions) return false;
    bool only_applies = false, only_ok = false;
    for (const auto& r : restrictions_) {
      if (r.from_way != a.road->way_id || !viaHere(r.via_node)) continue;
      const bool only = r.mandatory();
      if (!only && !r.prohibitive()) continue;
      if (!isWayOut(r.to_way)) {
        if (!only) continue;
        const std::set<int64_t> ways = onlyWaysOut(r);
        if (ways.empty()) continue;
        only_applies = true;
        only_ok |= ways.count(d.road->way_id) > 0;
        continue;
      }
      bool target = r.to_way == d.road->way_id;
      if (target) {
        // Several ways out on to_way (a way not split at the node, or the same way back): the
        // restriction's own movement says which.
        int on_way = 0;
        for (const Approach& o : outs_) on_way += o.road->way_id == r.to_way ? 1 : 0;
        bool r_uturn = false;
        const TurnDirection rm = restrictionMovement(r.restriction, &r_uturn);
        if (on_way > 1 && (r_uturn || rm != TurnDirection::kNone)) {
          target = r_uturn ? uturn : (!uturn && rm == movement);
        }
      }
      if (only) {
        only_applies = true;
        only_ok |= target;
      } else if (target) {
        return true;
      }
    }
    return only_applies && !only_ok;
  }

  void connectApproach(const Approach& a) {
    std::vector<int> connections(a.lanes.size(), 0);
    const Approach* straightest = nullptr;
    double best_dot = -2.0;
    for (const Approach& d : outs_) {
      const bool uturn = isUturn(*a.road, *d.road) ||
                         std::abs(headingChange(a.tangent, d.tangent)) > o_.uturn_min_deg * M_PI / 180.0;
      if (uturn && !o_.allow_u_turns) continue;
      const TurnDirection movement =
          uturn ? (o_.right_hand_traffic ? TurnDirection::kLeft : TurnDirection::kRight)
                : turnDirection(a.tangent, d.tangent, o_.straight_max_deg);
      if (restricted(a, d, movement, uturn)) continue;
      if (!uturn && a.tangent.dot(d.tangent) > best_dot) {
        best_dot = a.tangent.dot(d.tangent);
        straightest = &d;
      }
      std::vector<Movements> moves;
      for (const auto& l : a.lanes) moves.push_back(l.moves);
      std::vector<std::pair<int, int>> pairs;
      if (!uturn && movement == TurnDirection::kStraight) pairs = pairByOffset(a, d);
      if (pairs.empty()) pairs = pairLanes(moves, static_cast<int>(d.lanes.size()), movement, uturn, o_.right_hand_traffic);
      pairs = withDrivenPairs(a, d, std::move(pairs));
      for (const auto& [i, o] : pairs) {
        if (connect(a, i, d, o, movement, false)) ++connections[i];
      }
    }
    if (!o_.connect_orphan_lanes || !straightest) return;
    // A lane with no connection may be headed for a way out that this map does not have (a road
    // the drive never took): then it is not an orphan, and inventing a straight connection for it
    // would be wrong. It may be when the rules would let it make that road's movement (pairLanes:
    // the left edge lane or the lanes tagged left for a left turn, the right for a right turn, any
    // lane straight on); a lane that could not (the right lane of two where only a left turn is
    // unmapped) is an orphan.
    const int nin = static_cast<int>(a.lanes.size()), nout = static_cast<int>(straightest->lanes.size());
    std::vector<bool> may_leave(a.lanes.size(), false);
    std::vector<Movements> moves;
    for (const auto& l : a.lanes) moves.push_back(l.moves);
    for (int64_t rid : in_.outgoing) {
      const skeleton::AtomicRoad* r = sk_.road(rid);
      const bool mapped = std::any_of(outs_.begin(), outs_.end(), [&](const Approach& d) { return d.road->id == rid; });
      if (!r || mapped || r->polyline.size() < 2 || isUturn(*a.road, *r)) continue;
      Approach d;
      d.road = r;
      d.tangent = roadTangent(*r, false);
      if (std::abs(headingChange(a.tangent, d.tangent)) > o_.uturn_min_deg * M_PI / 180.0) continue;  // a U-turn
      const TurnDirection movement = turnDirection(a.tangent, d.tangent, o_.straight_max_deg);
      if (restricted(a, d, movement, false)) continue;
      // Its side of the straightest way out too: a way out that forks off to the left of it (within
      // straight_max_deg of the approach, so straight on) is a left turn for the lanes there.
      const double side = straightest->tangent.x() * d.tangent.y() - straightest->tangent.y() * d.tangent.x();
      const TurnDirection fork = side > 0.0 ? TurnDirection::kLeft : TurnDirection::kRight;
      for (const TurnDirection m : {movement, fork}) {
        for (const auto& [i, o] : pairLanes(moves, nin, m, false, o_.right_hand_traffic)) may_leave[i] = true;
      }
    }
    const TurnDirection movement = turnDirection(a.tangent, straightest->tangent, o_.straight_max_deg);
    for (int i = 0; i < nin; ++i) {
      if (connections[i] || may_leave[i]) continue;
      const int o = o_.right_hand_traffic ? std::min(i, nout - 1) : nout - 1 - std::min(nin - 1 - i, nout - 1);
      connect(a, i, *straightest, o, movement, true);
    }
  }

  // Straight on with fewer lanes mapped on one side than on the other (a lane the drive did not
  // find, or not yet): counted from the left, k -> k would join lanes that do not continue each
  // other. When no lane of `a` is tagged and both roads are one-way (or both two-way), each lane of
  // `a` pairs with the lane of `d` at its offset from the road's line (the roads' lines continue
  // each other straight on), within
  // offset_match_m and 1 m nearer than any other, in order; empty when the counts agree, nothing
  // pairs, a lane lies between two, or only some lanes of the road with fewer pair (a lane that
  // really ends or turns off there, the lines' offsets then half a lane apart: the rules then).
  std::vector<std::pair<int, int>> pairByOffset(const Approach& a, const Approach& d) const {
    std::vector<std::pair<int, int>> out;
    if (a.lanes.size() == d.lanes.size() || o_.offset_match_m <= 0.0) return out;
    // Offsets compare between two one-way roads or two two-way ones (d = 0 the divider on both).
    if ((a.road->reverse_id >= 0) != (d.road->reverse_id >= 0)) return out;
    for (const auto& l : a.lanes) {
      if (l.moves.specified || l.pocket) return out;
    }
    int next = 0;  // out lanes left of a pair's are taken
    for (int i = 0; i < static_cast<int>(a.lanes.size()); ++i) {
      const NearestTwo n = nearestTwo(next, static_cast<int>(d.lanes.size()),
                                      [&](int o) { return std::abs(d.lanes[o].lateral - a.lanes[i].lateral); });
      if (n.best < 0 || n.best_d > o_.offset_match_m) continue;
      // A lane between two (one lane becoming two: a lane added, not one unmapped): the rules say.
      if (n.second_d - n.best_d < 1.0) return {};
      out.emplace_back(i, n.best);
      next = n.best + 1;
    }
    if (out.size() < std::min(a.lanes.size(), d.lanes.size())) return {};
    return out;
  }

  // Adds the intersection lanelet from lane i of `a` to lane o of `d`; false (and listed in
  // not_built) when Lanelet2's loader would misread it (io::orientationProblem: a sharp connection
  // between overlapping lane ends), so that the map stays loadable.
  bool connect(const Approach& a, int i, const Approach& d, int o, TurnDirection movement, bool orphan) {
    const LaneEnd& from = a.lanes[i];
    const LaneEnd& to = d.lanes[o];
    const BezierConnection curve =
        bezierConnection(from.centre.head<2>(), from.tangent, to.centre.head<2>(), to.tangent, o_.curve);
    // The same construction as the bounds' (connectionPolyline), so the centre stays between them.
    std::vector<Vector2d> pts =
        connectionPolyline(from.centre.head<2>(), from.tangent, to.centre.head<2>(), to.tangent, o_.curve);
    ConnectorBounds bounds = connectorBounds(from.left.head<2>(), from.right.head<2>(), from.tangent,
                                             to.left.head<2>(), to.right.head<2>(), to.tangent, o_.curve, &pts);
    // Shaped by the car's paths from this road to that one, where it stays sound.
    int shaped_by = 0;
    if (const Displacement* raw = displacementFor(a, d)) {
      // (no bound tighter than the Bezier's own limit: Lanelet2's validator flags curvature 0.5)
      const double k_max = o_.curve.min_bound_radius_m > 0.0 ? 1.0 / o_.curve.min_bound_radius_m : INFINITY;
      for (const int passes : o_.passage.smoothing_passes) {  // the least smoothing that is sound
        const Displacement shift = raw->smoothed(passes);
        std::vector<Vector2d> c = shift.apply(pts, o_.passage.step_m);
        ConnectorBounds b{shift.apply(bounds.left, o_.passage.step_m), shift.apply(bounds.right, o_.passage.step_m)};
        if (!selfIntersects(c) && outlineIsSimple(b.left, b.right) && !centreLeavesOutline(c, b.left, b.right) &&
            maxCurvature(b.left) <= k_max && maxCurvature(b.right) <= k_max) {
          pts = std::move(c);
          bounds = std::move(b);
          shaped_by = raw->passages;
          break;
        }
      }
    }
    // Heights run linearly in arc length from the in-lane's end to the out-lane's start.
    const auto lift = [](const std::vector<Vector2d>& p, double z0, double z1) {
      std::vector<double> u(p.size(), 0.0);
      for (size_t k = 1; k < p.size(); ++k) u[k] = u[k - 1] + (p[k] - p[k - 1]).norm();
      const double total = std::max(1e-9, u.back());
      std::vector<Vector3d> out;
      for (size_t k = 0; k < p.size(); ++k) out.emplace_back(p[k].x(), p[k].y(), z0 + (z1 - z0) * u[k] / total);
      return out;
    };
    map::LineString left, right;
    left.type = right.type = map::LineType::kVirtual;
    left.points = lift(bounds.left, from.left.z(), to.left.z());
    right.points = lift(bounds.right, from.right.z(), to.right.z());
    map::Lanelet ll;
    ll.centre = lift(pts, from.centre.z(), to.centre.z());
    ll.centre.front() = from.centre;
    ll.centre.back() = to.centre;
    left.points.front() = from.left;
    left.points.back() = to.left;
    right.points.front() = from.right;
    right.points.back() = to.right;
    // Nor one whose centre line leaves its lanelet (lane ends that nearly overlap make it hook), nor
    // one a bound of which Lanelet2 would turn (around a tight corner, the inner lane ends
    // overlapping: the inner bound's end lies behind its start).
    if (!io::orientationProblem(ll, left, right).empty() || centreLeavesOutline(pts, bounds.left, bounds.right) ||
        io::boundTurnedOnLoad(left, right)) {
      result_.not_built.push_back({a.road->id, i, d.road->id, o});
      return false;
    }
    // Two connections side by side between lanes that share their border (toLaneMap) share
    // their border too: the bound of an earlier connection of this intersection with the same ends.
    const map::LineString* shared_left = connectorLineBetween(left.points);
    const map::LineString* shared_right = connectorLineBetween(right.points);
    // (Read with the shared bound, a short connection whose own bounds Lanelet2 reads as meant
    // only just can be misread: not built either.)
    if ((shared_left || shared_right) &&
        !io::orientationProblem(ll, shared_left ? *shared_left : left, shared_right ? *shared_right : right).empty()) {
      result_.not_built.push_back({a.road->id, i, d.road->id, o});
      return false;
    }
    left.id = shared_left ? shared_left->id : next_id_++;
    right.id = shared_right ? shared_right->id : next_id_++;
    const bool own_left = !shared_left, own_right = !shared_right;  // (the pointers die with the next push)
    ll.id = next_id_++;
    ll.kind = map::LaneletKind::kIntersection;
    ll.left_id = left.id;
    ll.right_id = right.id;
    ll.successors = {to.lanelet};
    ll.turn = turnDirection(from.tangent, to.tangent, o_.straight_max_deg);
    ll.intersection_id = in_.id;
    Connection c;
    c.lanelet_id = ll.id;
    c.in_road = a.road->id;
    c.out_road = d.road->id;
    c.in_lanelet = from.lanelet;
    c.out_lanelet = to.lanelet;
    c.in_index = i;
    c.out_index = o;
    c.movement = movement;
    c.turn = ll.turn;
    c.quadratic = curve.quadratic;
    c.orphan = orphan;
    c.passages = shaped_by;
    result_.connections.push_back(c);
    if (own_left) result_.map.lines.push_back(std::move(left));
    if (own_right) result_.map.lines.push_back(std::move(right));
    result_.map.lanelets.push_back(std::move(ll));
    return true;
  }

  // The bound of a connection built so far in this intersection that runs the way `pts` does: the
  // same ends, each within 5 cm (the writer's node merge distance), and its middle point (by arc
  // length) within 10 cm (lines closer are one border drawn twice: lanemap-check's
  // shared_borders), or nullptr. (Two bounds between the same ends differ where one connection was
  // shaped by a passage and the other kept its Bezier.) Valid until a line is added.
  const map::LineString* connectorLineBetween(const std::vector<Vector3d>& pts) const {
    if (pts.size() < 2) return nullptr;
    const auto middle = [](const std::vector<Vector3d>& p) {
      std::vector<Vector2d> q;
      for (const auto& v : p) q.push_back(v.head<2>());
      return resampleEvenly(q, 3)[1];
    };
    const Vector2d mid = middle(pts);
    for (const auto& line : result_.map.lines) {
      if (line.points.size() < 2) continue;
      if ((line.points.front().head<2>() - pts.front().head<2>()).norm() < 0.05 &&
          (line.points.back().head<2>() - pts.back().head<2>()).norm() < 0.05 && (middle(line.points) - mid).norm() < 0.1) {
        return &line;
      }
    }
    return nullptr;
  }

  // The lanes the car drove from road a to road d (driven_passage.h): per path of that road pair,
  // its nearest in-lane end and out-lane start, when it passes both within passage.max_offset_m
  // (drivenCentre) and each at most half as far as the next nearest, with its driven centre
  // between them. In the passages' fixed order.
  struct DrivenPair {
    int in = -1, out = -1;
    std::vector<Vector2d> centre;
  };
  const std::vector<DrivenPair>& drivenPairs(const Approach& a, const Approach& d) {
    const auto key = std::make_pair(a.road->id, d.road->id);
    if (auto it = driven_.find(key); it != driven_.end()) return it->second;
    std::vector<DrivenPair> found;
    // The lane end the path passes nearest, when it is clearly that one: at most half as far as the
    // next nearest (a car between two lanes, changing lanes there, says neither); else -1.
    const auto nearest = [](const std::vector<LaneEnd>& lanes, const std::vector<Vector2d>& path) {
      const NearestTwo n = nearestTwo(0, static_cast<int>(lanes.size()),
                                      [&](int k) { return project(path, lanes[k].centre.head<2>()).distance; });
      return n.best_d <= 0.5 * n.second_d ? n.best : -1;
    };
    for (const auto& p : passages_) {
      if (p.from_road != a.road->id || p.to_road != d.road->id || p.path.size() < 2) continue;
      const int i = nearest(a.lanes, p.path), o = nearest(d.lanes, p.path);
      if (i < 0 || o < 0) continue;
      auto centre = drivenCentre(p.path, a.lanes[i].centre.head<2>(), d.lanes[o].centre.head<2>(), o_.passage);
      if (centre) found.push_back({i, o, std::move(*centre)});
    }
    return driven_.emplace(key, std::move(found)).first->second;
  }

  // The displacement of the car's paths from road a to road d from the Bezier of the lanes they
  // drove, averaged; nullptr when no path of that road pair fits. Cached per road pair.
  const Displacement* displacementFor(const Approach& a, const Approach& d) {
    const auto key = std::make_pair(a.road->id, d.road->id);
    if (auto it = displacement_.find(key); it != displacement_.end()) return it->second ? &*it->second : nullptr;
    std::vector<Displacement> found;
    for (const auto& p : drivenPairs(a, d)) {
      const LaneEnd& from = a.lanes[p.in];
      const LaneEnd& to = d.lanes[p.out];
      const auto bezier = connectionPolyline(from.centre.head<2>(), from.tangent, to.centre.head<2>(), to.tangent, o_.curve);
      found.push_back(displacementBetween(p.centre, bezier, o_.passage));
    }
    return displacement_.emplace(key, meanDisplacement(found)).first->second ? &*displacement_.at(key) : nullptr;
  }

  // The rules' pairs of road a to road d corrected by the lanes the car drove (passage.pairs): the
  // rules align a movement's lanes on one side; where the car went from lane i to lane o and the
  // rules pair i with another lane, every pair shifts by that difference (the car showed how the
  // lanes line up), out of range dropped; where the rules pair no lane with i but another in lane
  // j with o (a road of two lanes into one of one: the rules chose j, the car came from i), every
  // pair's in lane shifts by i - j the same way; then each driven pair is one (its in lane's other
  // pairs dropped). Unchanged when nothing was driven.
  std::vector<std::pair<int, int>> withDrivenPairs(const Approach& a, const Approach& d, std::vector<std::pair<int, int>> pairs) {
    if (!o_.passage.pairs) return pairs;
    const auto& driven = drivenPairs(a, d);
    if (driven.empty()) return pairs;
    const int nout = static_cast<int>(d.lanes.size());
    const DrivenPair& first = driven.front();
    const auto rule = std::find_if(pairs.begin(), pairs.end(), [&](const auto& q) { return q.first == first.in; });
    if (rule != pairs.end() && rule->second != first.out) {
      const int shift = first.out - rule->second;
      std::vector<std::pair<int, int>> shifted;
      for (const auto& [i, o] : pairs) {
        if (o + shift >= 0 && o + shift < nout) shifted.emplace_back(i, o + shift);
      }
      pairs = std::move(shifted);
    } else if (rule == pairs.end() && o_.passage.shift_in_lanes) {
      const auto into = std::find_if(pairs.begin(), pairs.end(), [&](const auto& q) { return q.second == first.out; });
      if (into != pairs.end()) {
        const int shift = first.in - into->first;
        const int nin = static_cast<int>(a.lanes.size());
        std::vector<std::pair<int, int>> shifted;
        for (const auto& [i, o] : pairs) {
          if (i + shift >= 0 && i + shift < nin) shifted.emplace_back(i + shift, o);
        }
        pairs = std::move(shifted);
      }
    }
    for (const auto& p : driven) {
      pairs.erase(std::remove_if(pairs.begin(), pairs.end(), [&](const auto& q) { return q.first == p.in && q.second != p.out; }),
                  pairs.end());
      if (std::find(pairs.begin(), pairs.end(), std::make_pair(p.in, p.out)) == pairs.end()) pairs.emplace_back(p.in, p.out);
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  }

  const skeleton::Skeleton& sk_;
  const skeleton::Intersection& in_;
  const std::map<int64_t, map::LaneMap>& roads_;
  const IntersectionOptions& o_;
  const std::vector<osm::Restriction>& restrictions_;
  const std::vector<DrivenPassage>& passages_;
  std::map<std::pair<int64_t, int64_t>, std::vector<DrivenPair>> driven_;            // by (in road, out road)
  std::map<std::pair<int64_t, int64_t>, std::optional<Displacement>> displacement_;  // by (in road, out road)
  int64_t next_id_;
  std::vector<Approach> ins_, outs_;
  IntersectionResult result_;
};

}  // namespace

std::vector<std::pair<int, int>> pairLanes(const std::vector<Movements>& in_lanes, int n_out, TurnDirection movement,
                                           bool uturn, bool right_hand_traffic) {
  std::vector<std::pair<int, int>> out;
  const int nin = static_cast<int>(in_lanes.size()), nout = n_out;
  if (nin == 0 || nout <= 0) return out;
  bool any_specified = false;
  for (const auto& m : in_lanes) any_specified |= m.specified;
  std::vector<int> cand;
  const auto alignLeft = [&] {
    for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) out.emplace_back(cand[j], j);
  };
  const auto alignRight = [&] {
    for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) {
      out.emplace_back(cand[cand.size() - 1 - j], nout - 1 - j);
    }
  };
  if (uturn) {
    for (int i = 0; i < nin; ++i) {
      if (in_lanes[i].reverse) cand.push_back(i);
    }
    if (cand.empty()) cand.push_back(right_hand_traffic ? 0 : nin - 1);
    cand.resize(1);
    right_hand_traffic ? alignLeft() : alignRight();
    return out;
  }
  if (movement == TurnDirection::kStraight) {
    for (int i = 0; i < nin; ++i) {
      const auto& m = in_lanes[i];
      if (!m.specified || m.straight) cand.push_back(i);
    }
    right_hand_traffic ? alignLeft() : alignRight();
    return out;
  }
  const bool left = movement == TurnDirection::kLeft;
  for (int i = 0; i < nin; ++i) {
    const auto& m = in_lanes[i];
    if (m.specified && (left ? m.left : m.right)) cand.push_back(i);
  }
  if (cand.empty()) {
    const int edge = left ? 0 : nin - 1;
    // Tagged lanes with no such movement: only an untagged edge lane may turn.
    if (any_specified && in_lanes[edge].specified) return out;
    cand.push_back(edge);
  }
  left ? alignLeft() : alignRight();
  return out;
}

std::vector<Movements> turnLanes(const skeleton::AtomicRoad& road) {
  std::string key = "turn:lanes";
  if (road.reverse_id >= 0) key = road.along_way ? "turn:lanes:forward" : "turn:lanes:backward";
  const auto it = road.tags.find(key);
  std::vector<Movements> out;
  if (it == road.tags.end() || it->second.empty()) return out;
  for (const auto& entry : osm::splitTurnLanes(it->second)) out.push_back(osm::parseTurnLane(entry));
  return out;
}

IntersectionOptions IntersectionOptions::fromYaml(const YAML::Node& node) {
  try {
    const config::YamlReader r(node);
    IntersectionOptions o = fromYaml(r);
    r.finish();
    return o;
  } catch (const config::ConfigError& e) {
    throw IntersectionsError(e.what());
  }
}

IntersectionOptions IntersectionOptions::fromYaml(const config::YamlReader& r) {
  IntersectionOptions o;
  r.read("right_hand_traffic", o.right_hand_traffic);
  r.read("allow_u_turns", o.allow_u_turns);
  r.read("use_turn_lanes", o.use_turn_lanes);
  r.read("use_restrictions", o.use_restrictions);
  r.read("pockets_are_turn_lanes", o.pockets_are_turn_lanes);
  r.read("connect_orphan_lanes", o.connect_orphan_lanes);
  r.read("straight_max_deg", o.straight_max_deg);
  r.read("offset_match_m", o.offset_match_m);
  r.read("uturn_min_deg", o.uturn_min_deg);
  r.read("end_tolerance_m", o.end_tolerance_m);
  r.read("unseen_end_m", o.unseen_end_m);
  r.read("lane_tangent_m", o.lane_tangent_m);
  r.read("road_tangent_m", o.road_tangent_m);
  r.read("pocket_min_m", o.pocket_min_m);
  r.read("parallel_deg", o.curve.parallel_deg);
  r.read("min_control_fraction", o.curve.min_control_fraction);
  r.read("max_control_fraction", o.curve.max_control_fraction);
  r.read("cubic_handle_fraction", o.curve.cubic_handle_fraction);
  r.read("step_m", o.curve.step_m);
  r.read("min_bound_radius_m", o.curve.min_bound_radius_m);
  r.read("passage_max_offset_m", o.passage.max_offset_m);
  r.read("passage_pairs", o.passage.pairs);
  r.read("passage_shift_in_lanes", o.passage.shift_in_lanes);
  r.read("id_base", o.id_base);
  try {
    o.validate();
  } catch (const IntersectionsError& e) {
    r.failHere(e.what());
  }
  return o;
}

void IntersectionOptions::validate() const {
  const auto check = [](bool ok, const char* what) {
    if (!ok) throw IntersectionsError(std::string("intersections options: ") + what);
  };
  check(straight_max_deg > 0.0 && straight_max_deg < 90.0, "straight_max_deg must be in (0, 90)");
  check(end_tolerance_m >= 0.0, "end_tolerance_m must be >= 0");
  check(unseen_end_m >= 0.0, "unseen_end_m must be >= 0");
  check(offset_match_m >= 0.0, "offset_match_m must be >= 0");
  check(lane_tangent_m > 0.0, "lane_tangent_m must be > 0");
  check(road_tangent_m > 0.0, "road_tangent_m must be > 0");
  check(pocket_min_m >= 0.0, "pocket_min_m must be >= 0");
  check(curve.parallel_deg >= 0.0 && curve.parallel_deg < 90.0, "parallel_deg must be in [0, 90)");
  check(curve.min_control_fraction >= 0.0 && curve.max_control_fraction > curve.min_control_fraction,
        "need 0 <= min_control_fraction < max_control_fraction");
  check(curve.cubic_handle_fraction > 0.0 && curve.cubic_handle_fraction <= 1.0, "cubic_handle_fraction must be in (0, 1]");
  check(curve.step_m > 0.0, "step_m must be > 0");
  check(curve.min_bound_radius_m >= 0.0, "min_bound_radius_m must be >= 0");
  check(id_base >= 0, "id_base must be >= 0");
  check(passage.max_offset_m >= 0.0, "passage_max_offset_m must be >= 0");
  check(passage.samples >= 2, "passage samples must be >= 2");
  check(std::all_of(passage.smoothing_passes.begin(), passage.smoothing_passes.end(), [](int n) { return n >= 0; }) &&
            passage.step_m > 0.0,
        "passage smoothing_passes >= 0 and step_m > 0");
}

IntersectionResult buildIntersection(const skeleton::Skeleton& skeleton, int64_t intersection_id,
                                     const std::map<int64_t, map::LaneMap>& roads,
                                     const IntersectionOptions& options,
                                     const std::vector<osm::Restriction>& restrictions,
                                     const std::vector<DrivenPassage>& passages) {
  options.validate();
  const auto& all = skeleton.intersections();
  const auto it = std::find_if(all.begin(), all.end(), [&](const auto& in) { return in.id == intersection_id; });
  if (it == all.end()) throw IntersectionsError("unknown intersection id " + std::to_string(intersection_id));
  const int64_t base = options.id_base > 0 ? options.id_base : kIdBase + 100000 * static_cast<int64_t>(it - all.begin());
  return Builder(skeleton, *it, roads, options, restrictions, passages, base).build();
}

std::optional<IntersectionResult> buildJoinedIntersection(const skeleton::Skeleton& skeleton, size_t index,
                                                          const std::map<int64_t, map::LaneMap>& roads,
                                                          const IntersectionOptions& options,
                                                          const std::vector<osm::Restriction>& restrictions,
                                                          const std::vector<DrivenPassage>& passages) {
  const auto& in = skeleton.intersections().at(index);
  const auto known = [&](const std::vector<int64_t>& ids) {
    return std::any_of(ids.begin(), ids.end(), [&](int64_t id) { return roads.count(id) > 0; });
  };
  if (!known(in.incoming) || !known(in.outgoing)) return std::nullopt;
  IntersectionOptions o = options;
  o.id_base = 0;  // per intersection
  IntersectionResult r = buildIntersection(skeleton, in.id, roads, o, restrictions, passages);
  if (r.connections.empty()) return std::nullopt;
  return r;
}

std::vector<IntersectionResult> buildIntersections(const skeleton::Skeleton& skeleton,
                                                   const std::map<int64_t, map::LaneMap>& roads,
                                                   const IntersectionOptions& options,
                                                   const std::vector<osm::Restriction>& restrictions,
                                                   std::vector<std::string>* failures) {
  std::vector<IntersectionResult> out;
  for (size_t i = 0; i < skeleton.intersections().size(); ++i) {
    try {
      if (auto r = buildJoinedIntersection(skeleton, i, roads, options, restrictions)) out.push_back(std::move(*r));
    } catch (const std::exception& e) {
      if (failures) failures->push_back("intersection " + std::to_string(skeleton.intersections()[i].id) + ": " + e.what());
    }
  }
  return out;
}

namespace {

// Drops these lanelets and lines from `whole`, and every successor link to those lanelets.
void removeLaneletsAndLines(map::LaneMap& whole, const std::set<int64_t>& lanelets, const std::set<int64_t>& lines) {
  whole.lanelets.erase(std::remove_if(whole.lanelets.begin(), whole.lanelets.end(),
                                      [&](const map::Lanelet& ll) { return lanelets.count(ll.id) > 0; }),
                       whole.lanelets.end());
  whole.lines.erase(std::remove_if(whole.lines.begin(), whole.lines.end(),
                                   [&](const map::LineString& l) { return lines.count(l.id) > 0; }),
                    whole.lines.end());
  for (auto& ll : whole.lanelets) {
    ll.successors.erase(std::remove_if(ll.successors.begin(), ll.successors.end(),
                                       [&](int64_t s) { return lanelets.count(s) > 0; }),
                        ll.successors.end());
  }
}

}  // namespace

void appendIntersection(map::LaneMap& whole, const IntersectionResult& result) {
  std::set<int64_t> old_lanelets, old_lines;
  for (const auto& ll : whole.lanelets) {
    if (ll.kind == map::LaneletKind::kIntersection && ll.intersection_id == result.intersection_id) {
      old_lanelets.insert(ll.id);
      old_lines.insert(ll.left_id);
      old_lines.insert(ll.right_id);
    }
  }
  for (const auto& ll : result.map.lanelets) old_lanelets.insert(ll.id);
  for (const auto& l : result.map.lines) old_lines.insert(l.id);
  removeLaneletsAndLines(whole, old_lanelets, old_lines);
  whole.lines.insert(whole.lines.end(), result.map.lines.begin(), result.map.lines.end());
  whole.lanelets.insert(whole.lanelets.end(), result.map.lanelets.begin(), result.map.lanelets.end());
  for (const auto& c : result.connections) {
    for (auto& ll : whole.lanelets) {
      if (ll.id == c.in_lanelet) {
        if (std::find(ll.successors.begin(), ll.successors.end(), c.lanelet_id) == ll.successors.end()) {
          ll.successors.push_back(c.lanelet_id);
        }
        break;
      }
    }
  }
}

void appendIntersections(map::LaneMap& whole, const std::vector<const IntersectionResult*>& results) {
  // One pass is appendIntersection in order when no fragment shares an id with another (each
  // has its own id base) and `whole` holds no fragment of these intersections yet; else in order.
  std::set<int64_t> intersection_ids, fragment_lanelets, fragment_lines;
  bool disjoint = true;
  for (const auto* r : results) {
    disjoint &= intersection_ids.insert(r->intersection_id).second;
    for (const auto& ll : r->map.lanelets) disjoint &= fragment_lanelets.insert(ll.id).second;
    for (const auto& l : r->map.lines) disjoint &= fragment_lines.insert(l.id).second;
  }
  for (const auto& ll : whole.lanelets) {
    disjoint &= !(ll.kind == map::LaneletKind::kIntersection && intersection_ids.count(ll.intersection_id));
  }
  if (!disjoint) {
    for (const auto* r : results) appendIntersection(whole, *r);
    return;
  }
  removeLaneletsAndLines(whole, fragment_lanelets, fragment_lines);
  for (const auto* r : results) {
    whole.lines.insert(whole.lines.end(), r->map.lines.begin(), r->map.lines.end());
    whole.lanelets.insert(whole.lanelets.end(), r->map.lanelets.begin(), r->map.lanelets.end());
  }
  std::unordered_map<int64_t, size_t> first_of;  // lanelet id -> its first index
  for (size_t i = 0; i < whole.lanelets.size(); ++i) first_of.emplace(whole.lanelets[i].id, i);
  for (const auto* r : results) {
    for (const auto& c : r->connections) {
      const auto it = first_of.find(c.in_lanelet);
      if (it == first_of.end()) continue;
      auto& successors = whole.lanelets[it->second].successors;
      if (std::find(successors.begin(), successors.end(), c.lanelet_id) == successors.end()) successors.push_back(c.lanelet_id);
    }
  }
}

std::map<int64_t, map::LaneMap> roadsOf(const map::LaneMap& whole) {
  std::map<int64_t, map::LaneMap> out;
  std::map<int64_t, const map::LineString*> lines;
  for (const auto& l : whole.lines) lines[l.id] = &l;
  for (const auto& ll : whole.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad || ll.road_id < 0) continue;
    auto [it, fresh] = out.try_emplace(ll.road_id);
    map::LaneMap& m = it->second;
    if (fresh) {
      m.origin_lat = whole.origin_lat;
      m.origin_lon = whole.origin_lon;
      m.origin_alt = whole.origin_alt;
    }
    m.lanelets.push_back(ll);
    for (int64_t id : {ll.left_id, ll.right_id, ll.stop_line_id.value_or(-1)}) {
      const auto l = lines.find(id);
      if (l == lines.end()) continue;
      if (std::none_of(m.lines.begin(), m.lines.end(), [&](const auto& x) { return x.id == id; })) {
        m.lines.push_back(*l->second);
      }
    }
  }
  return out;
}

}  // namespace lanemap::intersections
