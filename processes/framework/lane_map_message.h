// LANE_MAP (lane_map_t: one road's lanes) to and from the core's map::LaneMap: the lane mapper
// publishes with toMessage, the viewer (and anything else on the bus) reads with fromMessage. The
// lanes' confidence and a partial road's stop station go over the bus too (-1 on the bus: none).
#pragma once

#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/polyline_t.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace lanemap {

inline int8_t polylineType(map::LineType t) {
  switch (t) {
    case map::LineType::kDashed: return polyline_t::TYPE_DASHED;
    case map::LineType::kSolid:
    case map::LineType::kSolidSolid: return polyline_t::TYPE_SOLID;
    case map::LineType::kCurb: return polyline_t::TYPE_CURB;
    case map::LineType::kVirtual: return polyline_t::TYPE_VIRTUAL;
    case map::LineType::kStopLine: return polyline_t::TYPE_STOP_LINE;
  }
  return polyline_t::TYPE_UNKNOWN;
}

// The message's line types are fewer: solid_solid comes back solid, unknown as virtual.
inline map::LineType lineType(int8_t t) {
  switch (t) {
    case polyline_t::TYPE_DASHED: return map::LineType::kDashed;
    case polyline_t::TYPE_SOLID: return map::LineType::kSolid;
    case polyline_t::TYPE_CURB: return map::LineType::kCurb;
    case polyline_t::TYPE_STOP_LINE: return map::LineType::kStopLine;
    default: return map::LineType::kVirtual;
  }
}

inline polyline_t toPolyline(const std::vector<Eigen::Vector3d>& pts, int8_t type) {
  polyline_t p;
  p.num_points = static_cast<int32_t>(pts.size());
  for (const auto& q : pts) {
    p.east.push_back(q.x());
    p.north.push_back(q.y());
    p.up.push_back(q.z());
  }
  p.type = type;
  return p;
}

// The points of a polyline; a message whose arrays disagree with num_points gives the shortest.
inline std::vector<Eigen::Vector3d> points(const polyline_t& p) {
  std::vector<Eigen::Vector3d> out;
  const size_t n = std::min({static_cast<size_t>(std::max(0, p.num_points)), p.east.size(), p.north.size(), p.up.size()});
  for (size_t i = 0; i < n; ++i) out.emplace_back(p.east[i], p.north[i], p.up[i]);
  return out;
}

// One road's lanes (its lanelets and their bounds) as LANE_MAP.
inline lane_map_t toMessage(int64_t road_id, const map::LaneMap& m, int64_t utime, const std::string& map_path) {
  lane_map_t msg;
  msg.utime = utime;
  msg.kind = lane_map_t::KIND_ROAD;
  msg.id = road_id;
  msg.origin_latitude = m.origin_lat;
  msg.origin_longitude = m.origin_lon;
  msg.origin_altitude = m.origin_alt;
  msg.partial_station_m = msg.partial_road_length_m = -1.0;
  for (const auto& ll : m.lanelets) {
    if (ll.partial) {  // the road's: every lanelet of a partial road carries the same
      msg.partial_station_m = ll.partial->station_m;
      msg.partial_road_length_m = ll.partial->road_length_m;
    }
    lane_t lane;
    lane.lane_id = ll.id;
    lane.index_from_left = ll.index_from_left;
    lane.centre = toPolyline(ll.centre, polyline_t::TYPE_VIRTUAL);
    const map::LineString* l = m.line(ll.left_id);
    const map::LineString* r = m.line(ll.right_id);
    lane.left_boundary = l ? toPolyline(l->points, polylineType(l->type)) : toPolyline({}, polyline_t::TYPE_UNKNOWN);
    lane.right_boundary = r ? toPolyline(r->points, polylineType(r->type)) : toPolyline({}, polyline_t::TYPE_UNKNOWN);
    lane.successors = ll.successors;
    lane.num_successors = static_cast<int32_t>(ll.successors.size());
    lane.confidence = ll.confidence ? *ll.confidence : -1.0;
    msg.lanes.push_back(std::move(lane));
  }
  msg.num_lanes = static_cast<int32_t>(msg.lanes.size());
  msg.map_path = map_path;
  return msg;
}

// LANE_MAP as a LaneMap: one lanelet per lane, its two boundaries as line strings of their own,
// with ids clear of the lane mapper's road ids ((road + 1) * 100000 + n) and of the intersections'
// (config/intersections.yaml id_base: 1e12 + 100000 * intersection). `sk` gives the road's nodes.
inline map::LaneMap fromMessage(const lane_map_t& msg, const skeleton::Skeleton& sk) {
  map::LaneMap m;
  m.origin_lat = msg.origin_latitude;
  m.origin_lon = msg.origin_longitude;
  m.origin_alt = msg.origin_altitude;
  const skeleton::AtomicRoad* road = sk.road(msg.id);
  int64_t next_line = 5'000'000'000'000LL + std::max<int64_t>(0, msg.id) * 100'000;
  for (const auto& lane : msg.lanes) {
    map::Lanelet ll;
    ll.id = lane.lane_id;
    ll.kind = map::LaneletKind::kRoad;
    ll.road_id = msg.id;
    if (road) {
      ll.from_node = road->from;
      ll.to_node = road->to;
    }
    ll.index_from_left = lane.index_from_left;
    ll.centre = points(lane.centre);
    ll.successors = lane.successors;
    if (std::isfinite(lane.confidence) && lane.confidence >= 0.0) ll.confidence = std::min(1.0, lane.confidence);
    if (std::isfinite(msg.partial_station_m) && msg.partial_station_m >= 0.0) {
      ll.partial = map::PartialRoad{msg.partial_station_m, std::max(msg.partial_station_m, msg.partial_road_length_m)};
    }
    for (const polyline_t* b : {&lane.left_boundary, &lane.right_boundary}) {
      auto pts = points(*b);
      if (pts.size() < 2) continue;
      map::LineString ls;
      ls.id = next_line++;
      ls.type = lineType(b->type);
      ls.points = std::move(pts);
      (b == &lane.left_boundary ? ll.left_id : ll.right_id) = ls.id;
      m.lines.push_back(std::move(ls));
    }
    m.lanelets.push_back(std::move(ll));
  }
  return m;
}

}  // namespace lanemap
