// Two straight lanes per atomic road, with no BEV and no exploration: a map of any size for what
// costs or breaks with the number of roads and junctions (lanemap-bench-store; the intersection
// builder over every junction of Monaco in tests/intersections).
#pragma once

#include "core/map/lane_map.h"
#include "core/mapping/road_lanes.h"
#include "core/skeleton/skeleton.h"

#include <algorithm>
#include <vector>

namespace lanemap::testing {

// Two lanes on the right of the road's line, straight segments every 5 m of its stretch.
inline map::LaneMap twoStraightLanes(const skeleton::Skeleton& sk, const skeleton::AtomicRoad& road) {
  map::LaneMap m;
  m.origin_lat = sk.frame().origin().lat;
  m.origin_lon = sk.frame().origin().lon;
  const double s0 = road.s_begin, s1 = std::max(road.s_begin + 1.0, road.s_end);
  int64_t id = (road.id + 1) * 100000;
  std::vector<map::LineString> lines(3);
  for (int k = 0; k < 3; ++k) {
    lines[k].id = ++id;
    lines[k].type = k == 1 ? map::LineType::kDashed : map::LineType::kSolid;
  }
  std::vector<std::vector<Eigen::Vector3d>> centres(2);
  const int steps = std::max(1, static_cast<int>((s1 - s0) / 5.0));
  for (int i = 0; i <= steps; ++i) {
    const double s = s0 + (s1 - s0) * i / steps;
    const Eigen::Vector2d p = sk.pointAt(road, s), t = sk.tangentAt(road, s), right(t.y(), -t.x());
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d q = p + right * (0.2 + 3.5 * k);
      lines[k].points.emplace_back(q.x(), q.y(), 0.0);
    }
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d q = p + right * (0.2 + 1.75 + 3.5 * k);
      centres[k].emplace_back(q.x(), q.y(), 0.0);
    }
  }
  for (int k = 0; k < 2; ++k) {
    map::Lanelet ll;
    ll.id = ++id;
    ll.road_id = road.id;
    ll.from_node = road.from;
    ll.to_node = road.to;
    ll.index_from_left = k;
    ll.left_id = lines[k].id;
    ll.right_id = lines[k + 1].id;
    ll.centre = centres[k];
    m.lanelets.push_back(ll);
  }
  m.lines = lines;
  mapping::dropMisreadLanelets(m);  // offset lines turned inside out on a tight bend, as the mapper does
  return m;
}

}  // namespace lanemap::testing
