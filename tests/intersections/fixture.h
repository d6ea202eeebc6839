// Hand-made street networks for the intersection tests: OSM data in ENU metres around a fixed
// origin, the skeleton, and straight road lanes laid out from the lane counts (two-way roads: lanes
// right of the way's centre line; one-way roads: centred), optionally with a left turn pocket.
#pragma once

#include "core/intersections/intersections.h"
#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace lanemap::testing {

class Net {
 public:
  void node(int64_t id, double x, double y) {
    const double lat0 = 37.80, lon0 = -122.28;
    data.nodes[id] = {id, lat0 + y / 111132.0, lon0 + x / (111320.0 * std::cos(lat0 * M_PI / 180.0))};
  }
  void way(int64_t id, std::vector<int64_t> nodes, osm::Tags tags = {}) {
    if (!tags.count("highway")) tags["highway"] = "residential";
    data.ways.push_back({id, std::move(nodes), std::move(tags)});
  }
  void restriction(const std::string& value, int64_t from_way, int64_t via, int64_t to_way) {
    osm::Restriction r;
    r.id = 900 + static_cast<int64_t>(data.restrictions.size());
    r.restriction = value;
    r.from_way = from_way;
    r.via_node = via;
    r.to_way = to_way;
    data.restrictions.push_back(r);
  }
  skeleton::Skeleton build() {
    data.bounds = {37.79, -122.29, 37.81, -122.27};
    skeleton::SkeletonOptions o;
    o.origin = geo::LatLonAlt{37.80, -122.28, 0.0};
    return skeleton::Skeleton::build(data, o);
  }
  osm::OsmData data;
};

// Lanes of a road in its direction from the OSM tags (defaults: 1 per direction).
inline int laneCount(const skeleton::AtomicRoad& r) {
  const auto tag = [&](const char* k) { return r.tags.count(k) ? std::stoi(r.tags.at(k)) : 0; };
  if (r.reverse_id < 0) return std::max(1, tag("lanes"));
  if (r.along_way && tag("lanes:forward")) return tag("lanes:forward");
  if (!r.along_way && tag("lanes:backward")) return tag("lanes:backward");
  return std::max(1, tag("lanes") / 2);
}

struct LaneSpec {
  int lanes = 1;
  bool left_pocket = false;  // an extra left lane over the last 30 m, split from lane 0
  bool right_hand = true;    // two-way roads: lanes right (true) or left of the centre line
  double width = 3.5;
  double first_seen_m = 0.0;  // every lane starts this far past the road's start (a drive began there)
  double stub_m = 0.0;        // > 0: one more lane, from the road's start, lost this far in (not at the junction)
};

// The road's lanes as core/lanes' toLaneMap would give them (ids (road_id + 1) * 100000 + k).
inline map::LaneMap roadLanes(const skeleton::Skeleton& sk, const skeleton::AtomicRoad& r, const LaneSpec& spec) {
  map::LaneMap m;
  m.origin_lat = sk.frame().origin().lat;
  m.origin_lon = sk.frame().origin().lon;
  int64_t next = (r.id + 1) * 100000 + 1;
  const double w = spec.width;
  const bool two_way = r.reverse_id >= 0;
  const auto offset = [&](int k) {
    if (!two_way) return (spec.lanes / 2.0 - k - 0.5) * w;
    return spec.right_hand ? -(k + 0.5) * w : (spec.lanes - k - 0.5) * w;
  };
  const auto piece = [&](double s0, double s1, double d, int index) {
    map::LineString left, right;
    map::Lanelet ll;
    left.id = next++;
    right.id = next++;
    ll.id = next++;
    left.type = right.type = map::LineType::kDashed;
    const int n = std::max(2, static_cast<int>(std::ceil((s1 - s0) / 2.0)) + 1);
    for (int i = 0; i < n; ++i) {
      const double s = s0 + (s1 - s0) * i / (n - 1);
      const Eigen::Vector2d p = sk.pointAt(r, s), t = sk.tangentAt(r, s), nl(-t.y(), t.x());
      const Eigen::Vector2d c = p + d * nl, l = p + (d + w / 2) * nl, q = p + (d - w / 2) * nl;
      ll.centre.emplace_back(c.x(), c.y(), 0.0);
      left.points.emplace_back(l.x(), l.y(), 0.0);
      right.points.emplace_back(q.x(), q.y(), 0.0);
    }
    ll.left_id = left.id;
    ll.right_id = right.id;
    ll.road_id = r.id;
    ll.from_node = r.from;
    ll.to_node = r.to;
    ll.index_from_left = index;
    m.lines.push_back(left);
    m.lines.push_back(right);
    m.lanelets.push_back(ll);
    return ll.id;
  };
  const double split = r.s_end - 30.0;
  const double start = r.s_begin + spec.first_seen_m;
  const int shift = spec.left_pocket ? 1 : 0;
  for (int k = 0; k < spec.lanes; ++k) {
    if (k == 0 && spec.left_pocket) {
      const int64_t a = piece(start, split, offset(0), shift);
      const int64_t b = piece(split, r.s_end, offset(0), shift);
      const int64_t p = piece(split, r.s_end, offset(0) + w, 0);
      for (auto& ll : m.lanelets) {
        if (ll.id == a) ll.successors = {b, p};
      }
    } else {
      piece(start, r.s_end, offset(k), k + shift);
    }
  }
  if (spec.stub_m > 0.0) piece(r.s_begin, r.s_begin + spec.stub_m, offset(0), 0);
  return m;
}

// Lanes of every road of the skeleton, `spec_of(road)` deciding each road's layout.
template <typename F>
std::map<int64_t, map::LaneMap> allLanes(const skeleton::Skeleton& sk, F spec_of) {
  std::map<int64_t, map::LaneMap> out;
  for (const auto& r : sk.roads()) out[r.id] = roadLanes(sk, r, spec_of(r));
  return out;
}

// A connection as (from node of the in road, in lane index, to node of the out road, out index).
using Pair = std::tuple<int64_t, int, int64_t, int>;
inline std::vector<Pair> pairsOf(const skeleton::Skeleton& sk, const intersections::IntersectionResult& r) {
  std::vector<Pair> out;
  for (const auto& c : r.connections) {
    out.emplace_back(sk.road(c.in_road)->from, c.in_index, sk.road(c.out_road)->to, c.out_index);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace lanemap::testing
