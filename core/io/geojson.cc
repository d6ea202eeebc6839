// GeoJSON export of a LaneMap (see geojson.h).
#include "core/io/geojson.h"

#include "core/geo/local_frame.h"
#include "core/io/lanelet2.h"

#include <algorithm>
#include <cmath>

namespace lanemap::io {
namespace {

using nlohmann::json;

double roundTo(double v, double step) { return std::round(v / step) * step; }

json position(const geo::LocalFrame& frame, const Eigen::Vector3d& p) {
  const geo::LatLonAlt g = enuToLatLonEle(frame, p);
  return json::array({roundTo(g.lon, 1e-9), roundTo(g.lat, 1e-9), roundTo(g.alt, 1e-4)});
}

json positions(const geo::LocalFrame& frame, const std::vector<Eigen::Vector3d>& pts) {
  json out = json::array();
  for (const auto& p : pts) out.push_back(position(frame, p));
  return out;
}

json feature(json geometry, json properties) {
  return json{{"type", "Feature"}, {"geometry", std::move(geometry)}, {"properties", std::move(properties)}};
}

// laneletOutline turned counter-clockwise (RFC 7946) and closed.
std::vector<Eigen::Vector3d> laneletRing(const map::LaneMap& map, const map::Lanelet& lanelet) {
  std::vector<Eigen::Vector3d> ring = laneletOutline(map, lanelet);
  if (ring.empty()) return ring;
  double area2 = 0.0;
  for (size_t i = 0; i < ring.size(); ++i) {
    const auto& a = ring[i];
    const auto& b = ring[(i + 1) % ring.size()];
    area2 += a.x() * b.y() - b.x() * a.y();
  }
  if (area2 < 0.0) std::reverse(ring.begin(), ring.end());
  ring.push_back(ring.front());
  return ring;
}

// A partial road's lanelet (mapped as far as the drive went): partial, and where it stops; the
// lane's confidence (null when the map has none).
void addPartial(json& props, const map::Lanelet& ll) {
  props["partial"] = ll.partial.has_value();
  props["partial_station_m"] = ll.partial ? json(ll.partial->station_m) : json(nullptr);
  props["road_length_m"] = ll.partial ? json(ll.partial->road_length_m) : json(nullptr);
  props["confidence"] = ll.confidence ? json(*ll.confidence) : json(nullptr);
}

const char* kindName(map::LaneletKind k) {
  return k == map::LaneletKind::kIntersection ? "intersection" : "road";
}

}  // namespace

nlohmann::json toGeoJson(const map::LaneMap& map) {
  const geo::LocalFrame frame({map.origin_lat, map.origin_lon, map.origin_alt});
  json features = json::array();
  for (const auto& ll : map.lanelets) {
    const std::vector<Eigen::Vector3d> ring = laneletRing(map, ll);
    if (ring.empty()) continue;
    json props{{"feature", "lanelet"},
               {"id", ll.id},
               {"kind", kindName(ll.kind)},
               {"road_id", ll.road_id},
               {"from_node", ll.from_node},
               {"to_node", ll.to_node},
               {"intersection_id", ll.intersection_id},
               {"index_from_left", ll.index_from_left},
               {"turn", map::toString(ll.turn)},
               {"successors", ll.successors},
               {"left_id", ll.left_id},
               {"right_id", ll.right_id},
               {"stop_line_id", ll.stop_line_id ? json(*ll.stop_line_id) : json(nullptr)}};
    addPartial(props, ll);
    json geometry{{"type", "Polygon"},
                  {"coordinates", json::array({positions(frame, ring)})}};
    features.push_back(feature(std::move(geometry), std::move(props)));
  }
  for (const auto& ll : map.lanelets) {
    if (ll.centre.size() < 2) continue;
    json props{{"feature", "centre_line"},
               {"lanelet", ll.id},
               {"kind", kindName(ll.kind)},
               {"road_id", ll.road_id},
               {"index_from_left", ll.index_from_left},
               {"turn", map::toString(ll.turn)}};
    addPartial(props, ll);
    json geometry{{"type", "LineString"}, {"coordinates", positions(frame, ll.centre)}};
    features.push_back(feature(std::move(geometry), std::move(props)));
  }
  for (const auto& line : map.lines) {
    if (line.points.empty()) continue;
    json props{{"feature", "boundary"}, {"id", line.id}, {"type", map::toString(line.type)}};
    json geometry = line.points.size() == 1
                        ? json{{"type", "Point"}, {"coordinates", position(frame, line.points.front())}}
                        : json{{"type", "LineString"}, {"coordinates", positions(frame, line.points)}};
    features.push_back(feature(std::move(geometry), std::move(props)));
  }
  // Traffic rules at the stop lines: the stop line is the geometry (a light: its bottom edge, too).
  for (const auto& re : map.regulatory_elements) {
    const map::LineString* stop = map.line(re.stop_line_id);
    if (!stop || stop->points.size() < 2) continue;
    json props{{"feature", "regulatory_element"},
               {"id", re.id},
               {"kind", map::toString(re.kind)},
               {"stop_line_id", re.stop_line_id},
               {"lanelets", re.lanelets},
               {"priority", re.priority},
               {"osm_node", re.osm_node >= 0 ? json(re.osm_node) : json(nullptr)}};
    json lines = json::array({positions(frame, stop->points)});
    if (re.kind == map::RegulatoryKind::kTrafficLight && re.light.size() >= 2) {
      lines.push_back(positions(frame, re.light));
      props["light_height_m"] = re.light_height_m;
      props["light_estimated"] = re.light_estimated;
    }
    features.push_back(feature(json{{"type", "MultiLineString"}, {"coordinates", std::move(lines)}}, std::move(props)));
  }
  // Pedestrian crossings: the area between their two edges.
  for (const auto& cw : map.crosswalks) {
    if (cw.left.size() < 2 || cw.right.size() < 2) continue;
    std::vector<Eigen::Vector3d> ring = cw.left;
    ring.insert(ring.end(), cw.right.rbegin(), cw.right.rend());
    double area2 = 0.0;
    for (size_t i = 0; i < ring.size(); ++i) {
      area2 += ring[i].x() * ring[(i + 1) % ring.size()].y() - ring[(i + 1) % ring.size()].x() * ring[i].y();
    }
    if (area2 < 0.0) std::reverse(ring.begin(), ring.end());
    ring.push_back(ring.front());
    json props{{"feature", "crosswalk"}, {"id", cw.id}, {"crossing", cw.crossing}, {"road_id", cw.road_id}};
    features.push_back(feature(json{{"type", "Polygon"}, {"coordinates", json::array({positions(frame, ring)})}}, std::move(props)));
  }
  return json{{"type", "FeatureCollection"},
              {"lanemap_origin", {{"lat", map.origin_lat}, {"lon", map.origin_lon}, {"alt", map.origin_alt}}},
              {"features", std::move(features)}};
}

void writeGeoJson(const map::LaneMap& map, const std::string& path) {
  writeFileAtomically(path, toGeoJson(map).dump() + "\n");
}

}  // namespace lanemap::io
