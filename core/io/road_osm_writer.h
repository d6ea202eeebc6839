// Writes the road-level OpenStreetMap file the mapper is given (DESIGN.md, simulator output):
// drivable ways with their nodes and tags, turn restrictions and bounds, as OSM XML that
// libosmium and `osmium fileinfo` read. By default the lane-level tags are dropped, so the mapper
// has to find the lanes itself, as with a real OSM map that lacks them.
#pragma once

#include "core/io/atomic_file.h"
#include "core/osm/osm_data.h"

#include <map>
#include <string>

namespace lanemap::io {

struct RoadOsmOptions {
  bool keep_lane_tags = false;  // keep lanes*, *:lanes*, width*, placement* (see isLaneTag)
  // Tags written on the nodes of these ids that the file has (OsmData keeps no node tags): e.g.
  // the junction controls highway=stop|give_way|traffic_signals (intersections::readControlNodes).
  std::map<int64_t, osm::Tags> node_tags;
};

// Keys that describe lanes: `lanes`, `lanes:*`, any `*:lanes` / `*:lanes:*` (turn:lanes,
// turn:lanes:forward, width:lanes, change:lanes, ...), `width`, `width:*`, `placement*`.
bool isLaneTag(const std::string& key);

// The OSM XML document: bounds (from data.bounds, else from the nodes), the nodes the ways use
// (sorted by id), the ways (sorted by id) and one type=restriction relation per restriction.
// Throws IoError naming `name` when a way refers to a node that `data` does not have.
std::string toRoadOsmXml(const osm::OsmData& data, const RoadOsmOptions& options = {},
                         const std::string& name = "<road osm>");

// Writes toRoadOsmXml(data) to `path` atomically.
void writeRoadOsm(const osm::OsmData& data, const std::string& path,
                  const RoadOsmOptions& options = {});

}  // namespace lanemap::io
