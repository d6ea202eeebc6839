// Road-level OSM XML writer (see road_osm_writer.h).

#include "core/io/road_osm_writer.h"
#include "core/io/xml_escape.h"

#include "core/io/atomic_file.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <set>

namespace lanemap::io {
namespace {

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// OSM's own precision: 7 decimals (about 1 cm).
std::string coord(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.7f", v);
  return buf;
}

void appendTag(std::string& out, const std::string& k, const std::string& v) {
  out += "    <tag k=\"" + escapeXml(k) + "\" v=\"" + escapeXml(v) + "\"/>\n";
}

osm::Bounds boundsOf(const osm::OsmData& data, const std::set<int64_t>& used_nodes) {
  if (data.bounds.valid()) return data.bounds;
  osm::Bounds b{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                std::numeric_limits<double>::lowest(), std::numeric_limits<double>::lowest()};
  for (int64_t id : used_nodes) {
    const osm::Node& n = data.nodes.at(id);
    b.min_lat = std::min(b.min_lat, n.lat);
    b.min_lon = std::min(b.min_lon, n.lon);
    b.max_lat = std::max(b.max_lat, n.lat);
    b.max_lon = std::max(b.max_lon, n.lon);
  }
  return b;
}

}  // namespace

bool isLaneTag(const std::string& key) {
  return key == "lanes" || startsWith(key, "lanes:") || key.find(":lanes") != std::string::npos ||
         key == "width" || startsWith(key, "width:") || startsWith(key, "placement");
}

std::string toRoadOsmXml(const osm::OsmData& data, const RoadOsmOptions& options,
                         const std::string& name) {
  std::vector<const osm::Way*> ways;
  for (const auto& w : data.ways) ways.push_back(&w);
  std::sort(ways.begin(), ways.end(), [](const auto* a, const auto* b) { return a->id < b->id; });

  std::set<int64_t> used_nodes;
  for (const auto* w : ways) {
    for (int64_t n : w->nodes) {
      if (!data.nodes.count(n)) {
        throw IoError("cannot write road OSM '" + name + "': way " + std::to_string(w->id) +
                      " refers to missing node " + std::to_string(n));
      }
      used_nodes.insert(n);
    }
  }

  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<osm version=\"0.6\" generator=\"lanemap\">\n";
  if (!used_nodes.empty() || data.bounds.valid()) {
    const osm::Bounds b = boundsOf(data, used_nodes);
    out += "  <bounds minlat=\"" + coord(b.min_lat) + "\" minlon=\"" + coord(b.min_lon) +
           "\" maxlat=\"" + coord(b.max_lat) + "\" maxlon=\"" + coord(b.max_lon) + "\"/>\n";
  }
  for (int64_t id : used_nodes) {
    const osm::Node& n = data.nodes.at(id);
    const auto tags = options.node_tags.find(id);
    out += "  <node id=\"" + std::to_string(id) + "\" version=\"1\" visible=\"true\" lat=\"" +
           coord(n.lat) + "\" lon=\"" + coord(n.lon) + "\"";
    if (tags == options.node_tags.end() || tags->second.empty()) {
      out += "/>\n";
    } else {
      out += ">\n";
      for (const auto& [k, v] : tags->second) appendTag(out, k, v);
      out += "  </node>\n";
    }
  }
  for (const auto* w : ways) {
    out += "  <way id=\"" + std::to_string(w->id) + "\" version=\"1\" visible=\"true\">\n";
    for (int64_t n : w->nodes) out += "    <nd ref=\"" + std::to_string(n) + "\"/>\n";
    for (const auto& [k, v] : w->tags) {
      if (options.keep_lane_tags || !isLaneTag(k)) appendTag(out, k, v);
    }
    out += "  </way>\n";
  }
  std::vector<const osm::Restriction*> restrictions;
  for (const auto& r : data.restrictions) restrictions.push_back(&r);
  std::sort(restrictions.begin(), restrictions.end(),
            [](const auto* a, const auto* b) { return a->id < b->id; });
  for (const auto* r : restrictions) {
    out += "  <relation id=\"" + std::to_string(r->id) + "\" version=\"1\" visible=\"true\">\n";
    out += "    <member type=\"way\" ref=\"" + std::to_string(r->from_way) + "\" role=\"from\"/>\n";
    out += "    <member type=\"node\" ref=\"" + std::to_string(r->via_node) + "\" role=\"via\"/>\n";
    out += "    <member type=\"way\" ref=\"" + std::to_string(r->to_way) + "\" role=\"to\"/>\n";
    appendTag(out, "type", "restriction");
    appendTag(out, "restriction", r->restriction);
    out += "  </relation>\n";
  }
  out += "</osm>\n";
  return out;
}

void writeRoadOsm(const osm::OsmData& data, const std::string& path, const RoadOsmOptions& options) {
  writeFileAtomically(path, toRoadOsmXml(data, options, path));
}

}  // namespace lanemap::io
