// Road-level OpenStreetMap data as lanemap needs it: drivable ways with their tags, their nodes,
// and turn restrictions. Read with libosmium (XML .osm, .osm.pbf, ...).
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace lanemap::osm {

using Tags = std::map<std::string, std::string>;

struct Node {
  int64_t id = 0;
  double lat = 0.0;
  double lon = 0.0;
};

struct Way {
  int64_t id = 0;
  std::vector<int64_t> nodes;
  Tags tags;
  std::string tag(const std::string& key, const std::string& fallback = "") const;
};

struct Restriction {  // type=restriction relation
  int64_t id = 0;
  std::string restriction;  // e.g. no_left_turn, only_straight_on
  int64_t from_way = 0;
  int64_t via_node = 0;
  int64_t to_way = 0;
  bool prohibitive() const { return restriction.rfind("no_", 0) == 0; }  // no_*: this turn is forbidden
  bool mandatory() const { return restriction.rfind("only_", 0) == 0; }  // only_*: every other turn is
};

struct Bounds {
  double min_lat = 0.0, min_lon = 0.0, max_lat = 0.0, max_lon = 0.0;
  bool valid() const { return max_lat > min_lat && max_lon > min_lon; }
};

struct OsmData {
  std::unordered_map<int64_t, Node> nodes;  // only nodes used by the ways below
  std::vector<Way> ways;                     // drivable highway ways, sorted by id
  std::vector<Restriction> restrictions;
  Bounds bounds;                             // from the file's header, else from the nodes
};

class OsmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// True for highway=* values a car may drive on (motorway ... residential, service, *_link, ...).
bool isDrivableHighway(const std::string& highway);

// True for a way lanemap keeps: a drivable highway value, and not service=parking_aisle|driveway,
// area=yes or access=no (see osm_data.cc for the reasons).
bool isDrivableWay(const Tags& tags);

// Reads the drivable ways of an OSM file. Throws OsmError with a clear message for a missing,
// unreadable or malformed file, and for a file with no drivable way.
OsmData readOsm(const std::string& path);

}  // namespace lanemap::osm
