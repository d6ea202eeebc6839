// Tests of the road-level OSM writer (core/io/road_osm_writer.h): lane tags are dropped (or kept
// on request), ways, nodes, restrictions and bounds survive, and libosmium / `osmium fileinfo`
// read the file back.
#include "core/io/road_osm_writer.h"
#include "tests/common/temp_dir.h"
#include "core/intersections/regulatory.h"

#include <gtest/gtest.h>

#include <osmium/handler.hpp>
#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/relation.hpp>
#include <osmium/osm/way.hpp>
#include <osmium/visitor.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace lanemap::io {
namespace {

// The file's scratch folder (tests/common/temp_dir.h), made on first use and removed at exit.
const lanemap::testing::TempDir& scratch() {
  static const lanemap::testing::TempDir dir("io-road-osm");
  return dir;
}
std::string tempPath(const std::string& name) { return scratch().str(name); }

// Everything libosmium reads from a file.
struct Loaded : osmium::handler::Handler {
  std::map<int64_t, std::pair<double, double>> nodes;
  std::map<int64_t, std::vector<int64_t>> way_nodes;
  std::map<int64_t, osm::Tags> way_tags;
  std::map<int64_t, osm::Tags> relation_tags;
  std::map<int64_t, std::vector<std::string>> relation_members;  // "w:123:from"
  osmium::Box box;
  void node(const osmium::Node& n) { nodes[n.id()] = {n.location().lat(), n.location().lon()}; }
  void way(const osmium::Way& w) {
    for (const auto& nr : w.nodes()) way_nodes[w.id()].push_back(nr.ref());
    for (const auto& t : w.tags()) way_tags[w.id()][t.key()] = t.value();
  }
  void relation(const osmium::Relation& r) {
    for (const auto& t : r.tags()) relation_tags[r.id()][t.key()] = t.value();
    for (const auto& m : r.members()) {
      relation_members[r.id()].push_back(std::string(m.type() == osmium::item_type::way ? "w" : "n") +
                                         ":" + std::to_string(m.ref()) + ":" + m.role());
    }
  }
};

Loaded load(const std::string& path) {
  Loaded l;
  osmium::io::Reader reader{osmium::io::File{path, "osm"}};
  l.box = reader.header().box();
  osmium::apply(reader, l);
  reader.close();
  return l;
}

// A junction of a two-lane primary road (way 10, west-east, with lane tags) and a residential
// road (way 20, north), with a no_left_turn restriction.
osm::OsmData junction() {
  osm::OsmData d;
  d.nodes[1] = {1, 37.8000000, -122.3000000};
  d.nodes[2] = {2, 37.8000000, -122.2990000};
  d.nodes[3] = {3, 37.8000000, -122.2980000};
  d.nodes[4] = {4, 37.8010000, -122.2990000};
  d.nodes[99] = {99, 37.9, -122.1};  // unused by any way: not written
  osm::Way main;
  main.id = 10;
  main.nodes = {1, 2, 3};
  main.tags = {{"highway", "primary"}, {"name", "Peralta & <Main>"}, {"lanes", "2"},
               {"lanes:forward", "1"}, {"turn:lanes:forward", "left|through"}, {"width", "7"},
               {"placement:forward", "right_of:1"}, {"oneway", "no"}, {"maxspeed", "40"},
               {"width:lanes", "3.5|3.5"}};
  osm::Way side;
  side.id = 20;
  side.nodes = {2, 4};
  side.tags = {{"highway", "residential"}, {"oneway", "yes"}};
  d.ways = {side, main};  // out of order on purpose: the file is sorted
  d.restrictions.push_back({500, "no_left_turn", 10, 2, 20});
  d.bounds = {37.79, -122.31, 37.81, -122.29};
  return d;
}

TEST(RoadOsmWriter, LaneTagClassification) {
  for (const char* k : {"lanes", "lanes:forward", "lanes:backward", "turn:lanes", "turn:lanes:forward",
                        "width", "width:lanes", "placement", "placement:backward", "change:lanes"}) {
    EXPECT_TRUE(isLaneTag(k)) << k;
  }
  for (const char* k : {"highway", "oneway", "name", "maxspeed", "junction", "lanesville", "ref"}) {
    EXPECT_FALSE(isLaneTag(k)) << k;
  }
}

TEST(RoadOsmWriter, DropsLaneTagsKeepsWaysNodesRestrictionsBounds) {
  const std::string path = tempPath("junction.osm");
  writeRoadOsm(junction(), path);
  const Loaded l = load(path);
  ASSERT_EQ(l.way_nodes.size(), 2u);
  EXPECT_EQ(l.way_nodes.at(10), (std::vector<int64_t>{1, 2, 3}));
  EXPECT_EQ(l.way_nodes.at(20), (std::vector<int64_t>{2, 4}));
  EXPECT_EQ(l.nodes.size(), 4u);  // node 99 is used by no way
  EXPECT_NEAR(l.nodes.at(4).first, 37.801, 1e-7);
  EXPECT_NEAR(l.nodes.at(4).second, -122.299, 1e-7);
  const osm::Tags expected_main{{"highway", "primary"}, {"name", "Peralta & <Main>"},
                                {"oneway", "no"}, {"maxspeed", "40"}};
  EXPECT_EQ(l.way_tags.at(10), expected_main);
  EXPECT_EQ(l.way_tags.at(20), (osm::Tags{{"highway", "residential"}, {"oneway", "yes"}}));
  ASSERT_EQ(l.relation_tags.size(), 1u);
  EXPECT_EQ(l.relation_tags.at(500), (osm::Tags{{"type", "restriction"}, {"restriction", "no_left_turn"}}));
  EXPECT_EQ(l.relation_members.at(500), (std::vector<std::string>{"w:10:from", "n:2:via", "w:20:to"}));
  ASSERT_TRUE(l.box.valid());
  EXPECT_NEAR(l.box.bottom_left().lat(), 37.79, 1e-7);
  EXPECT_NEAR(l.box.top_right().lon(), -122.29, 1e-7);
}

TEST(RoadOsmWriter, KeepsLaneTagsOnRequest) {
  const std::string path = tempPath("junction_lanes.osm");
  RoadOsmOptions keep;
  keep.keep_lane_tags = true;
  writeRoadOsm(junction(), path, keep);
  const Loaded l = load(path);
  EXPECT_EQ(l.way_tags.at(10), junction().ways[1].tags);
}

TEST(RoadOsmWriter, BoundsFromNodesWhenDataHasNone) {
  osm::OsmData d = junction();
  d.bounds = {};
  const std::string xml = toRoadOsmXml(d);
  EXPECT_NE(xml.find("<bounds minlat=\"37.8000000\" minlon=\"-122.3000000\" maxlat=\"37.8010000\" "
                     "maxlon=\"-122.2980000\"/>"),
            std::string::npos)
      << xml;
}

TEST(RoadOsmWriter, MissingNodeThrowsWithPath) {
  osm::OsmData d = junction();
  d.ways[0].nodes.push_back(12345);
  const std::string path = tempPath("broken.osm");
  try {
    writeRoadOsm(d, path);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("12345"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

// Real data: the highway ways of West Oakland, read with libosmium into OsmData, written, read
// back. Counts from the file itself:
//   awk '/<way /{w=1;h=0} w&&/k="highway"/{h=1} /<\/way>/{if(h)n++; w=0} END{print n}' FILE
//     -> 31 ways with a highway tag (grep -c 'k="highway"' says 38: 7 are nodes, signals/stops)
//   awk '/<way /{w=1} w&&(/k="lanes"/||/k="turn:lanes"/){n++} /<\/way>/{w=0} END{print n}' FILE
//     -> 5 lane tags on ways (3 lanes + 2 turn:lanes), the only lane tags in the file
struct HighwayCollector : osmium::handler::Handler {
  osm::OsmData data;
  std::map<int64_t, osm::Node> all_nodes;
  void node(const osmium::Node& n) { all_nodes[n.id()] = {n.id(), n.location().lat(), n.location().lon()}; }
  void way(const osmium::Way& w) {
    if (!w.tags().has_key("highway")) return;
    osm::Way out;
    out.id = w.id();
    for (const auto& nr : w.nodes()) out.nodes.push_back(nr.ref());
    for (const auto& t : w.tags()) out.tags[t.key()] = t.value();
    data.ways.push_back(std::move(out));
  }
};

TEST(RoadOsmWriter, KeepsTheJunctionControlsOfItsNodes) {
  // West Oakland's highway=stop / traffic_signals nodes survive into the road-level file (the
  // lane mapper reads its regulatory elements from there).
  const std::string src = std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm";
  const osm::OsmData data = osm::readOsm(src);
  const auto controls = intersections::readControlNodes(src);
  RoadOsmOptions o;
  size_t used = 0;
  for (const auto& [id, c] : controls) {
    if (!data.nodes.count(id)) continue;  // not on a drivable way: not in the file
    ++used;
    o.node_tags[id]["highway"] = intersections::toString(c.control);
  }
  ASSERT_GT(used, 0u);
  const std::string path = tempPath("west_oakland_controls.osm");
  writeRoadOsm(data, path, o);
  const auto back = intersections::readControlNodes(path);
  EXPECT_EQ(back.size(), used);
  for (const auto& [id, c] : back) {
    ASSERT_TRUE(controls.count(id)) << id;
    EXPECT_EQ(c.control, controls.at(id).control) << id;
    EXPECT_NEAR(c.lat, controls.at(id).lat, 1e-7) << id;
  }
  // Without node_tags the nodes carry none.
  writeRoadOsm(data, path);
  EXPECT_TRUE(intersections::readControlNodes(path).empty());
}

TEST(RoadOsmWriter, WestOaklandRoundTripAndOsmiumFileinfo) {
  HighwayCollector c;
  osmium::io::Reader reader{osmium::io::File{std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"}};
  osmium::apply(reader, c);
  reader.close();
  ASSERT_EQ(c.data.ways.size(), 31u);
  size_t lane_tags = 0;
  for (const auto& w : c.data.ways) {
    for (const auto& n : w.nodes) c.data.nodes[n] = c.all_nodes.at(n);
    for (const auto& [k, v] : w.tags) lane_tags += isLaneTag(k);
  }
  EXPECT_EQ(lane_tags, 5u);

  const std::string path = tempPath("west_oakland_roads.osm");
  writeRoadOsm(c.data, path);
  const Loaded l = load(path);
  EXPECT_EQ(l.way_nodes.size(), 31u);
  EXPECT_EQ(l.nodes.size(), c.data.nodes.size());
  size_t tags_left = 0, lane_tags_left = 0;
  for (const auto& [id, tags] : l.way_tags) {
    for (const auto& [k, v] : tags) {
      ++tags_left;
      lane_tags_left += isLaneTag(k);
    }
  }
  EXPECT_EQ(lane_tags_left, 0u);
  size_t tags_before = 0;
  for (const auto& w : c.data.ways) tags_before += w.tags.size();
  EXPECT_EQ(tags_left, tags_before - 5u);
  for (const auto& w : c.data.ways) EXPECT_EQ(l.way_nodes.at(w.id), w.nodes) << w.id;

  // The osmium command-line tool accepts the file too (skipped where it is not installed).
  if (std::filesystem::exists("/usr/bin/osmium")) {
    const std::string out = tempPath("fileinfo.txt");
    const std::string cmd = "/usr/bin/osmium fileinfo -e -g data.count.ways '" + path + "' > '" + out + "' 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(out);
    std::string count;
    std::getline(in, count);
    EXPECT_EQ(count, "31");
  }
}

}  // namespace
}  // namespace lanemap::io
