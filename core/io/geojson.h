// A LaneMap as GeoJSON (RFC 7946, WGS84 lon/lat/ele via the map's LocalFrame) for web maps and
// GIS tools: one Polygon per lanelet, one LineString per centre line and per boundary.
#pragma once

#include "core/io/atomic_file.h"
#include "core/map/lane_map.h"

#include <nlohmann/json.hpp>

#include <string>

namespace lanemap::io {

// FeatureCollection, features in this order:
// - per lanelet, a Polygon (exterior ring counter-clockwise, closed) with properties
//   feature="lanelet", id, kind ("road"/"intersection"), road_id, from_node, to_node,
//   intersection_id, index_from_left, turn ("none"/"straight"/"left"/"right"), successors (ids),
//   left_id, right_id, stop_line_id (null when none), partial (true on the road a drive ended on,
//   mapped as far as driven), partial_station_m and road_length_m (where along the atomic road its
//   lanes stop, and the road's length; null unless partial), confidence (the lane's, 0..1,
//   core/mapping/lane_confidence.h; null when the map has none);
// - per lanelet with >= 2 centre points, a LineString: feature="centre_line", lanelet, kind,
//   road_id, index_from_left, turn, partial, partial_station_m, road_length_m, confidence;
// - per line string, a LineString (a Point when it has one point): feature="boundary", id,
//   type ("dashed", "solid", "solid_solid", "curbstone", "virtual", "stop_line");
// - per regulatory element whose stop line exists, a MultiLineString (the stop line; a traffic
//   light's estimated bottom edge second): feature="regulatory_element", id, kind ("stop_sign",
//   "give_way", "traffic_light"), stop_line_id, lanelets (that obey or yield), priority (with right
//   of way), osm_node (the OSM node whose tag gave it, or null); a light also light_height_m and
//   light_estimated;
// - per crosswalk with two edges, a Polygon between them: feature="crosswalk", id, crossing (the
//   road lanelets under it), road_id.
// Positions are [lon, lat, ele] (ele = origin_alt + z), lon/lat rounded to 1e-9 degrees
// (0.1 mm). A foreign member "lanemap_origin" {lat, lon, alt} records the ENU origin.
// Lanelets whose bound is missing get no polygon (their centre line is still written).
nlohmann::json toGeoJson(const map::LaneMap& map);

// Writes toGeoJson(map) to `path` atomically. Throws IoError naming the path on failure.
void writeGeoJson(const map::LaneMap& map, const std::string& path);

}  // namespace lanemap::io
