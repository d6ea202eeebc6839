// LANE_MAP conversion (processes/framework/lane_map_message.h): what the lane mapper publishes the
// viewer reads back: lanes, centre lines, bound geometry and types, successors, each lane's
// confidence and a partial road's stop station.
#include "processes/framework/lane_map_message.h"

#include "core/osm/osm_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace lanemap {
namespace {

map::LineString line(int64_t id, map::LineType type, std::vector<Eigen::Vector3d> pts) {
  map::LineString l;
  l.id = id;
  l.type = type;
  l.points = std::move(pts);
  return l;
}

// West Oakland's skeleton, built once for the file's tests (fromMessage takes a road's nodes from it).
const skeleton::Skeleton& westOakland() {
  static const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  return sk;
}

// Two lanes of a 50 m road between a curb, a dashed line and a double solid line.
map::LaneMap twoLanes() {
  map::LaneMap m;
  m.origin_lat = 37.8;
  m.origin_lon = -122.3;
  m.origin_alt = 4.0;
  m.lines = {line(1, map::LineType::kCurb, {{0, 0, 0}, {50, 0, 0.5}}),
             line(2, map::LineType::kDashed, {{0, 3.5, 0}, {25, 3.5, 0.2}, {50, 3.5, 0.5}}),
             line(3, map::LineType::kSolidSolid, {{0, 7, 0}, {50, 7, 0.5}})};
  map::Lanelet a;
  a.id = 500001;
  a.right_id = 1;
  a.left_id = 2;
  a.centre = {{0, 1.75, 0}, {50, 1.75, 0.5}};
  a.index_from_left = 1;
  a.successors = {900001, 900002};
  map::Lanelet b = a;
  b.id = 500002;
  b.right_id = 2;
  b.left_id = 3;
  b.centre = {{0, 5.25, 0}, {50, 5.25, 0.5}};
  b.index_from_left = 0;
  b.successors = {};
  m.lanelets = {a, b};
  return m;
}

TEST(LaneMapMessage, ALaneMapGoesOverTheBusAndBack) {
  const map::LaneMap m = twoLanes();

  const lane_map_t msg = toMessage(7, m, 123456, "/store/lane_map.osm");
  EXPECT_EQ(msg.id, 7);
  EXPECT_EQ(msg.utime, 123456);
  EXPECT_EQ(msg.num_lanes, 2);
  EXPECT_EQ(msg.map_path, "/store/lane_map.osm");
  EXPECT_EQ(msg.lanes[0].left_boundary.type, +polyline_t::TYPE_DASHED);
  EXPECT_EQ(msg.lanes[0].right_boundary.type, +polyline_t::TYPE_CURB);
  EXPECT_EQ(msg.lanes[1].left_boundary.type, +polyline_t::TYPE_SOLID);  // the message has no double solid

  const skeleton::Skeleton& sk = westOakland();
  const auto* road = sk.road(7);
  ASSERT_NE(road, nullptr);
  const map::LaneMap back = fromMessage(msg, sk);
  EXPECT_EQ(back.origin_alt, 4.0);
  ASSERT_EQ(back.lanelets.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const auto& in = m.lanelets[i];
    const auto& out = back.lanelets[i];
    EXPECT_EQ(out.id, in.id);
    EXPECT_EQ(out.road_id, 7);
    EXPECT_EQ(out.from_node, road->from);
    EXPECT_EQ(out.to_node, road->to);
    EXPECT_EQ(out.index_from_left, in.index_from_left);
    EXPECT_EQ(out.successors, in.successors);
    ASSERT_EQ(out.centre.size(), in.centre.size());
    EXPECT_TRUE(out.centre.back().isApprox(in.centre.back()));
    const auto* l = back.line(out.left_id);
    const auto* r = back.line(out.right_id);
    ASSERT_TRUE(l && r);
    EXPECT_EQ(l->points.size(), m.line(in.left_id)->points.size());
    EXPECT_TRUE(r->points.front().isApprox(m.line(in.right_id)->points.front()));
  }
  EXPECT_EQ(back.line(back.lanelets[0].left_id)->type, map::LineType::kDashed);
  EXPECT_EQ(back.line(back.lanelets[0].right_id)->type, map::LineType::kCurb);
  EXPECT_EQ(back.line(back.lanelets[1].left_id)->type, map::LineType::kSolid);
  // The two lanes' shared bound comes back as two line strings, with ids of their own.
  EXPECT_NE(back.lanelets[0].left_id, back.lanelets[1].right_id);

  // A hostile count: the arrays decide.
  lane_map_t bad = msg;
  bad.lanes[0].centre.num_points = 1000;
  EXPECT_EQ(fromMessage(bad, sk).lanelets[0].centre.size(), 2u);
  // A map that says neither confidence nor partial: -1 on the bus, none back.
  EXPECT_EQ(msg.lanes[0].confidence, -1.0);
  EXPECT_EQ(msg.partial_station_m, -1.0);
  EXPECT_FALSE(back.lanelets[0].confidence.has_value());
  EXPECT_FALSE(back.lanelets[0].partial.has_value());
}

// The lane mapper's per-lane confidence and a road mapped as far as driven reach the viewer.
TEST(LaneMapMessage, ConfidenceAndPartialRoadGoOverTheBus) {
  map::LaneMap m = twoLanes();
  m.lanelets[0].confidence = 0.86;
  m.lanelets[1].confidence = 0.33;
  for (auto& ll : m.lanelets) ll.partial = map::PartialRoad{31.5, 120.0};

  const lane_map_t msg = toMessage(7, m, 1, "");
  EXPECT_DOUBLE_EQ(msg.partial_station_m, 31.5);
  EXPECT_DOUBLE_EQ(msg.partial_road_length_m, 120.0);
  // Through the wire format, as the viewer gets it.
  std::vector<uint8_t> wire(msg.getEncodedSize());
  ASSERT_EQ(msg.encode(wire.data(), 0, static_cast<int>(wire.size())), static_cast<int>(wire.size()));
  lane_map_t got;
  ASSERT_EQ(got.decode(wire.data(), 0, static_cast<int>(wire.size())), static_cast<int>(wire.size()));

  const skeleton::Skeleton& sk = westOakland();
  const map::LaneMap back = fromMessage(got, sk);
  ASSERT_EQ(back.lanelets.size(), 2u);
  ASSERT_TRUE(back.lanelets[0].confidence && back.lanelets[1].confidence);
  EXPECT_DOUBLE_EQ(*back.lanelets[0].confidence, 0.86);
  EXPECT_DOUBLE_EQ(*back.lanelets[1].confidence, 0.33);
  for (const auto& ll : back.lanelets) {
    ASSERT_TRUE(ll.partial.has_value());
    EXPECT_DOUBLE_EQ(ll.partial->station_m, 31.5);
    EXPECT_DOUBLE_EQ(ll.partial->road_length_m, 120.0);
  }
  // Out of range on the bus: clamped to 1; NaN is none.
  lane_map_t odd = got;
  odd.lanes[0].confidence = 1.7;
  odd.lanes[1].confidence = std::nan("");
  const map::LaneMap clamped = fromMessage(odd, sk);
  EXPECT_DOUBLE_EQ(*clamped.lanelets[0].confidence, 1.0);
  EXPECT_FALSE(clamped.lanelets[1].confidence.has_value());
}

}  // namespace
}  // namespace lanemap
