#include "core/sim/drive.h"

#include "core/config/yaml_reader.h"
#include "core/geo/polyline.h"
#include "core/intersections/curve.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <queue>
#include <set>
#include <sstream>
#include <unordered_map>

namespace lanemap::sim {
namespace {

using map::Lanelet;
using map::LaneletKind;
using map::LaneMap;

// Lanelet-level adjacency of the ground truth, built once per plan.
struct LaneGraph {
  const LaneMap& truth;
  std::unordered_map<int64_t, const Lanelet*> by_id;
  std::unordered_map<int64_t, std::vector<const Lanelet*>> by_road;  // road lanelets per atomic road

  explicit LaneGraph(const LaneMap& m) : truth(m) {
    for (const auto& l : m.lanelets) {
      by_id[l.id] = &l;
      if (l.kind == LaneletKind::kRoad && l.road_id >= 0) by_road[l.road_id].push_back(&l);
    }
  }
  const Lanelet* get(int64_t id) const {
    auto it = by_id.find(id);
    return it == by_id.end() ? nullptr : it->second;
  }
  // Road lanelets of road `to` reachable from a road lanelet of road `from`, directly or through
  // one intersection lanelet.
  bool connects(int64_t from, int64_t to) const {
    auto it = by_road.find(from);
    if (it == by_road.end()) return false;
    for (const Lanelet* a : it->second) {
      for (int64_t s1 : a->successors) {
        const Lanelet* b = get(s1);
        if (!b) continue;
        if (b->kind == LaneletKind::kRoad && b->road_id == to) return true;
        if (b->kind != LaneletKind::kIntersection) continue;
        for (int64_t s2 : b->successors) {
          const Lanelet* c = get(s2);
          if (c && c->kind == LaneletKind::kRoad && c->road_id == to) return true;
        }
      }
    }
    return false;
  }
};

// Point of a polyline at arc length s (clamped).
Eigen::Vector2d pointAt(const std::vector<Eigen::Vector3d>& pts, double s) {
  if (pts.empty()) return Eigen::Vector2d::Zero();
  if (s <= 0.0) return pts.front().head<2>();
  for (size_t i = 1; i < pts.size(); ++i) {
    const double seg = (pts[i] - pts[i - 1]).head<2>().norm();
    if (s <= seg && seg > 0.0) {
      return pts[i - 1].head<2>() + (s / seg) * (pts[i] - pts[i - 1]).head<2>();
    }
    s -= seg;
  }
  return pts.back().head<2>();
}

// Arc length of the point of a polyline closest to p.
double project(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector2d& p) {
  double best_d = 1e300, best_s = 0.0, acc = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) {
    const Eigen::Vector2d a = pts[i - 1].head<2>();
    const Eigen::Vector2d ab = pts[i].head<2>() - a;
    const double len2 = ab.squaredNorm();
    const double u = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const double d = (a + u * ab - p).squaredNorm();
    const double len = std::sqrt(len2);
    if (d < best_d) {
      best_d = d;
      best_s = acc + u * len;
    }
    acc += len;
  }
  return best_s;
}

// Atomic roads from I_from reachable as a road sequence ending at a road into I_to (BFS over
// roads, transitions allowed only where the ground-truth lanes connect).
std::vector<int64_t> roadsBetween(const skeleton::Skeleton& sk, const LaneGraph& g,
                                  int64_t prev_road, int64_t from, int64_t to) {
  std::map<int64_t, int64_t> parent;  // road -> previous road (-1 for a start road)
  std::queue<int64_t> q;
  const auto* start = sk.intersection(from);
  if (!start) return {};
  for (int64_t r : start->outgoing) {
    if (prev_road >= 0 && !g.connects(prev_road, r)) continue;
    if (!g.by_road.count(r)) continue;
    parent[r] = -1;
    q.push(r);
  }
  while (!q.empty()) {
    const int64_t r = q.front();
    q.pop();
    const auto* road = sk.road(r);
    if (road->to == to) {
      std::vector<int64_t> seq;
      for (int64_t x = r; x >= 0; x = parent[x]) seq.push_back(x);
      std::reverse(seq.begin(), seq.end());
      return seq;
    }
    const auto* inter = sk.intersection(road->to);
    if (!inter) continue;
    for (int64_t n : inter->outgoing) {
      if (parent.count(n) || !g.by_road.count(n) || !g.connects(r, n)) continue;
      parent[n] = r;
      q.push(n);
    }
  }
  return {};
}

// Neighbour lanelets of a road lanelet: same road, next lane left or right, running beside it.
std::vector<const Lanelet*> neighbours(const LaneGraph& g, const Lanelet& l) {
  std::vector<const Lanelet*> out;
  const Eigen::Vector2d mid = pointAt(l.centre, 0.5 * geo::polylineLengthXy(l.centre));
  for (const Lanelet* n : g.by_road.at(l.road_id)) {
    if (std::abs(n->index_from_left - l.index_from_left) != 1) continue;
    if ((pointAt(n->centre, project(n->centre, mid)) - mid).norm() > 5.0) continue;
    out.push_back(n);
  }
  return out;
}

// The lane a car turning round at the end of `l` drives on in: at a dead end of a two-way road, the
// reverse road's lane starting nearest l's end (within kUturnMaxWidthM); nullptr elsewhere.
constexpr double kUturnMaxWidthM = 15.0;
const Lanelet* uTurnLane(const skeleton::Skeleton& sk, const LaneGraph& g, const Lanelet& l) {
  const auto* road = sk.road(l.road_id);
  if (!road || road->reverse_id < 0 || l.kind != LaneletKind::kRoad) return nullptr;
  const auto* end = sk.intersection(road->to);
  const auto it = g.by_road.find(road->reverse_id);
  if (!end || !end->dead_end || it == g.by_road.end()) return nullptr;
  const Lanelet* best = nullptr;
  double best_d = kUturnMaxWidthM;
  for (const Lanelet* r : it->second) {
    const double d = (r->centre.front() - l.centre.back()).head<2>().norm();
    if (d < best_d) best_d = d, best = r;
  }
  return best;
}

// Auto drive: a seeded random walk over the lane graph, so that every turn it takes is one its lane
// allows. At a road lanelet long enough, it changes to a neighbour lane with
// lane_change_probability; at a road's end it takes one of its lane's successors, avoiding U-turns,
// dead ends and roads it has driven, where it can. When no such walk lasts the drive, walks that
// take a dead end where only dead ends go on (a fresh one first) and turn round at its end onto
// the reverse road (uTurnLane).
std::vector<LanePlan::Leg> autoLanes(const skeleton::Skeleton& sk, const LaneGraph& g,
                                     const DriveOptions& o, std::mt19937_64& rng) {
  const double wanted = o.cruise_speed_mps * o.duration_s * 1.2 + 50.0;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<const Lanelet*> starts;
  for (const auto& l : g.truth.lanelets) {
    if (l.kind != LaneletKind::kRoad || l.road_id < 0 || !sk.road(l.road_id)) continue;
    const auto* road = sk.road(l.road_id);
    const auto* end = sk.intersection(road->to);
    if (road->length > 40.0 && geo::polylineLengthXy(l.centre) > 20.0 && end && !end->dead_end) starts.push_back(&l);
  }
  if (starts.empty()) throw RouteError("no road lane of 20 m or more to start a drive on");
  std::vector<LanePlan::Leg> best;
  double best_len = -1.0;
  // Twenty walks that stop where only dead ends go on; if none lasts the drive (a small extract
  // whose roads end at its edges), twenty more that drive into a dead end and turn round there.
  const int attempts = o.turn_round_at_dead_ends ? 40 : 20;
  for (int attempt = 0; attempt < attempts && best_len < wanted; ++attempt) {
    const bool turn_round = attempt >= 20;
    std::vector<LanePlan::Leg> legs;
    std::map<int64_t, int> roads_used;
    const Lanelet* cur = starts[rng() % starts.size()];
    double len = 0.0;
    while (len < wanted && legs.size() < 2000) {
      len += geo::polylineLengthXy(cur->centre);
      roads_used[cur->road_id]++;
      if (cur->kind == LaneletKind::kRoad && geo::polylineLengthXy(cur->centre) >= 40.0 &&
          uniform(rng) < o.lane_change_probability) {
        const auto ns = neighbours(g, *cur);
        if (!ns.empty()) {
          legs.push_back({cur->id, true});
          cur = ns[rng() % ns.size()];
          len += geo::polylineLengthXy(cur->centre) * 0.5;
          roads_used[cur->road_id]++;
        }
      }
      legs.push_back({cur->id, false});
      // Candidate next lanelets (through an intersection lanelet when there is one).
      struct Option {
        const Lanelet* via;   // intersection lanelet or nullptr
        const Lanelet* next;  // the road lanelet after it
      };
      std::vector<Option> options, fresh, dead_ends, fresh_dead_ends;
      for (int64_t sid : cur->successors) {
        const Lanelet* n = g.get(sid);
        if (!n) continue;
        std::vector<Option> here;
        if (n->kind == LaneletKind::kRoad) {
          here.push_back({nullptr, n});
        } else {
          for (int64_t s2 : n->successors) {
            if (const Lanelet* m = g.get(s2); m && m->kind == LaneletKind::kRoad) here.push_back({n, m});
          }
        }
        for (const auto& opt : here) {
          const auto* road = sk.road(opt.next->road_id);
          const auto* cur_road = sk.road(cur->road_id);
          if (!road) continue;
          if (cur_road && opt.next->road_id == cur_road->reverse_id) continue;  // no U-turns
          const auto* end = sk.intersection(road->to);
          const bool is_fresh = opt.next->road_id == cur->road_id || !roads_used.count(opt.next->road_id);
          if (opt.next->road_id != cur->road_id && end && end->dead_end) {
            dead_ends.push_back(opt);
            if (is_fresh) fresh_dead_ends.push_back(opt);
            continue;
          }
          options.push_back(opt);
          if (is_fresh) fresh.push_back(opt);
        }
      }
      const auto& pick = !fresh.empty() ? fresh : !options.empty() ? options
                         : !turn_round ? options : !fresh_dead_ends.empty() ? fresh_dead_ends : dead_ends;
      if (pick.empty()) {
        // The lane ends with nothing after it: turn round at a dead end, else the drive ends here.
        const Lanelet* back = turn_round && cur->successors.empty() ? uTurnLane(sk, g, *cur) : nullptr;
        if (!back) break;
        legs.back().u_turn_to_next = true;
        len += 0.5 * M_PI * (back->centre.front() - cur->centre.back()).head<2>().norm();
        cur = back;
        continue;
      }
      const Option& chosen = pick[rng() % pick.size()];
      if (chosen.via) {
        legs.push_back({chosen.via->id, false});
        len += geo::polylineLengthXy(chosen.via->centre);
      }
      cur = chosen.next;
    }
    if (len > best_len) {
      best_len = len;
      best = legs;
    }
  }
  return best;
}

// Dijkstra over (lanelet, route stage): successor edges and lane changes to a neighbour lanelet of
// the same road. Seeded per-lanelet cost factors make the car pick varied lanes (and so change
// lanes now and then) when several are equally good.
std::vector<LanePlan::Leg> planLanes(const LaneGraph& g, const std::vector<int64_t>& roads,
                                     const DriveOptions& o, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> factor(1.0 - o.lane_change_probability,
                                                1.0 + o.lane_change_probability);
  std::unordered_map<int64_t, double> cost_factor;
  for (const auto& l : g.truth.lanelets) cost_factor[l.id] = factor(rng);
  const double lane_change_penalty = 8.0;
  const int last = static_cast<int>(roads.size()) - 1;

  using State = std::pair<int64_t, int>;  // lanelet, stage
  std::map<State, double> dist;
  std::map<State, std::pair<State, bool>> parent;  // -> (previous, was lane change)
  using Item = std::pair<double, State>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> pq;

  // Start: road lanelets of the first road that no lanelet of that road precedes.
  std::set<int64_t> has_pred;
  for (const Lanelet* l : g.by_road.at(roads[0])) {
    for (int64_t s : l->successors) has_pred.insert(s);
  }
  for (const Lanelet* l : g.by_road.at(roads[0])) {
    if (has_pred.count(l->id)) continue;
    dist[{l->id, 0}] = 0.0;
    pq.push({0.0, {l->id, 0}});
  }
  auto relax = [&](const State& from, const State& to, double w, bool lane_change) {
    const double d = dist[from] + w;
    auto it = dist.find(to);
    if (it == dist.end() || d < it->second) {
      dist[to] = d;
      parent[to] = {from, lane_change};
      pq.push({d, to});
    }
  };
  std::optional<State> goal;
  int furthest_stage = 0;
  while (!pq.empty()) {
    auto [d, st] = pq.top();
    pq.pop();
    if (d > dist[st]) continue;
    furthest_stage = std::max(furthest_stage, st.second);
    const Lanelet* l = g.get(st.first);
    const int stage = st.second;
    const double w = geo::polylineLengthXy(l->centre) * cost_factor[l->id];
    bool has_same_road_successor = false;
    for (int64_t sid : l->successors) {
      const Lanelet* n = g.get(sid);
      if (!n) continue;
      if (n->kind == LaneletKind::kRoad && n->road_id == roads[stage]) {
        has_same_road_successor = true;
        relax(st, {n->id, stage}, w, false);
      } else if (stage < last && n->kind == LaneletKind::kRoad && n->road_id == roads[stage + 1]) {
        relax(st, {n->id, stage + 1}, w, false);
      } else if (stage < last && n->kind == LaneletKind::kIntersection) {
        // An intersection lanelet belongs to the stage of the road it leads into.
        for (int64_t s2 : n->successors) {
          const Lanelet* m = g.get(s2);
          if (m && m->kind == LaneletKind::kRoad && m->road_id == roads[stage + 1]) {
            relax(st, {n->id, stage + 1}, w, false);
            break;
          }
        }
      }
    }
    if (l->kind == LaneletKind::kIntersection) continue;
    if (stage == last && !has_same_road_successor) {
      goal = st;
      break;
    }
    // Lane changes: neighbour lanes of the same road that run beside this one.
    if (geo::polylineLengthXy(l->centre) < 15.0) continue;  // too short to change lanes
    for (const Lanelet* n : neighbours(g, *l)) relax(st, {n->id, stage}, lane_change_penalty + 0.5 * w, true);
  }
  if (!goal) {
    std::ostringstream msg;
    msg << "no lane-level path follows the route through the ground-truth lanes: no lane of atomic road "
        << roads[furthest_stage];
    if (furthest_stage < last) {
      msg << " reaches atomic road " << roads[furthest_stage + 1];
    } else {
      msg << " reaches its end";
    }
    throw RouteError(msg.str());
  }
  // Walk back from the goal: each state, and whether the edge out of it was a lane change.
  std::vector<LanePlan::Leg> legs{{goal->first, false}};
  for (State s = *goal; parent.count(s);) {
    const auto& [prev, lane_change] = parent.at(s);
    legs.push_back({prev.first, lane_change});
    s = prev;
  }
  std::reverse(legs.begin(), legs.end());
  return legs;
}

}  // namespace

DriveOptions DriveOptions::fromYaml(const YAML::Node& n) {
  const config::YamlReader r(n);
  DriveOptions o = fromYaml(r);
  r.finish();
  return o;
}

DriveOptions DriveOptions::fromYaml(const config::YamlReader& r) {
  DriveOptions o;
  r.read("cruise_speed_mps", o.cruise_speed_mps);
  r.read("max_lateral_accel", o.max_lateral_accel);
  r.read("accel", o.accel);
  r.read("lane_change_length_m", o.lane_change_length_m);
  r.read("lane_change_probability", o.lane_change_probability);
  r.read("label_ahead_max_turn_deg", o.label_ahead_max_turn_deg);
  r.read("turn_round_at_dead_ends", o.turn_round_at_dead_ends);
  if (o.cruise_speed_mps <= 0 || o.accel <= 0 || o.max_lateral_accel <= 0 || o.lane_change_length_m <= 0 ||
      o.lane_change_probability < 0 || o.lane_change_probability >= 1 || o.label_ahead_max_turn_deg > 180) {
    r.failHere("speeds, accelerations and lengths must be > 0, lane_change_probability in [0, 1), "
               "label_ahead_max_turn_deg at most 180 (negative: never)");
  }
  return o;
}

LanePlan planDrive(const skeleton::Skeleton& sk, const map::LaneMap& truth, const DriveOptions& o) {
  LaneGraph g(truth);
  std::mt19937_64 rng(o.seed * 7919 + 17);
  LanePlan plan;
  if (o.route_nodes.empty()) {
    plan.legs = autoLanes(sk, g, o, rng);
    for (const auto& leg : plan.legs) {
      const int64_t r = g.get(leg.lanelet)->road_id;
      if (r >= 0 && (plan.roads.empty() || plan.roads.back() != r)) plan.roads.push_back(r);
    }
  } else {
    if (o.route_nodes.size() < 2) throw RouteError("a route needs at least two intersection ids");
    for (int64_t n : o.route_nodes) {
      if (!sk.intersection(n)) throw RouteError("route node " + std::to_string(n) + " is not an intersection of the map");
    }
    for (size_t i = 0; i + 1 < o.route_nodes.size(); ++i) {
      const int64_t prev = plan.roads.empty() ? -1 : plan.roads.back();
      auto seq = roadsBetween(sk, g, prev, o.route_nodes[i], o.route_nodes[i + 1]);
      if (seq.empty()) {
        std::ostringstream msg;
        msg << "no drivable route from intersection " << o.route_nodes[i] << " to " << o.route_nodes[i + 1];
        throw RouteError(msg.str());
      }
      plan.roads.insert(plan.roads.end(), seq.begin(), seq.end());
    }
  }
  if (plan.roads.empty()) throw RouteError("empty route");
  if (plan.legs.empty()) plan.legs = planLanes(g, plan.roads, o, rng);
  for (int64_t r : plan.roads) plan.intersections.push_back(sk.road(r)->to);
  return plan;
}

}  // namespace lanemap::sim

namespace lanemap::sim {
namespace {

double smoothstep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

}  // namespace

Trajectory::Trajectory(const map::LaneMap& truth, const World& world, const LanePlan& plan,
                       const DriveOptions& o)
    : world_(world) {
  LaneGraph g(truth);
  const double step = 0.5;
  std::vector<PathPoint> raw;
  double entry_s = 0.0;  // where the car enters the current leg's centre line
  for (size_t i = 0; i < plan.legs.size(); ++i) {
    const Lanelet* a = g.get(plan.legs[i].lanelet);
    if (!a || a->centre.size() < 2) throw RouteError("lanelet " + std::to_string(plan.legs[i].lanelet) + " has no centre line");
    const double len_a = geo::polylineLengthXy(a->centre);
    if (plan.legs[i].lane_change_to_next && i + 1 < plan.legs.size()) {
      const Lanelet* b = g.get(plan.legs[i + 1].lanelet);
      const double available = len_a - entry_s;
      const double lc_len = std::clamp(available - 4.0, 8.0, o.lane_change_length_m);
      const double start = entry_s + std::max(0.0, std::min(10.0, available - lc_len));
      for (double s = entry_s; s < start; s += step) raw.push_back({pointAt(a->centre, s), a->id, a->road_id});
      for (double u = 0.0; u < lc_len; u += step) {
        const Eigen::Vector2d pa = pointAt(a->centre, start + u);
        const Eigen::Vector2d pb = pointAt(b->centre, project(b->centre, pa));
        const double w = smoothstep(u / lc_len);
        raw.push_back({pa + w * (pb - pa), w < 0.5 ? a->id : b->id, a->road_id});
      }
      entry_s = project(b->centre, pointAt(a->centre, start + lc_len));
      continue;
    }
    for (double s = entry_s; s < len_a; s += step) raw.push_back({pointAt(a->centre, s), a->id, a->road_id});
    entry_s = 0.0;
    if (plan.legs[i].u_turn_to_next && i + 1 < plan.legs.size()) {
      // Turning round at a dead end: a cubic Bezier from a's end, heading on, to b's start, heading
      // back (control points 2/3 of the gap out: near a half circle across the road), on no lane.
      const Lanelet* b = g.get(plan.legs[i + 1].lanelet);
      if (!b || b->centre.size() < 2) throw RouteError("lanelet " + std::to_string(plan.legs[i + 1].lanelet) + " has no centre line");
      const Eigen::Vector2d p0 = pointAt(a->centre, len_a), p3 = pointAt(b->centre, 0.0);
      const Eigen::Vector2d ta = (p0 - pointAt(a->centre, len_a - 1.0)).normalized();
      const Eigen::Vector2d tb = (pointAt(b->centre, 1.0) - p3).normalized();
      const double k = 2.0 / 3.0 * (p3 - p0).norm();
      intersections::BezierConnection turn;
      turn.control = {p0, p0 + k * ta, p3 - k * tb, p3};
      const int n = std::max(4, static_cast<int>(std::ceil(0.5 * M_PI * (p3 - p0).norm() / step)));
      for (int j = 0; j < n; ++j) raw.push_back({turn.point(static_cast<double>(j) / n), -1, -1});
    }
  }
  if (raw.size() < 4) throw RouteError("the planned drive is too short");

  // Light smoothing (+-1.5 m moving average) removes kinks where lanelets meet.
  const int half = 3;
  path_.resize(raw.size());
  for (size_t i = 0; i < raw.size(); ++i) {
    Eigen::Vector2d acc = Eigen::Vector2d::Zero();
    int n = 0;
    for (int k = -half; k <= half; ++k) {
      const long j = static_cast<long>(i) + k;
      if (j < 0 || j >= static_cast<long>(raw.size())) continue;
      acc += raw[static_cast<size_t>(j)].p;
      ++n;
    }
    path_[i] = {acc / n, raw[i].lanelet, raw[i].road_id, raw[i].lanelet};
  }
  // Inside an intersection the labels follow the road lanelet the car drives into next, once the
  // car heads within label_ahead_max_turn_deg of that lane's direction at its start (never when
  // negative).
  const Lanelet* next_road = nullptr;
  for (size_t i = path_.size(); i-- > 0;) {
    const Lanelet* ll = g.get(path_[i].lanelet);
    if (ll && ll->kind == LaneletKind::kRoad) {
      next_road = ll;
      continue;
    }
    path_[i].label_lanelet = -1;
    if (!next_road || o.label_ahead_max_turn_deg < 0) continue;
    const Eigen::Vector2d lane_dir = pointAt(next_road->centre, 2.0) - pointAt(next_road->centre, 0.0);
    const Eigen::Vector2d car_dir = path_[std::min(i + 2, path_.size() - 1)].p - path_[i >= 2 ? i - 2 : 0].p;
    if (lane_dir.norm() < 1e-6 || car_dir.norm() < 1e-6) continue;
    const double turn = std::acos(std::clamp(lane_dir.normalized().dot(car_dir.normalized()), -1.0, 1.0));
    if (turn <= o.label_ahead_max_turn_deg * M_PI / 180.0) path_[i].label_lanelet = next_road->id;
  }
  s_.assign(path_.size(), 0.0);
  for (size_t i = 1; i < path_.size(); ++i) s_[i] = s_[i - 1] + (path_[i].p - path_[i - 1].p).norm();

  // Speed profile: cruise, slower where curvature demands, acceleration-limited both ways.
  const size_t n = path_.size();
  std::vector<double> v(n, o.cruise_speed_mps);
  for (size_t i = 2; i + 2 < n; ++i) {
    const Eigen::Vector2d d1 = path_[i].p - path_[i - 2].p, d2 = path_[i + 2].p - path_[i].p;
    const double ds = 0.5 * (d1.norm() + d2.norm());
    if (ds < 1e-6) continue;
    const double dphi = std::atan2(d1.x() * d2.y() - d1.y() * d2.x(), d1.dot(d2));
    const double curvature = std::abs(dphi) / ds;
    if (curvature > 1e-6) v[i] = std::min(v[i], std::sqrt(o.max_lateral_accel / curvature));
  }
  v[0] = std::min(v[0], 2.0);
  for (size_t i = 1; i < n; ++i) {
    const double ds = s_[i] - s_[i - 1];
    v[i] = std::min(v[i], std::sqrt(v[i - 1] * v[i - 1] + 2.0 * o.accel * ds));
  }
  for (size_t i = n - 1; i-- > 0;) {
    const double ds = s_[i + 1] - s_[i];
    v[i] = std::min(v[i], std::sqrt(v[i + 1] * v[i + 1] + 2.0 * o.accel * ds));
  }
  t_of_s_.assign(n, 0.0);
  for (size_t i = 1; i < n; ++i) {
    t_of_s_[i] = t_of_s_[i - 1] + 2.0 * (s_[i] - s_[i - 1]) / std::max(0.1, v[i - 1] + v[i]);
  }
  duration_ = std::min(o.duration_s, t_of_s_.back());
}

double Trajectory::arcLengthAt(double t) const {
  t = std::clamp(t, 0.0, t_of_s_.back());
  const auto it = std::upper_bound(t_of_s_.begin(), t_of_s_.end(), t);
  if (it == t_of_s_.begin()) return 0.0;
  if (it == t_of_s_.end()) return s_.back();
  const size_t i = static_cast<size_t>(it - t_of_s_.begin());
  const double u = (t - t_of_s_[i - 1]) / std::max(1e-9, t_of_s_[i] - t_of_s_[i - 1]);
  return s_[i - 1] + u * (s_[i] - s_[i - 1]);
}

Eigen::Isometry3d Trajectory::poseAt(double s) const {
  auto at2d = [this](double q) {
    q = std::clamp(q, 0.0, s_.back());
    const auto it = std::upper_bound(s_.begin(), s_.end(), q);
    if (it == s_.begin()) return path_.front().p;
    if (it == s_.end()) return path_.back().p;
    const size_t i = static_cast<size_t>(it - s_.begin());
    const double u = (q - s_[i - 1]) / std::max(1e-9, s_[i] - s_[i - 1]);
    return Eigen::Vector2d(path_[i - 1].p + u * (path_[i].p - path_[i - 1].p));
  };
  const Eigen::Vector2d p = at2d(s);
  Eigen::Vector2d dir = at2d(s + 1.0) - at2d(s - 1.0);
  if (dir.norm() < 1e-9) dir = Eigen::Vector2d::UnitX();
  dir.normalize();
  const Eigen::Vector2d left(-dir.y(), dir.x());
  const double yaw = std::atan2(dir.y(), dir.x());
  // The body rests on the ground: pitch from the heights under the axles (wheelbase 2.8 m),
  // roll from those under the wheels (track 1.6 m). Origin: rear axle centre on the ground.
  const double h = world_.height(p.x(), p.y());
  const Eigen::Vector2d front = p + 2.8 * dir;
  const double pitch = std::atan2(world_.height(front.x(), front.y()) - h, 2.8);  // nose up > 0
  const Eigen::Vector2d pl = p + 0.8 * left, pr = p - 0.8 * left;
  const double roll = std::atan2(world_.height(pl.x(), pl.y()) - world_.height(pr.x(), pr.y()), 1.6);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x(), p.y(), h);
  return T;
}

VehicleState Trajectory::at(double t) const {
  VehicleState st;
  st.t = t;
  const double s = arcLengthAt(t);
  st.vehicle_to_enu = poseAt(s);
  const double dt = 0.05;
  const double s1 = arcLengthAt(t + dt), s0 = arcLengthAt(t - dt);
  const double span = std::min(t + dt, t_of_s_.back()) - std::max(t - dt, 0.0);
  st.speed = span > 0 ? (s1 - s0) / span : 0.0;
  const Eigen::Vector3d x0 = poseAt(s0).linear().col(0), x1 = poseAt(s1).linear().col(0);
  const double dyaw = std::atan2(x0.x() * x1.y() - x0.y() * x1.x(), x0.head<2>().dot(x1.head<2>()));
  st.yaw_rate = span > 0 ? dyaw / span : 0.0;
  const auto it = std::upper_bound(s_.begin(), s_.end(), s);
  const size_t i = it == s_.begin() ? 0 : static_cast<size_t>(it - s_.begin()) - 1;
  st.lanelet = path_[i].lanelet;
  st.road_id = path_[i].road_id;
  st.label_lanelet = path_[i].label_lanelet;
  return st;
}

}  // namespace lanemap::sim
