// A partial road's lanelets (issue 14: mapped as far as a drive went) and the per-lane confidence
// go into the Lanelet2 sidecar and the GeoJSON properties, not into tags of the OSM file, and
// readLanelet2 reads them back.
#include "core/io/geojson.h"
#include "core/io/lanelet2.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"
#include "tests/eval/test_maps.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace {

TEST(PartialMetadata, SidecarAndGeoJsonCarryPartialAndConfidenceAndTheReaderReadsThemBack) {
  lanemap::testing::MapBuilder b;
  const int64_t done = b.lane(lanemap::testing::straight({0, 0}, {50, 0}), 1);
  const int64_t part = b.lane(lanemap::testing::straight({60, 0}, {90, 0}), 2);
  b.m.origin_lat = 37.8;
  b.m.origin_lon = -122.3;
  for (auto& ll : b.m.lanelets) {
    if (ll.id == done) ll.confidence = 0.875;
    if (ll.id == part) {
      ll.partial = lanemap::map::PartialRoad{31.25, 120.5};
      ll.confidence = 0.25;
    }
  }
  lanemap::testing::TempDir dir("partial-metadata");
  const std::string path = dir.str("map.osm");
  lanemap::io::writeLanelet2(b.m, path);
  const std::string xml = lanemap::testing::readFile(path);
  EXPECT_EQ(xml.find("partial"), std::string::npos) << "not a tag of the OSM file";
  EXPECT_EQ(xml.find("confidence"), std::string::npos);

  const auto back = lanemap::io::readLanelet2(path, 37.8, -122.3);
  ASSERT_EQ(back.lanelets.size(), 2u);
  for (const auto& ll : back.lanelets) {
    ASSERT_TRUE(ll.confidence.has_value()) << ll.id;
    if (ll.road_id == 2) {
      ASSERT_TRUE(ll.partial.has_value());
      EXPECT_DOUBLE_EQ(ll.partial->station_m, 31.25);
      EXPECT_DOUBLE_EQ(ll.partial->road_length_m, 120.5);
      EXPECT_DOUBLE_EQ(*ll.confidence, 0.25);
    } else {
      EXPECT_FALSE(ll.partial.has_value());
      EXPECT_DOUBLE_EQ(*ll.confidence, 0.875);
    }
  }

  const auto g = lanemap::io::toGeoJson(b.m);
  int lanelets = 0, centres = 0;
  for (const auto& f : g["features"]) {
    const auto& p = f["properties"];
    if (p["feature"] != "lanelet" && p["feature"] != "centre_line") continue;
    (p["feature"] == "lanelet" ? lanelets : centres)++;
    if (p["road_id"] == 2) {
      EXPECT_EQ(p["partial"], true);
      EXPECT_DOUBLE_EQ(p["partial_station_m"].get<double>(), 31.25);
      EXPECT_DOUBLE_EQ(p["road_length_m"].get<double>(), 120.5);
      EXPECT_DOUBLE_EQ(p["confidence"].get<double>(), 0.25);
    } else {
      EXPECT_EQ(p["partial"], false);
      EXPECT_TRUE(p["partial_station_m"].is_null());
      EXPECT_TRUE(p["road_length_m"].is_null());
      EXPECT_DOUBLE_EQ(p["confidence"].get<double>(), 0.875);
    }
  }
  EXPECT_EQ(lanelets, 2);
  EXPECT_EQ(centres, 2);
}

}  // namespace
