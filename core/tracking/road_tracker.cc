// The road tracker's state machine (see road_tracker.h for the idea):
//
//   kSearching / kOffMap --(a road within acquire_distance_m with a matching heading)--> kOnRoad
//                        --(inside an intersection ROI)---------------------------------> kInIntersection
//   kOnRoad r  --(filtered s on r >= r.s_end)--> REACHED_INTERSECTION r.to --> kInIntersection
//              --(heading against a one-way r)--> WRONG_WAY (stays on r; reaching r.s_begin then
//                 closes r at r.from)
//              --(heading against a two-way r)--> ENTERED_ROAD of r's reverse ("u-turn")
//              --(another road better by switch_margin_m for switch_time_s)--> ENTERED_ROAD ("rematched")
//   kInIntersection I --(on an outgoing road o of I beyond o.s_begin, heading matching, and o
//                        clearly better than any other outgoing road that also fits: forks)--> ENTERED_ROAD o
//                     --(already past a short outgoing road o: 1 Hz poses)--> ENTERED o, REACHED o.to [, ENTERED o2]
//                     --(leaving against an incoming one-way road)--> ENTERED_ROAD + WRONG_WAY
//                     --(far outside I matching none of its roads)--> kSearching
//   any on-map state --(no road within left_map_distance_m for left_map_time_s)--> LEFT_MAP, kOffMap
//   any state --(no valid pose for pose_gap_s)--> POSE_LOST, kSearching
//
// Every pose may cause several transitions (1 Hz poses can cross a short road in one step); the
// state machine runs until it settles (at most a few transitions per pose).
#include "core/tracking/road_tracker.h"

#include "core/config/yaml_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace lanemap::tracking {

namespace {
constexpr double kSwitchCostHeadingWeight = skeleton::kHeadingWeightMPerRad;
constexpr double kPi = 3.14159265358979323846;

double cost(const skeleton::RoadMatch& m) {
  return m.distance + kSwitchCostHeadingWeight * std::abs(m.heading_error);
}
}  // namespace

const char* toString(RoadEventType type) {
  switch (type) {
    case RoadEventType::kEnteredRoad: return "entered_road";
    case RoadEventType::kReachedIntersection: return "reached_intersection";
    case RoadEventType::kLeftMap: return "left_map";
    case RoadEventType::kWrongWay: return "wrong_way";
    case RoadEventType::kPoseLost: return "pose_lost";
  }
  return "unknown";
}

// ---- filter ----------------------------------------------------------------------------------

void RoadTracker::Filter::reset(const Eigen::Vector2d& p, const std::optional<Eigen::Vector2d>& v) {
  x_ = Eigen::Vector2d(p.x(), v ? v->x() : 0.0);
  y_ = Eigen::Vector2d(p.y(), v ? v->y() : 0.0);
  px_ = py_ = Eigen::Vector2d(4.0, v ? 1.0 : 400.0).asDiagonal();
}

bool RoadTracker::Filter::update(const Eigen::Vector2d& z, double dt, double r, double q,
                                 double max_innovation) {
  Eigen::Matrix2d f;
  f << 1.0, dt, 0.0, 1.0;
  Eigen::Matrix2d qm;
  qm << dt * dt * dt * dt / 4, dt * dt * dt / 2, dt * dt * dt / 2, dt * dt;
  qm *= q * q;
  Eigen::Vector2d x = f * x_, y = f * y_;
  Eigen::Matrix2d px = f * px_ * f.transpose() + qm;
  Eigen::Matrix2d py = f * py_ * f.transpose() + qm;
  const Eigen::Vector2d innovation(z.x() - x(0), z.y() - y(0));
  if (innovation.norm() > max_innovation) return false;
  auto correct = [r](Eigen::Vector2d& s, Eigen::Matrix2d& p, double nu) {
    const double denom = p(0, 0) + r * r;
    const Eigen::Vector2d k = p.col(0) / denom;
    s += k * nu;
    const Eigen::Matrix2d pk = p;
    p -= k * pk.row(0);
  };
  correct(x, px, innovation.x());
  correct(y, py, innovation.y());
  x_ = x;
  y_ = y;
  px_ = px;
  py_ = py;
  return true;
}

// ---- tracker ---------------------------------------------------------------------------------

RoadTracker::RoadTracker(const skeleton::Skeleton& skeleton, RoadTrackerConfig config)
    : skeleton_(skeleton), config_(config), order_(config.time_jump_s, 3) {}

void RoadTracker::losePose(const PoseInput& pose, const std::string& detail, std::vector<RoadEvent>& events) {
  RoadEvent e = makeEvent(RoadEventType::kPoseLost, pose, road_ >= 0 ? road_ : last_road_);
  e.intersection_id = intersection_;
  e.detail = detail;
  events.push_back(e);
  state_ = State::kSearching;
  road_ = intersection_ = last_road_ = -1;
  wrong_way_ = false;
  filter_ready_ = false;
  have_prev_ = false;
  far_since_s_ = -1.0;
}

std::vector<RoadEvent> RoadTracker::update(const PoseInput& pose) {
  std::vector<RoadEvent> events;
  switch (order_.check(pose.utime)) {
    case geo::TimeOrder::Verdict::kInOrder:
      break;
    case geo::TimeOrder::Verdict::kDuplicate:
      ++stats_.duplicates;
      return events;
    case geo::TimeOrder::Verdict::kOutOfOrder:
      ++stats_.out_of_order;
      return events;
    case geo::TimeOrder::Verdict::kRestart: {
      // The time went back (a log restarted): the road being driven belongs to another time.
      ++stats_.time_jumps;
      char buf[64];
      std::snprintf(buf, sizeof buf, "time jumped back by %.1f s",
                    (static_cast<double>(last_utime_) - static_cast<double>(pose.utime)) * 1e-6);
      losePose(pose, buf, events);
      have_last_valid_ = false;
      lost_reported_ = false;
      exit_crossings_.clear();
      break;
    }
  }
  ++stats_.poses;
  last_utime_ = pose.utime;

  // Dropout: no valid pose for longer than pose_gap_s. The current road is abandoned (not closed).
  // (Differences in double: a hostile utime must not overflow int64.)
  const double since_valid_s = (static_cast<double>(pose.utime) - static_cast<double>(last_valid_utime_)) * 1e-6;
  if (have_last_valid_ && !lost_reported_ && since_valid_s > config_.pose_gap_s) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "no valid pose for %.2f s", since_valid_s);
    losePose(pose, buf, events);
    lost_reported_ = true;
  }
  if (!pose.valid || !pose.position.allFinite() || !std::isfinite(pose.heading)) {
    ++stats_.invalid;
    stats_.events += static_cast<int64_t>(events.size());
    return events;
  }
  have_last_valid_ = true;
  lost_reported_ = false;
  last_valid_utime_ = pose.utime;

  // Filter the position.
  const double r = config_.measurement_sigma_m;
  if (!filter_ready_) {
    filter_.reset(pose.position, pose.velocity);
    filter_ready_ = true;
  } else {
    const double dt = (static_cast<double>(pose.utime) - static_cast<double>(prev_utime_)) * 1e-6;
    if (!filter_.update(pose.position, dt, r, config_.acceleration_sigma, config_.max_innovation_m)) {
      filter_.reset(pose.position, pose.velocity);
      ++stats_.filter_resets;
      have_prev_ = false;  // no interpolation across a jump
    }
  }
  PoseInput filtered = pose;
  filtered.position = filter_.position();
  now_s_ = pose.utime * 1e-6;

  for (int i = 0; i < 6; ++i) {
    bool again = false;
    switch (state_) {
      case State::kSearching:
      case State::kOffMap: again = stepSearching(filtered, events); break;
      case State::kOnRoad: again = stepOnRoad(filtered, events); break;
      case State::kInIntersection: again = stepInIntersection(filtered, events); break;
    }
    if (!again) break;
  }
  prev_position_ = filtered.position;
  prev_utime_ = pose.utime;
  have_prev_ = true;
  stats_.events += static_cast<int64_t>(events.size());
  return events;
}

bool RoadTracker::checkLeftMap(const PoseInput& pose, double nearest_distance,
                               std::vector<RoadEvent>& events) {
  if (nearest_distance <= config_.left_map_distance_m) {
    far_since_s_ = -1.0;
    return false;
  }
  if (far_since_s_ < 0) far_since_s_ = now_s_;
  if (now_s_ - far_since_s_ < config_.left_map_time_s) return false;
  RoadEvent e = makeEvent(RoadEventType::kLeftMap, pose, road_ >= 0 ? road_ : last_road_);
  e.intersection_id = intersection_;
  char buf[80];
  std::snprintf(buf, sizeof buf, "no road within %.0f m for %.1f s", config_.left_map_distance_m,
                now_s_ - far_since_s_);
  e.detail = buf;
  e.distance_m = nearest_distance;
  events.push_back(e);
  state_ = State::kOffMap;
  road_ = intersection_ = last_road_ = -1;
  wrong_way_ = false;
  far_since_s_ = -1.0;
  return false;
}

bool RoadTracker::stepSearching(const PoseInput& pose, std::vector<RoadEvent>& events) {
  const double radius = std::max(config_.acquire_distance_m, config_.left_map_distance_m);
  const auto candidates = skeleton_.nearestRoads(pose.position, radius, pose.heading);
  if (const skeleton::Intersection* in = skeleton_.intersectionContaining(pose.position)) {
    state_ = State::kInIntersection;
    intersection_ = in->id;
    exit_crossings_.clear();
    road_ = -1;
    return true;
  }
  for (const auto& m : candidates) {
    if (m.distance > config_.acquire_distance_m) continue;
    const skeleton::AtomicRoad* road = skeleton_.road(m.road_id);
    if (std::abs(m.heading_error) <= config_.acquire_heading_rad) {
      enterRoad(m, pose, false, -1.0, state_ == State::kOffMap ? "back on the map" : "acquired", events);
      return true;
    }
    if (road->reverse_id < 0 && std::abs(m.heading_error) >= config_.wrong_way_heading_rad) {
      enterRoad(m, pose, true, -1.0, "acquired against the one-way direction", events);
      return true;
    }
  }
  return false;
}

bool RoadTracker::stepOnRoad(const PoseInput& pose, std::vector<RoadEvent>& events) {
  const skeleton::AtomicRoad& road = *skeleton_.road(road_);
  const skeleton::RoadMatch m = skeleton_.project(road_, pose.position, pose.heading);
  const auto candidates = skeleton_.nearestRoads(pose.position, config_.left_map_distance_m, pose.heading);
  double nearest = m.distance;
  for (const auto& c : candidates) nearest = std::min(nearest, c.distance);
  checkLeftMap(pose, nearest, events);
  if (state_ == State::kOffMap) return false;

  // Wrong way (one-way road) or u-turn (two-way road): the heading stays against the road.
  // Against = heading against the road and not moving forward along it (a projection jumping to
  // the other leg of a hairpin has an opposite tangent but a larger s).
  const bool against = std::abs(m.heading_error) >= config_.wrong_way_heading_rad && m.s <= last_s_ + 0.1;
  last_s_ = m.s;
  if (against != wrong_way_) {
    if (wrong_way_since_s_ < 0) wrong_way_since_s_ = now_s_;
    ++wrong_way_poses_;
    if (now_s_ - wrong_way_since_s_ >= config_.wrong_way_time_s && wrong_way_poses_ >= 2) {
      wrong_way_since_s_ = -1.0;
      wrong_way_poses_ = 0;
      if (against && road.reverse_id >= 0) {
        enterRoad(skeleton_.project(road.reverse_id, pose.position, pose.heading), pose, false, -1.0,
                  "u-turn", events);
        return true;
      }
      wrong_way_ = against;
      if (against && !wrong_way_reported_) {
        RoadEvent e = makeEvent(RoadEventType::kWrongWay, pose, road_);
        e.distance_m = m.distance;
        e.detail = "driving against the one-way direction";
        events.push_back(e);
        wrong_way_reported_ = true;
      }
    }
  } else {
    wrong_way_since_s_ = -1.0;
    wrong_way_poses_ = 0;
  }

  // Reached the end intersection (against a one-way road: its start intersection).
  if (!wrong_way_ && m.s >= road.s_end) {
    reachIntersection(road.to, pose, road.s_end, "", events);
    return true;
  }
  if (wrong_way_ && m.s <= road.s_begin) {
    reachIntersection(road.from, pose, road.s_begin, "wrong way", events);
    return true;
  }

  // Hysteresis: another road replaces this one only when clearly and lastingly better.
  skeleton::RoadMatch own = m;
  if (wrong_way_) own.heading_error = std::abs(m.heading_error) - kPi;  // against is expected
  const skeleton::RoadMatch* better = nullptr;
  for (const auto& c : candidates) {
    if (c.road_id == road_ || std::abs(c.heading_error) > config_.acquire_heading_rad) continue;
    if (c.distance > config_.acquire_distance_m) continue;
    if (cost(c) + config_.switch_margin_m < cost(own)) better = &c;
    break;  // only the best other candidate counts
  }
  if (better == nullptr) {
    switch_candidate_ = -1;
    return false;
  }
  if (better->road_id != switch_candidate_) {
    switch_candidate_ = better->road_id;
    switch_since_s_ = now_s_;
    switch_poses_ = 1;
    return false;
  }
  ++switch_poses_;
  if (now_s_ - switch_since_s_ < config_.switch_time_s || switch_poses_ < 2) return false;
  ++stats_.rematches;
  enterRoad(*better, pose, false, -1.0, "rematched", events);
  return true;
}

bool RoadTracker::stepInIntersection(const PoseInput& pose, std::vector<RoadEvent>& events) {
  const skeleton::Intersection* in = skeleton_.intersection(intersection_);
  if (in == nullptr) {  // cannot happen with a consistent skeleton; recover by searching
    state_ = State::kSearching;
    return true;
  }
  const bool inside_this = skeleton::pointInPolygon(in->roi, pose.position);
  const int64_t u_turn = last_road_ >= 0 ? skeleton_.road(last_road_)->reverse_id : -1;

  // 1. Leaving onto an outgoing road o: on its ROI-free part [s_begin, s_end], close to it, heading
  //    along it (a u-turn back onto the reverse of the incoming road needs a closer heading).
  //    Where two outgoing roads both fit (a fork at a small angle), wait until one is better by
  //    exit_ambiguity_m or the car is exit_commit_m beyond s_begin; the event then carries the time
  //    the chosen road was first crossed into.
  // Plausible: close, heading along, not beyond the road's end; it fits once beyond s_begin.
  std::vector<skeleton::RoadMatch> plausible;
  for (int64_t id : in->outgoing) {
    const skeleton::AtomicRoad& o = *skeleton_.road(id);
    const skeleton::RoadMatch m = skeleton_.project(id, pose.position, pose.heading);
    const double max_heading = id == u_turn ? config_.u_turn_heading_rad : config_.exit_heading_rad;
    if (m.s >= o.length - 1e-6 || m.distance > config_.exit_distance_m ||
        std::abs(m.heading_error) > max_heading) {  // beyond o's end: steps 2 and 3
      continue;
    }
    plausible.push_back(m);
    if (m.s >= o.s_begin && !exit_crossings_.count(id)) {
      RoadEvent probe = makeEvent(RoadEventType::kEnteredRoad, pose, id);
      interpolateCrossing(probe, id, o.s_begin);
      exit_crossings_[id] = {probe.crossing_utime, probe.position};
    }
  }
  std::sort(plausible.begin(), plausible.end(),
            [](const skeleton::RoadMatch& x, const skeleton::RoadMatch& y) { return cost(x) < cost(y); });
  if (!plausible.empty()) {
    const skeleton::RoadMatch& m = plausible.front();
    const skeleton::AtomicRoad& o = *skeleton_.road(m.road_id);
    const bool clear = plausible.size() == 1 || cost(m) + config_.exit_ambiguity_m <= cost(plausible[1]);
    if (m.s >= o.s_begin && (clear || m.s >= o.s_begin + config_.exit_commit_m || m.s >= o.s_end)) {
      const auto crossing = exit_crossings_.at(m.road_id);
      enterRoad(m, pose, false, -1.0, "", events);
      events.back().crossing_utime = crossing.first;
      events.back().position = crossing.second;
      return true;
    }
    if (inside_this || m.s < o.s_begin) return false;  // wait for the next pose
  }

  // 2. Sparse poses (1 Hz) can jump over a short outgoing road o entirely. When the car has left
  //    this ROI and is inside the ROI of o's end intersection, past o's s_end, o was entered and
  //    closed. (Not while still inside this ROI: where two ROIs overlap that would ping-pong.)
  if (const skeleton::Intersection* inside = skeleton_.intersectionContaining(pose.position);
      !inside_this && inside != nullptr && inside != in) {
    for (int64_t id : in->outgoing) {
      const skeleton::AtomicRoad& o = *skeleton_.road(id);
      if (o.to != inside->id) continue;
      const skeleton::RoadMatch m = skeleton_.project(id, pose.position, pose.heading);
      if (m.distance > config_.exit_distance_m || m.s < o.s_end) continue;
      enterRoad(m, pose, false, o.s_begin, "short road passed between two poses", events);
      reachIntersection(o.to, pose, o.s_end, "short road passed between two poses", events);
      return true;
    }
  }
  // 3. Or the car is already on a road o2 leaving o's end intersection: o entered and closed, then o2.
  std::optional<skeleton::RoadMatch> best_o2;
  int64_t via = -1;
  for (int64_t id : inside_this ? std::vector<int64_t>{} : in->outgoing) {
    const skeleton::AtomicRoad& o = *skeleton_.road(id);
    const skeleton::Intersection* next = skeleton_.intersection(o.to);
    if (next == nullptr || next == in) continue;
    if (skeleton_.project(id, pose.position).s < o.s_end) continue;  // not past o's end
    for (int64_t id2 : next->outgoing) {
      const skeleton::AtomicRoad& o2 = *skeleton_.road(id2);
      if (id2 == o.reverse_id || o2.to == in->id) continue;
      const skeleton::RoadMatch m = skeleton_.project(id2, pose.position, pose.heading);
      if (m.s < o2.s_begin || m.s > o2.s_end || m.distance > config_.exit_distance_m ||
          std::abs(m.heading_error) > config_.exit_heading_rad) {
        continue;
      }
      if (!best_o2 || cost(m) < cost(*best_o2)) {
        best_o2 = m;
        via = id;
      }
    }
  }
  if (best_o2) {
    const skeleton::AtomicRoad& o = *skeleton_.road(via);
    enterRoad(skeleton_.project(via, pose.position, pose.heading), pose, false, o.s_begin,
              "short road passed between two poses", events);
    reachIntersection(o.to, pose, o.s_end, "short road passed between two poses", events);
    enterRoad(*best_o2, pose, false, skeleton_.road(best_o2->road_id)->s_begin, "", events);
    return true;
  }

  // 4. Leaving against the direction of an incoming one-way road: outside this ROI, on the road's
  //    ROI-free part, heading against it.
  std::optional<skeleton::RoadMatch> wrong;
  for (int64_t id : inside_this ? std::vector<int64_t>{} : in->incoming) {
    const skeleton::AtomicRoad* r = skeleton_.road(id);
    if (r->reverse_id >= 0) continue;
    const skeleton::RoadMatch m = skeleton_.project(id, pose.position, pose.heading);
    if (m.s > r->s_end || m.s < r->s_begin || m.distance > config_.exit_distance_m ||
        std::abs(m.heading_error) < config_.wrong_way_heading_rad) {
      continue;
    }
    if (!wrong || m.distance < wrong->distance) wrong = m;
  }
  if (wrong) {
    enterRoad(*wrong, pose, true, skeleton_.road(wrong->road_id)->s_end, "", events);
    return true;
  }

  // 5. Far from the map, or well outside this intersection without matching any of its roads.
  const auto candidates = skeleton_.nearestRoads(pose.position, config_.left_map_distance_m);
  double nearest = std::numeric_limits<double>::infinity();
  for (const auto& c : candidates) nearest = std::min(nearest, c.distance);
  checkLeftMap(pose, nearest, events);
  if (state_ == State::kOffMap) return false;
  double roi_radius = 0.0;
  for (const auto& q : in->roi) roi_radius = std::max(roi_radius, (q - in->centre).norm());
  if ((pose.position - in->centre).norm() > roi_radius + config_.acquire_distance_m && !inside_this) {
    state_ = State::kSearching;
    intersection_ = -1;
    return true;
  }
  return false;
}

void RoadTracker::enterRoad(const skeleton::RoadMatch& m, const PoseInput& pose, bool wrong_way,
                            double s_cross, const std::string& detail, std::vector<RoadEvent>& events) {
  const int64_t previous = road_ >= 0 ? road_ : last_road_;
  road_ = m.road_id;
  last_s_ = m.s;
  RoadEvent e = makeEvent(RoadEventType::kEnteredRoad, pose, m.road_id);
  e.previous_road_id = previous;
  e.distance_m = m.distance;
  e.detail = detail;
  if (s_cross >= 0) interpolateCrossing(e, m.road_id, s_cross);
  events.push_back(e);
  state_ = State::kOnRoad;
  intersection_ = -1;
  last_road_ = previous;
  wrong_way_ = wrong_way;
  wrong_way_reported_ = false;
  wrong_way_since_s_ = -1.0;
  wrong_way_poses_ = 0;
  switch_candidate_ = -1;
  if (wrong_way) {
    RoadEvent w = makeEvent(RoadEventType::kWrongWay, pose, m.road_id);
    w.distance_m = m.distance;
    w.detail = "driving against the one-way direction";
    events.push_back(w);
    wrong_way_reported_ = true;
  }
}

void RoadTracker::reachIntersection(int64_t intersection_id, const PoseInput& pose, double s_cross,
                                    const std::string& detail, std::vector<RoadEvent>& events) {
  RoadEvent e = makeEvent(RoadEventType::kReachedIntersection, pose, road_);
  e.intersection_id = intersection_id;
  e.distance_m = skeleton_.project(road_, pose.position).distance;
  e.detail = detail;
  interpolateCrossing(e, road_, s_cross);
  events.push_back(e);
  state_ = State::kInIntersection;
  intersection_ = intersection_id;
  exit_crossings_.clear();
  last_road_ = road_;
  road_ = -1;
  wrong_way_ = false;
  switch_candidate_ = -1;
}

RoadEvent RoadTracker::makeEvent(RoadEventType type, const PoseInput& pose, int64_t road_id) const {
  RoadEvent e;
  e.type = type;
  e.utime = pose.utime;
  e.crossing_utime = pose.utime;
  e.position = pose.position;
  e.road_id = road_id;
  if (const skeleton::AtomicRoad* r = skeleton_.road(road_id)) {
    e.from_node = r->from;
    e.to_node = r->to;
  }
  return e;
}

void RoadTracker::interpolateCrossing(RoadEvent& e, int64_t road, double s_cross) const {
  if (!have_prev_) return;
  const double s0 = skeleton_.project(road, prev_position_).s;
  const double s1 = skeleton_.project(road, e.position).s;
  double f = 1.0;
  if (std::abs(s1 - s0) > 1e-6) f = std::clamp((s_cross - s0) / (s1 - s0), 0.0, 1.0);
  e.crossing_utime = prev_utime_ + static_cast<int64_t>(std::llround(f * (e.utime - prev_utime_)));
  e.position = prev_position_ + f * (e.position - prev_position_);
}

RoadTrackerConfig RoadTrackerConfig::fromYaml(const YAML::Node& n) {
  const config::YamlReader r(n);
  RoadTrackerConfig c = fromYaml(r);
  r.finish();
  return c;
}

RoadTrackerConfig RoadTrackerConfig::fromYaml(const config::YamlReader& r) {
  RoadTrackerConfig c;
  r.read("measurement_sigma_m", c.measurement_sigma_m);
  r.read("acceleration_sigma", c.acceleration_sigma);
  r.read("acquire_distance_m", c.acquire_distance_m);
  r.read("acquire_heading_rad", c.acquire_heading_rad);
  r.read("exit_distance_m", c.exit_distance_m);
  r.read("exit_heading_rad", c.exit_heading_rad);
  r.read("u_turn_heading_rad", c.u_turn_heading_rad);
  r.read("exit_ambiguity_m", c.exit_ambiguity_m);
  r.read("exit_commit_m", c.exit_commit_m);
  r.read("switch_margin_m", c.switch_margin_m);
  r.read("switch_time_s", c.switch_time_s);
  r.read("left_map_distance_m", c.left_map_distance_m);
  r.read("left_map_time_s", c.left_map_time_s);
  r.read("wrong_way_heading_rad", c.wrong_way_heading_rad);
  r.read("wrong_way_time_s", c.wrong_way_time_s);
  r.read("pose_gap_s", c.pose_gap_s);
  r.read("max_innovation_m", c.max_innovation_m);
  r.read("time_jump_s", c.time_jump_s);
  return c;
}

}  // namespace lanemap::tracking
