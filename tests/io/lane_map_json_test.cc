// core/io/lane_map_json.h: a LaneMap through JSON comes back bit for bit (what lets a sharded
// fusion give the map one process gives), every field included; bad files get the path named.
#include "core/io/atomic_file.h"
#include "core/io/lane_map_json.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace lt = lanemap::testing;
using namespace lanemap;

namespace {

// Coordinates no decimal text of a few digits holds exactly.
Eigen::Vector3d odd(double k) { return {std::nextafter(0.1 * k + 1e5 / 3.0, 1e9), -std::sqrt(2.0) * k, 1e-9 / (k + 3.0)}; }

map::LaneMap everyField() {
  map::LaneMap m;
  m.origin_lat = 37.80412345678901;
  m.origin_lon = -122.29876543210987;
  m.origin_alt = 3.0 / 7.0;
  for (int i = 0; i < 3; ++i) {
    map::LineString l;
    l.id = 100 + i;
    l.type = static_cast<map::LineType>(i * 2);  // dashed, solid_solid, virtual
    for (int k = 0; k < 4; ++k) l.points.push_back(odd(k + 10 * i));
    m.lines.push_back(l);
  }
  map::Lanelet a;
  a.id = 7;
  a.left_id = 100;
  a.right_id = 101;
  a.centre = {odd(1), odd(2), odd(3)};
  a.successors = {8, 9};
  a.road_id = 42;
  a.from_node = 123456789012;
  a.to_node = 987654321;
  a.index_from_left = 1;
  a.stop_line_id = 102;
  a.partial = map::PartialRoad{12.345678901234567, 99.9};
  a.confidence = 2.0 / 3.0;
  map::Lanelet b;
  b.id = 8;
  b.kind = map::LaneletKind::kIntersection;
  b.turn = map::TurnDirection::kLeft;
  b.intersection_id = 555;
  b.left_id = 101;
  b.right_id = 102;
  b.centre = {odd(4), odd(5)};
  m.lanelets = {a, b};
  map::RegulatoryElement r;
  r.id = 900;
  r.kind = map::RegulatoryKind::kTrafficLight;
  r.stop_line_id = 102;
  r.lanelets = {7};
  r.priority = {8};
  r.light = {odd(6), odd(7)};
  r.light_height_m = 1.1;
  r.light_estimated = false;
  r.osm_node = 31415;
  m.regulatory_elements = {r};
  map::Crosswalk c;
  c.id = 77;
  c.left = {odd(8), odd(9)};
  c.right = {odd(10), odd(11)};
  c.crossing = {7};
  c.road_id = 42;
  m.crosswalks = {c};
  return m;
}

void expectSame(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a[i][k], b[i][k]) << "point " << i << " coordinate " << k;  // exact
  }
}

}  // namespace

TEST(LaneMapJson, ARoundTripGivesTheSameMapBitForBit) {
  const map::LaneMap m = everyField();
  lt::TempDir tmp("lane-map-json");
  io::writeLaneMapJson(m, tmp.str("road.json"));
  const map::LaneMap r = io::readLaneMapJson(tmp.str("road.json"));
  EXPECT_EQ(r.origin_lat, m.origin_lat);
  EXPECT_EQ(r.origin_lon, m.origin_lon);
  EXPECT_EQ(r.origin_alt, m.origin_alt);
  ASSERT_EQ(r.lines.size(), m.lines.size());
  for (size_t i = 0; i < m.lines.size(); ++i) {
    EXPECT_EQ(r.lines[i].id, m.lines[i].id);
    EXPECT_EQ(r.lines[i].type, m.lines[i].type);
    expectSame(r.lines[i].points, m.lines[i].points);
  }
  ASSERT_EQ(r.lanelets.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const auto &x = r.lanelets[i], &y = m.lanelets[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.left_id, y.left_id);
    EXPECT_EQ(x.right_id, y.right_id);
    expectSame(x.centre, y.centre);
    EXPECT_EQ(x.successors, y.successors);
    EXPECT_EQ(x.turn, y.turn);
    EXPECT_EQ(x.road_id, y.road_id);
    EXPECT_EQ(x.from_node, y.from_node);
    EXPECT_EQ(x.to_node, y.to_node);
    EXPECT_EQ(x.intersection_id, y.intersection_id);
    EXPECT_EQ(x.index_from_left, y.index_from_left);
    EXPECT_EQ(x.stop_line_id, y.stop_line_id);
    EXPECT_EQ(x.partial.has_value(), y.partial.has_value());
    if (x.partial && y.partial) {
      EXPECT_EQ(x.partial->station_m, y.partial->station_m);
      EXPECT_EQ(x.partial->road_length_m, y.partial->road_length_m);
    }
    EXPECT_EQ(x.confidence, y.confidence);
  }
  ASSERT_EQ(r.regulatory_elements.size(), 1u);
  const auto &re = r.regulatory_elements[0], &me = m.regulatory_elements[0];
  EXPECT_EQ(re.id, me.id);
  EXPECT_EQ(re.kind, me.kind);
  EXPECT_EQ(re.stop_line_id, me.stop_line_id);
  EXPECT_EQ(re.lanelets, me.lanelets);
  EXPECT_EQ(re.priority, me.priority);
  expectSame(re.light, me.light);
  EXPECT_EQ(re.light_height_m, me.light_height_m);
  EXPECT_EQ(re.light_estimated, me.light_estimated);
  EXPECT_EQ(re.osm_node, me.osm_node);
  ASSERT_EQ(r.crosswalks.size(), 1u);
  EXPECT_EQ(r.crosswalks[0].id, 77);
  expectSame(r.crosswalks[0].left, m.crosswalks[0].left);
  expectSame(r.crosswalks[0].right, m.crosswalks[0].right);
  EXPECT_EQ(r.crosswalks[0].crossing, m.crosswalks[0].crossing);
  EXPECT_EQ(r.crosswalks[0].road_id, 42);
  // And the text of the map read back is the text written.
  EXPECT_EQ(io::laneMapToJson(r).dump(), io::laneMapToJson(m).dump());
}

TEST(LaneMapJson, AFileThatIsNotOneIsRefusedWithItsPath) {
  lt::TempDir tmp("lane-map-json-bad");
  std::ofstream(tmp.str("a.json")) << "{\"lanemap_lane_map_json\": 1, \"origin\": [1, 2, 3], \"lines\": [{\"id\": 1}]}";
  std::ofstream(tmp.str("b.json")) << "not json";
  std::ofstream(tmp.str("c.json")) << "{\"lines\": []}";
  for (const char* f : {"a.json", "b.json", "c.json", "missing.json"}) {
    try {
      io::readLaneMapJson(tmp.str(f));
      ADD_FAILURE() << f << " was read";
    } catch (const io::IoError& e) {
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
  }
}
