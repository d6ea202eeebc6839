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
  return json{{"type", "FeatureCollection"},
              {"lanemap_origin", {{"lat", map.origin_lat}, {"lon", map.origin_lon}, {"alt", map.origin_alt}}},
              {"features", std::move(features)}};
}

void writeGeoJson(const map::LaneMap& map, const std::string& path) {
  writeFileAtomically(path, toGeoJson(map).dump() + "\n");
}

}  // namespace lanemap::io
