// Tests of tracking::RoadTracker with synthetic drives: along routes of atomic roads of the
// west-oakland skeleton (100 Hz and 1 Hz poses, white and slowly varying +-3 m GNSS noise) the
// event sequence must equal the true one and every "reached intersection" must fire within 5 m of
// the true ROI entry; plus wrong way, leaving the map, pose dropouts, parallel roads without
// flicker, a rematch, and out-of-order poses on small synthetic networks.
#include "core/tracking/road_tracker.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <sstream>

using Eigen::Vector2d;
using lanemap::skeleton::AtomicRoad;
using lanemap::skeleton::Skeleton;
using lanemap::tracking::PoseInput;
using lanemap::tracking::RoadEvent;
using lanemap::tracking::RoadEventType;
using lanemap::tracking::RoadTracker;

namespace {

const Skeleton& westOakland() {
  static const Skeleton s = Skeleton::build(lanemap::osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  return s;
}

// A path the car drives: a polyline with arc lengths.
struct Path {
  std::vector<Vector2d> pts;
  std::vector<double> cum;
  void add(const Vector2d& p) {
    if (!pts.empty() && (p - pts.back()).norm() < 1e-9) return;
    cum.push_back(pts.empty() ? 0.0 : cum.back() + (p - pts.back()).norm());
    pts.push_back(p);
  }
  double length() const { return cum.back(); }
  // Point and heading at arc length s.
  std::pair<Vector2d, double> at(double s) const {
    s = std::clamp(s, 0.0, length());
    size_t i = std::upper_bound(cum.begin(), cum.end(), s) - cum.begin();
    i = std::clamp<size_t>(i, 1, pts.size() - 1);
    const Vector2d d = pts[i] - pts[i - 1];
    const double t = d.norm() > 0 ? (s - cum[i - 1]) / d.norm() : 0.0;
    return {pts[i - 1] + t * d, std::atan2(d.y(), d.x())};
  }
};

// The true route: roads in order, and where each starts on the path.
struct Route {
  std::vector<int64_t> roads;
  std::vector<double> offset;  // path arc length of each road's polyline start
  Path path;
  double s_start = 0, s_stop = 0;  // the drive: from mid first road to mid last road
};

Route makeRoute(const Skeleton& sk, const std::vector<int64_t>& roads) {
  Route r;
  r.roads = roads;
  for (int64_t id : roads) {
    const AtomicRoad& road = *sk.road(id);
    r.offset.push_back(r.path.pts.empty() ? 0.0 : r.path.length() + (road.polyline.front() - r.path.pts.back()).norm());
    for (const auto& p : road.polyline) r.path.add(p);
  }
  const AtomicRoad& first = *sk.road(roads.front());
  const AtomicRoad& last = *sk.road(roads.back());
  r.s_start = r.offset.front() + 0.5 * (first.s_begin + first.s_end);
  r.s_stop = r.offset.back() + 0.5 * (last.s_begin + last.s_end);
  return r;
}

// A random route without u-turns, sharp reversals or dead ends, starting and ending on a road with
// 30 m between its ROIs.
std::vector<int64_t> randomRoute(const Skeleton& sk, uint32_t seed, size_t n) {
  std::mt19937 rng(seed);
  std::vector<int64_t> starts;
  for (const auto& r : sk.roads()) {
    if (r.s_end - r.s_begin > 30.0 && !sk.intersection(r.to)->dead_end && r.from != r.to) starts.push_back(r.id);
  }
  std::vector<int64_t> route{starts[rng() % starts.size()]};
  while (route.size() < n) {
    const AtomicRoad& cur = *sk.road(route.back());
    std::vector<int64_t> next;
    for (int64_t id : sk.intersection(cur.to)->outgoing) {
      const AtomicRoad& o = *sk.road(id);
      if (id == cur.reverse_id || o.from == o.to || sk.intersection(o.to)->dead_end) continue;
      // The synthetic car turns on the spot at a node: no turns sharper than about 145 degrees
      // (a u-turn into a road parallel to the one it came on is no drive a car makes).
      if (sk.tangentAt(cur, cur.length).dot(sk.tangentAt(o, 0.0)) < -0.8) continue;
      next.push_back(id);
    }
    if (next.empty()) break;
    route.push_back(next[rng() % next.size()]);
  }
  // End on a road long enough that 1 Hz poses (10 m apart) see it.
  while (route.size() > 1 && sk.road(route.back())->s_end - sk.road(route.back())->s_begin < 30.0) {
    route.pop_back();
  }
  return route;
}

struct Noise {
  double white_sigma = 0.0;  // per axis, clipped at +-3 m
  double bias = 0.0;         // magnitude of a slowly rotating offset
  double heading_sigma = 0.0;
};

struct Drive {
  std::vector<RoadEvent> events;
  double t0 = 0;  // seconds
};

// Drives the route at `speed` with poses at `rate_hz`, feeding `tracker`.
Drive drive(const Route& route, RoadTracker& tracker, double speed, double rate_hz, const Noise& noise,
            uint32_t seed, double s_from = -1, double s_to = -1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Drive d;
  d.t0 = 1000.0;
  const double a = s_from < 0 ? route.s_start : s_from;
  const double b = s_to < 0 ? route.s_stop : s_to;
  const double phase = 0.7 * seed;
  for (int k = 0;; ++k) {
    const double t = k / rate_hz;
    const double s = a + speed * t;
    if (s > b) break;
    auto [p, h] = route.path.at(s);
    auto clip = [](double v) { return std::clamp(v, -3.0, 3.0); };
    p += Vector2d(clip(noise.white_sigma * n01(rng)), clip(noise.white_sigma * n01(rng)));
    p += noise.bias * Vector2d(std::cos(0.05 * t + phase), std::sin(0.05 * t + phase));
    PoseInput pose;
    pose.utime = static_cast<int64_t>(std::llround((d.t0 + t) * 1e6));
    pose.position = p;
    pose.heading = h + noise.heading_sigma * n01(rng);
    for (auto& e : tracker.update(pose)) d.events.push_back(e);
  }
  return d;
}

std::string describe(const std::vector<RoadEvent>& events) {
  std::ostringstream os;
  size_t n = 0;
  for (const auto& e : events) {
    if (++n > 30) {
      os << "... (" << events.size() << " events)";
      break;
    }
    os << lanemap::tracking::toString(e.type) << "(road " << e.road_id;
    if (e.intersection_id >= 0) os << ", I " << e.intersection_id;
    if (!e.detail.empty()) os << ", " << e.detail;
    os << ") ";
  }
  return os.str();
}

// A drive along `route` compared with the truth: whether the ENTERED / REACHED sequence equals the
// true one, and how far (m along the path) each "reached intersection" is from the true ROI entry.
struct RouteResult {
  bool sequence_ok = false;
  double worst_reached_m = 0.0;  // over the reached events that match the true sequence
  std::string message;
};

RouteResult checkRouteDrive(const Skeleton& sk, const Route& route, const Drive& d, double speed) {
  RouteResult res;
  std::vector<std::pair<RoadEventType, int64_t>> expected{{RoadEventType::kEnteredRoad, route.roads[0]}};
  for (size_t i = 0; i + 1 < route.roads.size(); ++i) {
    expected.push_back({RoadEventType::kReachedIntersection, route.roads[i]});
    expected.push_back({RoadEventType::kEnteredRoad, route.roads[i + 1]});
  }
  std::vector<std::pair<RoadEventType, int64_t>> got;
  for (const auto& e : d.events) got.push_back({e.type, e.road_id});
  res.sequence_ok = got == expected;
  std::ostringstream msg;
  msg << "events: " << describe(d.events) << "\ntrue route: ";
  for (int64_t id : route.roads) {
    const AtomicRoad& r = *sk.road(id);
    msg << id << " (" << r.from << " -> " << r.to << ", " << r.length << " m, ROI-free " << r.s_begin << ".."
        << r.s_end << ") ";
  }
  size_t i = 0;
  for (const auto& e : d.events) {
    if (e.type != RoadEventType::kReachedIntersection) continue;
    if (i + 1 >= route.roads.size()) break;
    const AtomicRoad& r = *sk.road(route.roads[i++]);
    if (e.road_id != r.id || e.intersection_id != r.to || e.crossing_utime > e.utime) {
      res.sequence_ok = false;
      break;
    }
    // The route's speed is constant: the path arc length at the event's crossing time.
    const double s_true = route.offset[i - 1] + r.s_end;
    const double s_event = route.s_start + speed * (e.crossing_utime * 1e-6 - d.t0);
    if (std::abs(s_event - s_true) > res.worst_reached_m) {
      res.worst_reached_m = std::abs(s_event - s_true);
      msg << "\nroad " << r.id << " reached at path s " << s_event << ", true ROI entry " << s_true;
    }
  }
  res.message = msg.str();
  return res;
}

// Synthetic networks in ENU metres (origin 43.73 N 7.42 E, spherical approximation).
class Net {
 public:
  void node(int64_t id, double x, double y) {
    data_.nodes[id] = {id, 43.73 + y / 111132.0, 7.42 + x / (111320.0 * std::cos(43.73 * M_PI / 180))};
  }
  void way(int64_t id, std::vector<int64_t> nodes, lanemap::osm::Tags tags = {}) {
    tags["highway"] = "residential";
    data_.ways.push_back({id, std::move(nodes), std::move(tags)});
  }
  Skeleton build() {
    data_.bounds = {43.72, 7.41, 43.74, 7.43};
    lanemap::skeleton::SkeletonOptions o;
    o.origin = lanemap::geo::LatLonAlt{43.73, 7.42, 0.0};
    return Skeleton::build(data_, o);
  }

 private:
  lanemap::osm::OsmData data_;
};

int64_t roadOnWay(const Skeleton& sk, int64_t way, bool along) {
  for (const auto& r : sk.roads()) {
    if (r.way_id == way && r.along_way == along) return r.id;
  }
  return -1;
}

size_t countType(const std::vector<RoadEvent>& ev, RoadEventType t) {
  return std::count_if(ev.begin(), ev.end(), [t](const RoadEvent& e) { return e.type == t; });
}

}  // namespace

// Drives `n_routes` random routes of up to 8 roads on `sk` in every noise case and prints, per
// case, the share of routes with the exact true event sequence and the worst reached-intersection
// error. Every route must match and every reached event be within `max_reached_m`, except
// `allowed_failures` routes per case (0 for west-oakland, see the Monaco test for why it has 1).
void checkRoutes(const Skeleton& sk, const char* map, uint32_t n_routes, int allowed_failures,
                 double max_reached_m) {
  struct Case {
    double rate;
    Noise noise;
    const char* name;
  };
  const Case cases[] = {
      {100.0, {1.5, 0.0, 0.03}, "100 Hz, white noise sigma 1.5 m clipped at 3 m"},
      {100.0, {0.3, 3.0, 0.03}, "100 Hz, 3 m slowly rotating bias + 0.3 m white"},
      {1.0, {1.5, 0.0, 0.03}, "1 Hz, white noise sigma 1.5 m clipped at 3 m"},
      {1.0, {0.3, 3.0, 0.03}, "1 Hz, 3 m slowly rotating bias + 0.3 m white"},
      {10.0, {0.0, 0.0, 0.0}, "10 Hz, no noise"},
  };
  const double speed = 10.0;
  std::vector<Route> routes;
  int roads = 0;
  for (uint32_t seed = 1; seed <= n_routes; ++seed) {
    Route route = makeRoute(sk, randomRoute(sk, seed, 8));
    if (route.roads.size() < 3) continue;
    roads += static_cast<int>(route.roads.size());
    routes.push_back(std::move(route));
  }
  EXPECT_GE(routes.size(), n_routes * 3 / 4);
  for (const Case& c : cases) {
    int failures = 0;
    double worst = 0.0;
    for (size_t k = 0; k < routes.size(); ++k) {
      RoadTracker tracker(sk);
      const uint32_t seed = static_cast<uint32_t>(k + 1);
      const RouteResult r = checkRouteDrive(sk, routes[k], drive(routes[k], tracker, speed, c.rate, c.noise, seed), speed);
      const bool ok = r.sequence_ok && r.worst_reached_m <= max_reached_m;
      if (r.sequence_ok) worst = std::max(worst, r.worst_reached_m);
      if (!ok) {
        ++failures;
        std::printf("[ mismatch ] %s, %s, route %zu: %s\n", map, c.name, k, r.message.c_str());
      }
    }
    std::printf("[ measured ] %s, %s: %zu/%zu routes (%d roads) exact, worst reached-intersection "
                "error %.2f m\n",
                map, c.name, routes.size() - failures, routes.size(), roads, worst);
    EXPECT_LE(failures, allowed_failures) << map << ", " << c.name;
  }
}

// The brief's requirement: exact sequences and every reached event within 5 m.
TEST(RoadTracker, RoutesOnWestOaklandAt100HzAnd1Hz) { checkRoutes(westOakland(), "west-oakland", 16, 0, 5.0); }

// Monaco is much harder (hairpins, forks at small angles, one-way loops of 15 m roads, overlapping
// ROIs, roads stacked in tunnels). Measured today: 15/15 routes exact without bias, 14/15 with the
// 3 m bias at 100 Hz and at 1 Hz (the same route: in a cluster of short one-way roads the biased
// position matches a neighbouring road; the tracker rematches a few metres later), reached events
// within 4.6 m. Budget: one route per case and 6 m, so a regression still fails.
TEST(RoadTracker, RoutesOnMonacoAt100HzAnd1Hz) {
  static const Skeleton monaco =
      Skeleton::build(lanemap::osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/monaco.osm.pbf"));
  checkRoutes(monaco, "monaco", 16, 1, 6.0);
}

TEST(RoadTracker, WrongWayOnOneWayRoad) {
  // A one-way street 1 -> 2 -> 3 crossed by two-way streets at 2 and 3.
  Net net;
  net.node(1, 0, 0);
  net.node(2, 200, 0);
  net.node(3, 400, 0);
  net.node(4, 200, -200);
  net.node(5, 200, 200);
  net.node(6, 400, -200);
  net.way(10, {1, 2, 3}, {{"oneway", "yes"}});
  net.way(11, {4, 2, 5});
  net.way(12, {6, 3});
  const Skeleton sk = net.build();
  const int64_t one_way_12 = roadOnWay(sk, 10, true);  // 1 -> 2
  const int64_t one_way_23 = sk.road(one_way_12 + 1)->from == 2 ? one_way_12 + 1 : -1;
  ASSERT_GE(one_way_23, 0);
  // Come up from 6 to 3 on the two-way street, turn left into the one-way street against it,
  // drive to 2 and on towards 1.
  Route route;
  route.path.add(Vector2d(400, -200));
  route.path.add(Vector2d(400, 0));
  route.path.add(Vector2d(0, 0));
  route.s_start = 50;
  route.s_stop = route.path.length() - 50;
  for (double rate : {100.0, 1.0}) {
    SCOPED_TRACE(rate);
    RoadTracker tracker(sk);
    const Drive d = drive(route, tracker, 10.0, rate, {1.0, 0.0, 0.02}, 3);
    // entered 6->3, reached 3, entered 3->2 (wrong way), wrong way, reached 2 (wrong way),
    // entered 2->1 (wrong way), wrong way.
    std::vector<std::pair<RoadEventType, int64_t>> got;
    for (const auto& e : d.events) got.push_back({e.type, e.road_id});
    const int64_t two_way_63 = roadOnWay(sk, 12, true);
    const std::vector<std::pair<RoadEventType, int64_t>> expected{
        {RoadEventType::kEnteredRoad, two_way_63},     {RoadEventType::kReachedIntersection, two_way_63},
        {RoadEventType::kEnteredRoad, one_way_23},     {RoadEventType::kWrongWay, one_way_23},
        {RoadEventType::kReachedIntersection, one_way_23}, {RoadEventType::kEnteredRoad, one_way_12},
        {RoadEventType::kWrongWay, one_way_12}};
    EXPECT_EQ(got, expected) << describe(d.events);
    for (const auto& e : d.events) {
      if (e.type == RoadEventType::kReachedIntersection && e.road_id == one_way_23) {
        EXPECT_EQ(e.intersection_id, 2);  // the one-way road's start, reached against it
        EXPECT_EQ(e.detail, "wrong way");
      }
    }
    EXPECT_TRUE(tracker.wrongWay());
  }
}

TEST(RoadTracker, LeavingTheMapAndComingBack) {
  Net net;
  net.node(1, 0, 0);
  net.node(2, 500, 0);
  net.way(10, {1, 2});
  const Skeleton sk = net.build();
  Route route;
  route.path.add(Vector2d(0, 0));
  route.path.add(Vector2d(200, 0));
  route.path.add(Vector2d(200, 150));  // off road, into a car park
  route.path.add(Vector2d(220, 150));
  route.path.add(Vector2d(220, 0));    // and back onto the road
  route.path.add(Vector2d(500, 0));   // into the dead end's ROI at 494 m
  route.s_start = 50;
  route.s_stop = route.path.length();
  for (double rate : {100.0, 1.0}) {
    SCOPED_TRACE(rate);
    RoadTracker tracker(sk);
    const Drive d = drive(route, tracker, 10.0, rate, {1.5, 0.0, 0.02}, 5);
    ASSERT_EQ(countType(d.events, RoadEventType::kLeftMap), 1u) << describe(d.events);
    ASSERT_EQ(d.events.size(), 4u) << describe(d.events);
    EXPECT_EQ(d.events[0].type, RoadEventType::kEnteredRoad);
    EXPECT_EQ(d.events[1].type, RoadEventType::kLeftMap);
    EXPECT_EQ(d.events[1].road_id, d.events[0].road_id);
    EXPECT_EQ(d.events[2].type, RoadEventType::kEnteredRoad);
    EXPECT_EQ(d.events[2].road_id, d.events[0].road_id);
    EXPECT_EQ(d.events[3].type, RoadEventType::kReachedIntersection);
    // Left when 25 m from the road for 1 s (the path leaves it at s = 200): car at y >= 25 + 10 m
    // at 10 m/s, within one pose interval (10 m at 1 Hz) plus 3 m of noise.
    const double t_left = d.events[1].utime * 1e-6 - d.t0;
    const double y_left = 10.0 * t_left + 50.0 - 200.0;
    EXPECT_GE(y_left, 25.0 + 10.0 - 3.0);
    EXPECT_LE(y_left, 25.0 + 10.0 + 10.0 + 3.0);
    EXPECT_EQ(tracker.state(), RoadTracker::State::kInIntersection);
  }
}

TEST(RoadTracker, PoseDropoutIsReported) {
  Net net;
  net.node(1, 0, 0);
  net.node(2, 600, 0);
  net.way(10, {1, 2});
  const Skeleton sk = net.build();
  RoadTracker tracker(sk);
  std::vector<RoadEvent> ev;
  auto feed = [&](double t, double x, bool valid) {
    PoseInput p;
    p.utime = static_cast<int64_t>(t * 1e6);
    p.position = Vector2d(x, 0.5);
    p.heading = 0.0;
    p.valid = valid;
    for (auto& e : tracker.update(p)) ev.push_back(e);
  };
  double t = 10.0;
  for (; t < 15.0; t += 0.01) feed(t, 50 + 10 * (t - 10), true);
  // 0.8 s of invalid poses: below pose_gap_s = 1 s, nothing.
  for (double u = t; u < t + 0.8; u += 0.01) feed(u, 0, false);
  t += 0.8;
  for (; t < 20.0; t += 0.01) feed(t, 50 + 10 * (t - 10), true);
  ASSERT_EQ(ev.size(), 1u) << describe(ev);
  // 2 s of invalid poses: POSE_LOST when the gap passes 1 s, at an invalid pose.
  const double lost_start = t;
  for (double u = t; u < t + 2.0; u += 0.01) feed(u, 0, false);
  t += 2.0;
  ASSERT_EQ(ev.size(), 2u) << describe(ev);
  EXPECT_EQ(ev[1].type, RoadEventType::kPoseLost);
  EXPECT_EQ(ev[1].road_id, ev[0].road_id);
  EXPECT_NEAR(ev[1].utime * 1e-6 - lost_start, 1.0, 0.02);
  EXPECT_EQ(tracker.state(), RoadTracker::State::kSearching);
  // Poses come back: the road is entered again (a new start, no previous road).
  for (; t < 25.0; t += 0.01) feed(t, 50 + 10 * (t - 10), true);
  // No pose at all for 3 s: POSE_LOST at the next pose, then entered again at once.
  t += 3.0;
  for (; t < 30.0; t += 0.01) feed(t, 50 + 10 * (t - 10), true);
  ASSERT_EQ(ev.size(), 5u) << describe(ev);
  EXPECT_EQ(ev[2].type, RoadEventType::kEnteredRoad);
  EXPECT_EQ(ev[2].previous_road_id, -1);
  EXPECT_EQ(ev[3].type, RoadEventType::kPoseLost);
  EXPECT_NE(ev[3].detail.find("3.0"), std::string::npos) << ev[3].detail;
  EXPECT_EQ(ev[4].type, RoadEventType::kEnteredRoad);
  EXPECT_EQ(ev[4].utime, ev[3].utime);
  EXPECT_GT(tracker.stats().invalid, 250);
}

TEST(RoadTracker, NoFlickerBetweenParallelRoadsAndRematch) {
  // Two parallel one-way roads in the same direction, 7 m apart (a main road and a frontage road).
  Net net;
  net.node(1, 0, 0);
  net.node(2, 1000, 0);
  net.node(3, 0, 7);
  net.node(4, 1000, 7);
  net.way(10, {1, 2}, {{"oneway", "yes"}});
  net.way(11, {3, 4}, {{"oneway", "yes"}});
  const Skeleton sk = net.build();
  const int64_t a = roadOnWay(sk, 10, true), b = roadOnWay(sk, 11, true);
  Route on_a;
  on_a.path.add(Vector2d(0, 0));
  on_a.path.add(Vector2d(1000, 0));
  for (double rate : {100.0, 1.0}) {
    // White noise (sigma 1.5 m, clipped at 3 m) plus a 1.5 m rotating bias: up to 4.5 m off.
    for (uint32_t seed = 1; seed <= 3; ++seed) {
      SCOPED_TRACE(std::to_string(rate) + " Hz seed " + std::to_string(seed));
      RoadTracker tracker(sk);
      const Drive d = drive(on_a, tracker, 12.0, rate, {1.5, 1.5, 0.03}, seed, 50, 950);
      ASSERT_EQ(d.events.size(), 1u) << describe(d.events);
      EXPECT_EQ(d.events[0].road_id, a);
      EXPECT_EQ(tracker.stats().rematches, 0);
    }
  }
  // The car really is on b after starting on a (it moved over): one rematch, after switch_time_s.
  Route change;
  change.path.add(Vector2d(0, 0));
  change.path.add(Vector2d(300, 0));
  change.path.add(Vector2d(310, 7));
  change.path.add(Vector2d(1000, 7));
  RoadTracker tracker(sk);
  const Drive d = drive(change, tracker, 10.0, 100.0, {0.5, 0.0, 0.02}, 9, 50, 900);
  ASSERT_EQ(d.events.size(), 2u) << describe(d.events);
  EXPECT_EQ(d.events[1].road_id, b);
  EXPECT_EQ(d.events[1].previous_road_id, a);
  EXPECT_EQ(d.events[1].detail, "rematched");
  const double x = 50 + 10.0 * (d.events[1].utime * 1e-6 - d.t0);
  EXPECT_GT(x, 305.0 + 10.0 * 1.0 - 5.0);  // not before switch_time_s of 1 s
  EXPECT_LT(x, 305.0 + 10.0 * 1.0 + 15.0);
}

TEST(RoadTracker, UTurnOnTwoWayRoadAndOutOfOrderPoses) {
  Net net;
  net.node(1, 0, 0);
  net.node(2, 600, 0);
  net.way(10, {1, 2});
  const Skeleton sk = net.build();
  Route route;
  route.path.add(Vector2d(100, 0));
  route.path.add(Vector2d(300, 0));
  route.path.add(Vector2d(300, 0.5));
  route.path.add(Vector2d(100, 0.5));
  route.s_start = 0;
  route.s_stop = route.path.length();
  RoadTracker tracker(sk);
  const Drive d = drive(route, tracker, 10.0, 100.0, {1.0, 0.0, 0.02}, 2);
  ASSERT_EQ(d.events.size(), 2u) << describe(d.events);
  EXPECT_EQ(d.events[0].road_id, roadOnWay(sk, 10, true));
  EXPECT_EQ(d.events[1].road_id, roadOnWay(sk, 10, false));
  EXPECT_EQ(d.events[1].detail, "u-turn");
  // A pose older than the last one is ignored.
  PoseInput old;
  old.utime = 1;
  old.position = Vector2d(50, 0);
  EXPECT_TRUE(tracker.update(old).empty());
  EXPECT_EQ(tracker.stats().out_of_order, 1);
}
