// Reads the road-level part of an OpenStreetMap file with libosmium (XML .osm, .osm.pbf, and the
// other formats/compressions libosmium detects from the file name): the drivable highway ways, the
// nodes they use, and type=restriction relations.
//
// Decisions (documented here and in osm_data.h):
// - Drivable highway values: motorway, trunk, primary, secondary, tertiary, unclassified,
//   residential, their *_link, living_street, service, road. Not drivable: track, footway,
//   cycleway, path, steps, pedestrian, bridleway, construction, proposed, busway, ...
// - Among service roads, service=parking_aisle and service=driveway are dropped (car-park lanes and
//   private driveways are not part of the road network we map); alley, drive-through etc. stay.
// - A way tagged area=yes (a highway area polygon) or access=no is dropped.
// - Node references whose node is missing from the file (clipped extracts) are dropped from the
//   way; a way left with fewer than two distinct nodes is dropped.
// - Only restrictions whose via member is a node are kept (via-way restrictions are rare and the
//   skeleton cannot use them yet). The value comes from `restriction`, else `restriction:motorcar`.
#include "core/osm/osm_data.h"

#include "core/osm/coordinate_guard.h"

#include <osmium/handler.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/visitor.hpp>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <unordered_set>

namespace lanemap::osm {

std::string Way::tag(const std::string& key, const std::string& fallback) const {
  auto it = tags.find(key);
  return it == tags.end() ? fallback : it->second;
}

bool isDrivableHighway(const std::string& highway) {
  static const std::array<const char*, 15> kDrivable = {
      "motorway",      "trunk",          "primary",       "secondary",    "tertiary",
      "unclassified",  "residential",    "motorway_link", "trunk_link",   "primary_link",
      "secondary_link", "tertiary_link", "living_street", "service",      "road"};
  for (const char* v : kDrivable) {
    if (highway == v) return true;
  }
  return false;
}

bool isDrivableWay(const Tags& tags) {
  auto get = [&](const char* key) {
    auto it = tags.find(key);
    return it == tags.end() ? std::string() : it->second;
  };
  if (!isDrivableHighway(get("highway"))) return false;
  const std::string service = get("service");
  if (service == "parking_aisle" || service == "driveway") return false;
  if (get("area") == "yes") return false;
  if (get("access") == "no") return false;
  return true;
}

namespace {

Tags toTags(const osmium::TagList& list) {
  Tags tags;
  for (const osmium::Tag& t : list) tags.emplace(t.key(), t.value());
  return tags;
}

// Pass 1: drivable ways and turn restrictions.
class WayHandler : public osmium::handler::Handler {
 public:
  std::vector<Way> ways;
  std::vector<Restriction> restrictions;

  void way(const osmium::Way& w) {
    const char* highway = w.tags()["highway"];
    if (highway == nullptr || !isDrivableHighway(highway)) return;
    Tags tags = toTags(w.tags());
    if (!isDrivableWay(tags)) return;
    Way way;
    way.id = w.id();
    way.tags = std::move(tags);
    way.nodes.reserve(w.nodes().size());
    for (const osmium::NodeRef& n : w.nodes()) way.nodes.push_back(n.ref());
    ways.push_back(std::move(way));
  }

  void relation(const osmium::Relation& r) {
    const char* type = r.tags()["type"];
    if (type == nullptr || std::string(type) != "restriction") return;
    Restriction res;
    res.id = r.id();
    const char* value = r.tags()["restriction"];
    if (value == nullptr) value = r.tags()["restriction:motorcar"];
    if (value == nullptr) return;
    res.restriction = value;
    for (const osmium::RelationMember& m : r.members()) {
      const std::string role = m.role();
      if (role == "from" && m.type() == osmium::item_type::way) res.from_way = m.ref();
      if (role == "to" && m.type() == osmium::item_type::way) res.to_way = m.ref();
      if (role == "via" && m.type() == osmium::item_type::node) res.via_node = m.ref();
    }
    if (res.from_way != 0 && res.to_way != 0 && res.via_node != 0) restrictions.push_back(res);
  }
};

// Pass 2: the locations of the nodes the kept ways use.
class NodeHandler : public osmium::handler::Handler {
 public:
  explicit NodeHandler(const std::unordered_set<int64_t>& wanted) : wanted_(wanted) {}
  std::unordered_map<int64_t, Node> nodes;

  void node(const osmium::Node& n) {
    if (!wanted_.count(n.id())) return;
    const osmium::Location loc = n.location();
    if (!loc.valid()) return;  // no or out-of-range coordinates: treated as a missing node
    nodes[n.id()] = Node{n.id(), loc.lat(), loc.lon()};
  }

 private:
  const std::unordered_set<int64_t>& wanted_;
};

// Drops references to missing nodes and consecutive duplicates; returns false when the way is left
// with fewer than two distinct nodes.
bool cleanWayNodes(Way& way, const std::unordered_map<int64_t, Node>& nodes) {
  std::vector<int64_t> kept;
  kept.reserve(way.nodes.size());
  for (int64_t id : way.nodes) {
    if (!nodes.count(id)) continue;
    if (!kept.empty() && kept.back() == id) continue;
    kept.push_back(id);
  }
  way.nodes = std::move(kept);
  if (way.nodes.size() < 2) return false;
  if (way.nodes.size() == 2 && way.nodes.front() == way.nodes.back()) return false;
  return true;
}

Bounds boundsOfNodes(const std::unordered_map<int64_t, Node>& nodes) {
  Bounds b;
  b.min_lat = b.min_lon = std::numeric_limits<double>::infinity();
  b.max_lat = b.max_lon = -std::numeric_limits<double>::infinity();
  for (const auto& [id, n] : nodes) {
    b.min_lat = std::min(b.min_lat, n.lat);
    b.max_lat = std::max(b.max_lat, n.lat);
    b.min_lon = std::min(b.min_lon, n.lon);
    b.max_lon = std::max(b.max_lon, n.lon);
  }
  // A single point or a line: pad so that valid() holds and the centre is right.
  const double pad = 1e-6;
  if (!(b.max_lat > b.min_lat)) { b.min_lat -= pad; b.max_lat += pad; }
  if (!(b.max_lon > b.min_lon)) { b.min_lon -= pad; b.max_lon += pad; }
  return b;
}

}  // namespace

namespace {

namespace fs = std::filesystem;

// libosmium 2.18's PBF parser closes its file only when the whole parse succeeds
// (PBFParser::run): a corrupt .osm.pbf leaked one file descriptor per readOsm (found by
// fuzz/harness/osm_pbf.cc, which ran out of descriptors after ~25000 inputs). After a failed
// read, the descriptors open on this file that were not open before are closed. (Another thread
// opening the same file at the same moment would lose its descriptor: readOsm is a start-up call.)
std::set<int> descriptorsOn(const std::string& path) {
  std::set<int> fds;
  std::error_code ec;
  const fs::path target = fs::weakly_canonical(path, ec);
  if (ec) return fds;
  for (const auto& e : fs::directory_iterator("/proc/self/fd", ec)) {
    std::error_code link_ec;
    const fs::path link = fs::read_symlink(e.path(), link_ec);
    if (link_ec || link != target) continue;
    try {
      fds.insert(std::stoi(e.path().filename().string()));
    } catch (const std::exception&) {
    }
  }
  return fds;
}

void closeLeaked(const std::set<int>& before, const std::string& path) {
  for (int fd : descriptorsOn(path)) {
    if (!before.count(fd)) ::close(fd);
  }
}

}  // namespace

OsmData readOsm(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw OsmError("OSM file not found: '" + path + "'");
  if (fs::is_directory(path, ec)) throw OsmError("OSM path is a directory, not a file: '" + path + "'");
  if (fs::file_size(path, ec) == 0) throw OsmError("OSM file is empty: '" + path + "'");

  refuseExponentCoordinate<OsmError>(path, "cannot read OSM file '" + path + "'");  // libosmium overflows on it
  OsmData data;
  WayHandler ways;
  osmium::Box header_box;
  const std::set<int> open_before = descriptorsOn(path);
  try {
    osmium::io::File file{path};
    osmium::io::Reader reader{file, osmium::osm_entity_bits::way | osmium::osm_entity_bits::relation};
    header_box = reader.header().box();
    osmium::apply(reader, ways);
    reader.close();
  } catch (const std::exception& e) {
    closeLeaked(open_before, path);
    throw OsmError("cannot read OSM file '" + path + "': " + e.what());
  }
  if (ways.ways.empty()) {
    throw OsmError("OSM file '" + path + "' has no drivable highway way (highway=motorway ... "
                   "residential, service, *_link, living_street, road)");
  }

  std::unordered_set<int64_t> wanted;
  for (const Way& w : ways.ways) wanted.insert(w.nodes.begin(), w.nodes.end());
  NodeHandler nodes(wanted);
  try {
    osmium::io::File file{path};
    osmium::io::Reader reader{file, osmium::osm_entity_bits::node};
    osmium::apply(reader, nodes);
    reader.close();
  } catch (const std::exception& e) {
    closeLeaked(open_before, path);
    throw OsmError("cannot read the nodes of OSM file '" + path + "': " + e.what());
  }
  data.nodes = std::move(nodes.nodes);

  for (Way& w : ways.ways) {
    if (cleanWayNodes(w, data.nodes)) data.ways.push_back(std::move(w));
  }
  if (data.ways.empty()) {
    throw OsmError("OSM file '" + path + "' has drivable highway ways but none with two nodes "
                   "present in the file");
  }
  std::sort(data.ways.begin(), data.ways.end(), [](const Way& a, const Way& b) { return a.id < b.id; });

  // Keep only the nodes that the kept ways use.
  std::unordered_set<int64_t> used;
  for (const Way& w : data.ways) used.insert(w.nodes.begin(), w.nodes.end());
  for (auto it = data.nodes.begin(); it != data.nodes.end();) {
    it = used.count(it->first) ? std::next(it) : data.nodes.erase(it);
  }

  data.restrictions = std::move(ways.restrictions);
  std::sort(data.restrictions.begin(), data.restrictions.end(),
            [](const Restriction& a, const Restriction& b) { return a.id < b.id; });

  if (header_box.valid() && header_box.top_right().lat() > header_box.bottom_left().lat() &&
      header_box.top_right().lon() > header_box.bottom_left().lon()) {
    data.bounds.min_lat = header_box.bottom_left().lat();
    data.bounds.min_lon = header_box.bottom_left().lon();
    data.bounds.max_lat = header_box.top_right().lat();
    data.bounds.max_lon = header_box.top_right().lon();
  } else {
    data.bounds = boundsOfNodes(data.nodes);
  }
  return data;
}

}  // namespace lanemap::osm
