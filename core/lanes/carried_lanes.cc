#include "core/lanes/carried_lanes.h"

#include "core/lanes/frenet.h"

#include <algorithm>
#include <cmath>

namespace lanemap::lanes {

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
  const double len = road.s_end - road.s_begin;
  const int n = std::max(2, static_cast<int>(std::ceil(len / o.waypoint_spacing_m)) + 1);
  for (size_t k = 0; k < kept.size(); ++k) {
    const CarriedLane& c = kept[k];
    Lane lane;
    lane.id = static_cast<int>(k);
    lane.index_from_left = static_cast<int>(k);
    lane.s_begin = road.s_begin;
    lane.s_end = road.s_end;
    PiecewiseLinearFit fit;
    fit.knots = {road.s_begin, road.s_end};
    fit.values = {c.d, c.d};
    lane.centre = CentreLine(fit, road.s_begin, road.s_end);
    for (int i = 0; i < n; ++i) {
      const double s = road.s_begin + len * i / (n - 1);
      lane.waypoint_s.push_back(s);
      lane.waypoints.push_back(frame->toEnu(s, c.d));
      lane.left.d.push_back(c.d + c.half_left_m);
      lane.left.points.push_back(frame->toEnu(s, c.d + c.half_left_m));
      lane.right.d.push_back(c.d - c.half_right_m);
      lane.right.points.push_back(frame->toEnu(s, c.d - c.half_right_m));
    }
    lane.left.type = c.left_type;
    lane.right.type = c.right_type;
    res.lanes.push_back(std::move(lane));
  }
  return res;
}

int dropLanesApartFromCarried(const RoadGeometry& road, const std::vector<CarriedLane>& carried,
                              const ExplorerOptions& o, ExplorationResult* explored) {
  auto& lanes = explored->lanes;
  if (!o.drop_lanes_apart_from_carried || carried.empty() || !(road.s_end - road.s_begin < o.carry_lanes_max_m)) return 0;
  for (const auto& c : carried) {
    if (!c.seen) return 0;
  }
  // The carried lanes side by side nearest the road's line (the road before's own carriageway: a
  // lane more than a lane's width from the rest was itself explored across an island).
  std::vector<double> cd;
  for (const auto& c : carried) cd.push_back(c.d);
  std::sort(cd.begin(), cd.end());
  std::vector<double> group, best_group;
  double best_gap = INFINITY;
  for (size_t k = 0; k <= cd.size(); ++k) {
    if (k == cd.size() || (!group.empty() && cd[k] - group.back() > o.lane_width_max_m)) {
      const double gap = group.front() > 0.0 ? group.front() : group.back() < 0.0 ? -group.back() : 0.0;  // from d = 0
      if (gap < best_gap) {
        best_gap = gap;
        best_group = group;
      }
      group.clear();
    }
    if (k < cd.size()) group.push_back(cd[k]);
  }
  if (lanes.size() <= best_group.size()) return 0;
  // Each explored lane's offset: its centre's mean over its stretch.
  std::vector<double> d(lanes.size());
  for (size_t k = 0; k < lanes.size(); ++k) {
    const Lane& l = lanes[k];
    constexpr int kSamples = 9;
    double sum = 0.0;
    for (int i = 0; i < kSamples; ++i) sum += l.centre.d(l.s_begin + (l.s_end - l.s_begin) * i / (kSamples - 1));
    d[k] = sum / kSamples;
  }
  const auto matched = [&](double shift, std::vector<bool>* m) {
    int n = 0;
    for (size_t k = 0; k < lanes.size(); ++k) {
      bool hit = false;
      for (const double c : best_group) hit = hit || std::abs(d[k] - (c + shift)) < o.same_lane_m;
      if (m) (*m)[k] = hit;
      n += hit;
    }
    return n;
  };
  // The common shift matching the most lanes (of equals the smallest), in 5 cm steps.
  const int steps = static_cast<int>(std::floor(0.5 * o.lane_width_max_m / 0.05));
  int best_n = 0;
  double best_shift = 0.0;
  for (int i = 0; i <= steps; ++i) {
    for (const double shift : {0.05 * i, -0.05 * i}) {
      const int n = matched(shift, nullptr);
      if (n > best_n) {
        best_n = n;
        best_shift = shift;
      }
    }
  }
  if (best_n == 0) return 0;
  std::vector<bool> kept(lanes.size(), false);
  matched(best_shift, &kept);
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

}  // namespace lanemap::lanes
