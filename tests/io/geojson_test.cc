// Tests of the GeoJSON export (core/io/geojson.h): valid JSON with the expected features,
// properties and WGS84 positions, written atomically, clear error for a bad path.
#include "core/io/geojson.h"
#include "tests/common/temp_dir.h"

#include "core/geo/local_frame.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace lanemap::io {
namespace {

using map::LaneletKind;
using map::LaneMap;
using map::LineType;
using nlohmann::json;

// The file's scratch folder (tests/common/temp_dir.h), made on first use and removed at exit.
const lanemap::testing::TempDir& scratch() {
  static const lanemap::testing::TempDir dir("io-geojson");
  return dir;
}
std::filesystem::path tempDir() { return scratch().path(); }

map::LineString line(int64_t id, LineType type, std::vector<Eigen::Vector3d> pts) {
  map::LineString l;
  l.id = id;
  l.type = type;
  l.points = std::move(pts);
  return l;
}

// Two northbound lanes sharing line 2 (lanelets 10, 11), an intersection lanelet 12 after 10,
// a stop line 5 at the end of lanelet 11.
LaneMap smallMap() {
  LaneMap m;
  m.origin_lat = 37.8;
  m.origin_lon = -122.3;
  m.origin_alt = 10.0;
  m.lines.push_back(line(1, LineType::kSolidSolid, {{-3.5, 0, 0}, {-3.5, 40, 0}}));
  m.lines.push_back(line(2, LineType::kDashed, {{0, 0, 0}, {0, 20, 0}, {0, 40, 0}}));
  m.lines.push_back(line(3, LineType::kCurb, {{3.5, 0, 0}, {3.5, 40, 0}}));
  m.lines.push_back(line(4, LineType::kVirtual, {{-3.5, 40, 0}, {-3.5, 55, 0}}));
  m.lines.push_back(line(6, LineType::kVirtual, {{0, 40, 0}, {0, 55, 0}}));
  m.lines.push_back(line(5, LineType::kStopLine, {{0, 40, 0}, {3.5, 40, 0}}));
  map::Lanelet a;
  a.id = 10;
  a.left_id = 1;
  a.right_id = 2;
  a.centre = {{-1.75, 0, 0}, {-1.75, 40, 0}};
  a.successors = {12};
  a.road_id = 3;
  a.index_from_left = 0;
  map::Lanelet b = a;
  b.id = 11;
  b.left_id = 2;
  b.right_id = 3;
  b.centre = {{1.75, 0, 0}, {1.75, 40, 0}};
  b.successors = {};
  b.index_from_left = 1;
  b.stop_line_id = 5;
  map::Lanelet c;
  c.id = 12;
  c.kind = LaneletKind::kIntersection;
  c.turn = map::TurnDirection::kStraight;
  c.left_id = 4;
  c.right_id = 6;
  c.intersection_id = 77;
  c.centre = {{-1.75, 40, 0}, {-1.75, 55, 0}};
  m.lanelets = {a, b, c};
  return m;
}

TEST(GeoJson, FeaturesPropertiesAndPositions) {
  const LaneMap m = smallMap();
  std::filesystem::create_directories(tempDir());
  const std::string path = (tempDir() / "map.geojson").string();
  writeGeoJson(m, path);
  std::ifstream in(path);
  const json j = json::parse(in);  // throws (fails the test) when not valid JSON

  EXPECT_EQ(j.at("type"), "FeatureCollection");
  const json& features = j.at("features");
  // 3 lanelet polygons + 3 centre lines + 6 boundaries.
  ASSERT_EQ(features.size(), 12u);
  std::map<std::string, int> per_kind;
  for (const auto& f : features) {
    EXPECT_EQ(f.at("type"), "Feature");
    ++per_kind[f.at("properties").at("feature").get<std::string>()];
  }
  EXPECT_EQ(per_kind["lanelet"], 3);
  EXPECT_EQ(per_kind["centre_line"], 3);
  EXPECT_EQ(per_kind["boundary"], 6);

  const json& first = features[0];
  EXPECT_EQ(first.at("geometry").at("type"), "Polygon");
  const auto& props = first.at("properties");
  EXPECT_EQ(props.at("id"), 10);
  EXPECT_EQ(props.at("kind"), "road");
  EXPECT_EQ(props.at("road_id"), 3);
  EXPECT_EQ(props.at("index_from_left"), 0);
  EXPECT_EQ(props.at("successors"), json::array({12}));
  EXPECT_TRUE(props.at("stop_line_id").is_null());
  EXPECT_EQ(features[1].at("properties").at("stop_line_id"), 5);
  EXPECT_EQ(features[2].at("properties").at("kind"), "intersection");
  EXPECT_EQ(features[2].at("properties").at("turn"), "straight");
  EXPECT_EQ(features[2].at("properties").at("intersection_id"), 77);

  // Ring of lanelet 10: 2 left + 3 right points + closing point, counter-clockwise in lon/lat.
  const json& ring = first.at("geometry").at("coordinates").at(0);
  ASSERT_EQ(ring.size(), 6u);
  EXPECT_EQ(ring.front(), ring.back());
  double area2 = 0.0;
  for (size_t i = 0; i + 1 < ring.size(); ++i) {
    area2 += ring[i][0].get<double>() * ring[i + 1][1].get<double>() -
             ring[i + 1][0].get<double>() * ring[i][1].get<double>();
  }
  EXPECT_GT(area2, 0.0);
  // Positions are [lon, lat, ele]; compare with GeographicLib directly. 1e-8 degrees is ~1 mm,
  // above the 1e-9 rounding.
  const geo::LocalFrame frame({m.origin_lat, m.origin_lon, m.origin_alt});
  const json& centre = features[3];
  EXPECT_EQ(centre.at("properties").at("feature"), "centre_line");
  EXPECT_EQ(centre.at("properties").at("lanelet"), 10);
  const geo::LatLonAlt end = frame.toWgs84(Eigen::Vector3d(-1.75, 40, 0));
  const json& last = centre.at("geometry").at("coordinates").back();
  EXPECT_NEAR(last[0].get<double>(), end.lon, 1e-8);
  EXPECT_NEAR(last[1].get<double>(), end.lat, 1e-8);
  EXPECT_NEAR(last[2].get<double>(), 10.0, 1e-4);
  // Boundaries keep their type.
  EXPECT_EQ(features[6].at("properties").at("type"), "solid_solid");
  EXPECT_EQ(features[7].at("properties").at("type"), "dashed");
  EXPECT_EQ(features[7].at("geometry").at("coordinates").size(), 3u);
  EXPECT_EQ(features[11].at("properties").at("type"), "stop_line");
  EXPECT_EQ(j.at("lanemap_origin").at("lat"), 37.8);
}

TEST(GeoJson, RegulatoryElementsAndCrosswalks) {
  LaneMap m = smallMap();
  map::RegulatoryElement stop;
  stop.id = 900;
  stop.kind = map::RegulatoryKind::kStopSign;
  stop.stop_line_id = 5;
  stop.lanelets = {11};
  stop.osm_node = 4242;
  map::RegulatoryElement light = stop;
  light.id = 901;
  light.kind = map::RegulatoryKind::kTrafficLight;
  light.light = {{0, 41, 3}, {0.5, 41, 3}};
  light.osm_node = -1;
  map::RegulatoryElement dangling = stop;  // its stop line is not in the map: not written
  dangling.id = 902;
  dangling.stop_line_id = 999;
  m.regulatory_elements = {stop, light, dangling};
  map::Crosswalk cw;
  cw.id = 950;
  cw.left = {{0, 30, 0}, {3.5, 30, 0}};   // the walker's left edge, from one curb to the other
  cw.right = {{0, 27, 0}, {3.5, 27, 0}};
  cw.crossing = {10, 11};
  cw.road_id = 3;
  m.crosswalks = {cw};
  const json j = toGeoJson(m);
  std::vector<json> rules, crossings;
  for (const auto& f : j.at("features")) {
    const std::string kind = f.at("properties").at("feature");
    if (kind == "regulatory_element") rules.push_back(f);
    if (kind == "crosswalk") crossings.push_back(f);
  }
  ASSERT_EQ(rules.size(), 2u);
  EXPECT_EQ(rules[0].at("properties").at("id"), 900);
  EXPECT_EQ(rules[0].at("properties").at("kind"), "stop_sign");
  EXPECT_EQ(rules[0].at("properties").at("stop_line_id"), 5);
  EXPECT_EQ(rules[0].at("properties").at("lanelets"), json::array({11}));
  EXPECT_EQ(rules[0].at("properties").at("osm_node"), 4242);
  EXPECT_EQ(rules[0].at("geometry").at("type"), "MultiLineString");
  EXPECT_EQ(rules[0].at("geometry").at("coordinates").size(), 1u);  // the stop line
  EXPECT_EQ(rules[1].at("properties").at("kind"), "traffic_light");
  EXPECT_TRUE(rules[1].at("properties").at("osm_node").is_null());
  EXPECT_EQ(rules[1].at("properties").at("light_estimated"), true);
  ASSERT_EQ(rules[1].at("geometry").at("coordinates").size(), 2u);  // stop line, light
  const geo::LocalFrame frame({m.origin_lat, m.origin_lon, m.origin_alt});
  const auto light_end = frame.toWgs84(Eigen::Vector3d(0.5, 41, 3));
  EXPECT_NEAR(rules[1].at("geometry").at("coordinates")[1][1][1].get<double>(), light_end.lat, 1e-8);
  ASSERT_EQ(crossings.size(), 1u);
  EXPECT_EQ(crossings[0].at("properties").at("crossing"), json::array({10, 11}));
  EXPECT_EQ(crossings[0].at("properties").at("road_id"), 3);
  const json& ring = crossings[0].at("geometry").at("coordinates").at(0);
  ASSERT_EQ(ring.size(), 5u);  // four corners, closed
  EXPECT_EQ(ring.front(), ring.back());
  double area2 = 0.0;  // counter-clockwise, 3.5 m x 3 m
  for (size_t i = 0; i + 1 < ring.size(); ++i) {
    const auto a = frame.toEnu(ring[i][1].get<double>(), ring[i][0].get<double>());
    const auto b = frame.toEnu(ring[i + 1][1].get<double>(), ring[i + 1][0].get<double>());
    area2 += a.x() * b.y() - b.x() * a.y();
  }
  EXPECT_NEAR(area2 / 2, 10.5, 0.01);
}

TEST(GeoJson, EmptyMapIsAnEmptyCollection) {
  const json j = toGeoJson(LaneMap{});
  EXPECT_EQ(j.at("type"), "FeatureCollection");
  EXPECT_TRUE(j.at("features").empty());
}

TEST(GeoJson, UnwritablePathThrowsWithPath) {
  const std::string path = (tempDir() / "no_such_folder" / "map.geojson").string();
  try {
    writeGeoJson(smallMap(), path);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lanemap::io
