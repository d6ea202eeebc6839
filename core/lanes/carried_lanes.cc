#include "core/lanes/carried_lanes.h"

#include "core/lanes/frenet.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace lanemap::lanes {

namespace {

// A lane over [s_begin, s_end] at offset d with a carried lane's half-widths and line types; no
// particle supports it.
Lane laneAtCarriedOffset(const FrenetFrame& frame, double s_begin, double s_end, const CarriedLane& c, double d,
                         const ExplorerOptions& o) {
  const double len = s_end - s_begin;
  const int n = std::max(2, static_cast<int>(std::ceil(len / o.waypoint_spacing_m)) + 1);
  Lane lane;
  lane.s_begin = s_begin;
  lane.s_end = s_end;
  PiecewiseLinearFit fit;
  fit.knots = {s_begin, s_end};
  fit.values = {d, d};
  lane.centre = CentreLine(fit, s_begin, s_end);
  for (int i = 0; i < n; ++i) {
    const double s = s_begin + len * i / (n - 1);
    lane.waypoint_s.push_back(s);
    lane.waypoints.push_back(frame.toEnu(s, d));
    lane.left.d.push_back(d + c.half_left_m);
    lane.left.points.push_back(frame.toEnu(s, d + c.half_left_m));
    lane.right.d.push_back(d - c.half_right_m);
    lane.right.points.push_back(frame.toEnu(s, d - c.half_right_m));
  }
  lane.left.type = c.left_type;
  lane.right.type = c.right_type;
  return lane;
}

// A lane over [s_begin, s_end] as wide as the carried lane c, against `inner`'s right bound
// (`right`) or left bound: its near bound is that bound, station by station (the two share one
// border line string: laneNeighbours), its centre and far bound parallel to the road at the mean.
Lane laneAgainst(const FrenetFrame& frame, double s_begin, double s_end, const Lane& inner, bool right,
                 const CarriedLane& c, const ExplorerOptions& o) {
  const Boundary& bound = right ? inner.right : inner.left;
  const bool probed = !inner.waypoint_s.empty() && bound.d.size() == inner.waypoint_s.size();
  const auto boundAt = [&](double s) {
    return probed ? boundaryD(inner, bound, s) : inner.dAt(s) + (right ? -1.0 : 1.0) * o.default_half_width_m;
  };
  const double width = c.half_left_m + c.half_right_m;
  const double len = s_end - s_begin;
  const int n = std::max(2, static_cast<int>(std::ceil(len / o.waypoint_spacing_m)) + 1);
  double mean = 0.0;
  for (int i = 0; i < n; ++i) mean += boundAt(s_begin + len * i / (n - 1)) / n;
  const double d = right ? mean - 0.5 * width : mean + 0.5 * width;
  Lane lane = laneAtCarriedOffset(frame, s_begin, s_end, c, d, o);
  for (int i = 0; i < n; ++i) {
    const double s = lane.waypoint_s[i];
    Boundary& near = right ? lane.left : lane.right;
    Boundary& far = right ? lane.right : lane.left;
    near.d[i] = boundAt(s);
    near.points[i] = frame.toEnu(s, near.d[i]);
    far.d[i] = right ? d - 0.5 * width : d + 0.5 * width;
    far.points[i] = frame.toEnu(s, far.d[i]);
  }
  return lane;
}

// The carried lanes side by side nearest the road's line (the road before's own carriageway: a
// lane more than lane_width_max_m from the rest was itself explored across an island), right to
// left (increasing d). Empty when any carried lane was not seen (made from an OSM way).
std::vector<CarriedLane> carriedNearTheLine(const std::vector<CarriedLane>& carried, const ExplorerOptions& o) {
  for (const auto& c : carried) {
    if (!c.seen) return {};
  }
  std::vector<CarriedLane> cd = carried;
  std::sort(cd.begin(), cd.end(), [](const CarriedLane& a, const CarriedLane& b) { return a.d < b.d; });
  std::vector<CarriedLane> group, best_group;
  double best_gap = INFINITY;
  for (size_t k = 0; k <= cd.size(); ++k) {
    if (k == cd.size() || (!group.empty() && cd[k].d - group.back().d > o.lane_width_max_m)) {
      const double gap = group.front().d > 0.0 ? group.front().d : group.back().d < 0.0 ? -group.back().d : 0.0;
      if (gap < best_gap) {
        best_gap = gap;
        best_group = group;
      }
      group.clear();
    }
    if (k < cd.size()) group.push_back(cd[k]);
  }
  return best_group;
}

// Each explored lane's offset: its centre's mean over its stretch.
std::vector<double> meanOffsets(const std::vector<Lane>& lanes) {
  std::vector<double> d(lanes.size());
  for (size_t k = 0; k < lanes.size(); ++k) {
    const Lane& l = lanes[k];
    constexpr int kSamples = 9;
    double sum = 0.0;
    for (int i = 0; i < kSamples; ++i) sum += l.centre.d(l.s_begin + (l.s_end - l.s_begin) * i / (kSamples - 1));
    d[k] = sum / kSamples;
  }
  return d;
}

// Explored lanes (offsets d) within `tolerance` of a carried lane moved by `shift`; *hit per lane.
int matchedUnderShift(const std::vector<double>& d, const std::vector<CarriedLane>& group, double shift,
                      double tolerance, std::vector<bool>* hit = nullptr) {
  int n = 0;
  for (size_t k = 0; k < d.size(); ++k) {
    bool h = false;
    for (const auto& c : group) h = h || std::abs(d[k] - (c.d + shift)) < tolerance;
    if (hit) (*hit)[k] = h;
    n += h;
  }
  return n;
}

// The common shift (at most max_shift, in 5 cm steps) matching the most explored lanes to carried
// ones within `tolerance`, of equals the smallest; *matched: how many (0: none, the shift is 0).
double bestCommonShift(const std::vector<double>& d, const std::vector<CarriedLane>& group, double max_shift,
                       double tolerance, int* matched) {
  const int steps = static_cast<int>(std::floor(max_shift / 0.05 + 1e-9));
  int best_n = 0;
  double best_shift = 0.0;
  for (int i = 0; i <= steps; ++i) {
    for (const double shift : {0.05 * i, -0.05 * i}) {
      const int n = matchedUnderShift(d, group, shift, tolerance);
      if (n > best_n) {
        best_n = n;
        best_shift = shift;
      }
    }
  }
  *matched = best_n;
  return best_shift;
}

}  // namespace

bool takesCarriedLanes(const RoadGeometry& road, const ExplorationResult& explored, size_t carried,
                       const ExplorerOptions& o) {
  return carried > 0 && road.s_end - road.s_begin < o.carry_lanes_max_m && explored.lanes.empty();
}

ExplorationResult carryLanesThrough(const RoadGeometry& road_in, std::vector<CarriedLane> carried,
                                    const ExplorerOptions& o) {
  if (carried.empty()) throw LanesError("road " + std::to_string(road_in.road_id) + ": no lanes to carry through");
  RoadGeometry road;
  ExplorationResult res = startExploration(road_in, o, &road);
  const FrenetFrame* frame = res.frame.get();
  if (!(road.s_end - road.s_begin > 1.0)) {
    throw LanesError("road " + std::to_string(road.road_id) + " has no length to carry lanes through");
  }
  // Left to right; of two lanes closer than same_lane_m (one lane twice) the left one stays.
  std::sort(carried.begin(), carried.end(), [](const CarriedLane& a, const CarriedLane& b) { return a.d > b.d; });
  std::vector<CarriedLane> kept;
  for (const auto& c : carried) {
    if (kept.empty() || kept.back().d - c.d >= o.same_lane_m) kept.push_back(c);
  }
  for (size_t k = 0; k < kept.size(); ++k) {
    res.lanes.push_back(laneAtCarriedOffset(*frame, road.s_begin, road.s_end, kept[k], kept[k].d, o));
    res.lanes.back().id = res.lanes.back().index_from_left = static_cast<int>(k);
  }
  return res;
}

int dropLanesApartFromCarried(const RoadGeometry& road, const std::vector<CarriedLane>& carried,
                              const ExplorerOptions& o, ExplorationResult* explored) {
  auto& lanes = explored->lanes;
  if (!o.drop_lanes_apart_from_carried || carried.empty() || !(road.s_end - road.s_begin < o.carry_lanes_max_m)) return 0;
  const std::vector<CarriedLane> group = carriedNearTheLine(carried, o);
  if (group.empty() || lanes.size() <= group.size()) return 0;
  const std::vector<double> d = meanOffsets(lanes);
  int best_n = 0;
  const double best_shift = bestCommonShift(d, group, 0.5 * o.lane_width_max_m, o.same_lane_m, &best_n);
  if (best_n == 0) return 0;
  std::vector<bool> kept(lanes.size(), false);
  matchedUnderShift(d, group, best_shift, o.same_lane_m, &kept);
  for (bool grew = true; grew;) {  // outwards from the matched lanes, a lane's width at a time
    grew = false;
    for (size_t k = 0; k < lanes.size(); ++k) {
      if (kept[k]) continue;
      for (size_t j = 0; j < lanes.size() && !kept[k]; ++j) {
        if (kept[j] && std::abs(d[k] - d[j]) <= o.lane_width_max_m) kept[k] = grew = true;
      }
    }
  }
  std::vector<bool> drop(lanes.size());
  int dropped = 0;
  for (size_t k = 0; k < lanes.size(); ++k) dropped += drop[k] = !kept[k];
  if (dropped > 0) removeLanes(drop, &lanes);
  return dropped;
}

int addCarriedLanesNotFound(const RoadGeometry& road, const std::vector<CarriedLane>& carried,
                            const ExplorerOptions& o, ExplorationResult* explored) {
  auto& lanes = explored->lanes;
  if (!o.add_carried_lanes_not_found || carried.empty() || lanes.empty() || !explored->frame ||
      !(road.s_end - road.s_begin < o.carry_lanes_max_m)) {
    return 0;
  }
  const std::vector<CarriedLane> group = carriedNearTheLine(carried, o);
  if (lanes.size() >= group.size()) return 0;
  // The explored lanes lie where carried ones do: each within same_lane_m / 2 of one, under one
  // shift of at most that (a one-way road's line moved by half a lane where its lane count changed
  // at the junction: the link has other lanes than the road before, and nothing is added).
  const std::vector<double> d = meanOffsets(lanes);
  const double tolerance = 0.5 * o.same_lane_m;
  int matched = 0;
  const double shift = bestCommonShift(d, group, tolerance, tolerance, &matched);
  if (matched < static_cast<int>(lanes.size())) return 0;
  double s_begin = lanes.front().s_begin, s_end = lanes.front().s_end;
  for (const auto& l : lanes) {
    s_begin = std::min(s_begin, l.s_begin);
    s_end = std::max(s_end, l.s_end);
  }
  if (!(s_end - s_begin > 1.0)) return 0;
  // A kerb on the outer side of the outermost explored lane ends the carriageway there: no lane is
  // added beyond it.
  const auto leftmost = std::max_element(d.begin(), d.end()) - d.begin();
  const auto rightmost = std::min_element(d.begin(), d.end()) - d.begin();
  const bool kerb_left = lanes[leftmost].left.type == map::LineType::kCurb;
  const bool kerb_right = lanes[rightmost].right.type == map::LineType::kCurb;
  // Each lane to add, outwards from the explored ones: against the lane inside it (explored, or
  // added before it); one between two explored lanes at its carried offset.
  std::vector<std::pair<double, const CarriedLane*>> to_add;
  for (const auto& c : group) {
    const double at = c.d + shift;
    bool taken = false;  // an explored lane is there, or too near for a lane between
    for (const double dk : d) taken = taken || std::abs(dk - at) < o.lane_width_min_m;
    if (taken) continue;
    if ((at > d[leftmost] && kerb_left) || (at < d[rightmost] && kerb_right)) continue;
    to_add.emplace_back(at, &c);
  }
  std::sort(to_add.begin(), to_add.end(), [&](const auto& a, const auto& b) {
    return std::abs(a.first - d[a.first > d[leftmost] ? leftmost : rightmost]) <
           std::abs(b.first - d[b.first > d[leftmost] ? leftmost : rightmost]);
  });
  int left_lane = static_cast<int>(leftmost), right_lane = static_cast<int>(rightmost);
  int added = 0;
  for (const auto& [at, c] : to_add) {
    Lane lane;
    if (at < d[rightmost]) {
      lane = laneAgainst(*explored->frame, s_begin, s_end, lanes[right_lane], true, *c, o);
      right_lane = static_cast<int>(lanes.size());
    } else if (at > d[leftmost]) {
      lane = laneAgainst(*explored->frame, s_begin, s_end, lanes[left_lane], false, *c, o);
      left_lane = static_cast<int>(lanes.size());
    } else {
      lane = laneAtCarriedOffset(*explored->frame, s_begin, s_end, *c, at, o);
    }
    lane.id = static_cast<int>(lanes.size());
    lanes.push_back(std::move(lane));
    ++added;
  }
  if (added > 0) removeLanes(std::vector<bool>(lanes.size(), false), &lanes);  // index from the left again
  return added;
}

}  // namespace lanemap::lanes
