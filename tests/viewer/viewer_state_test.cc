// core/viewer/viewer_state.h on the West Oakland skeleton: coverage of the OSM roads (never driven
// -> driven -> mapped) in the skeleton GeoJSON and the state, a road's lanes in the GeoJSON and
// the Lanelet2 download (counts, ids, positions in WGS84), lanes given in another ENU origin, the
// trail's spacing, cap and paging, the BEV picture (size, transparency, bounds), and when the
// status panel calls a process behind.
#include "core/io/lanelet2.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "core/viewer/viewer_state.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <memory>

namespace {

using namespace lanemap;
using nlohmann::json;

std::shared_ptr<const skeleton::Skeleton> westOakland() {
  static std::shared_ptr<const skeleton::Skeleton> sk = std::make_shared<const skeleton::Skeleton>(
      skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm")));
  return sk;
}

// A long road of the skeleton (the test's lanes follow its polyline).
const skeleton::AtomicRoad& longRoad(const skeleton::Skeleton& sk) {
  const skeleton::AtomicRoad* best = nullptr;
  for (const auto& r : sk.roads()) {
    if (!best || r.length > best->length) best = &r;
  }
  return *best;
}

// `n` parallel lanes along the road, 3.5 m wide, lane 0 on the left.
map::LaneMap lanesAlong(const skeleton::Skeleton& sk, const skeleton::AtomicRoad& road, int n) {
  map::LaneMap m;
  const auto& o = sk.frame().origin();
  m.origin_lat = o.lat;
  m.origin_lon = o.lon;
  m.origin_alt = o.alt;
  const int64_t base = (road.id + 1) * 100000;
  auto offsetLine = [&](double d) {
    std::vector<Eigen::Vector3d> pts;
    for (double s = road.s_begin; s <= road.s_end; s += 5.0) {
      const Eigen::Vector2d p = sk.pointAt(road, s), t = sk.tangentAt(road, s);
      const Eigen::Vector2d left(-t.y(), t.x());
      pts.emplace_back(p.x() + d * left.x(), p.y() + d * left.y(), 0.0);
    }
    return pts;
  };
  int64_t next = base;
  std::vector<int64_t> bounds;
  for (int i = 0; i <= n; ++i) {
    map::LineString ls;
    ls.id = next++;
    ls.type = (i == 0 || i == n) ? map::LineType::kSolid : map::LineType::kDashed;
    ls.points = offsetLine(3.5 * n / 2.0 - 3.5 * i);
    bounds.push_back(ls.id);
    m.lines.push_back(ls);
  }
  for (int i = 0; i < n; ++i) {
    map::Lanelet ll;
    ll.id = next++;
    ll.kind = map::LaneletKind::kRoad;
    ll.left_id = bounds[i];
    ll.right_id = bounds[i + 1];
    ll.centre = offsetLine(3.5 * n / 2.0 - 3.5 * (i + 0.5));
    ll.road_id = road.id;
    ll.from_node = road.from;
    ll.to_node = road.to;
    ll.index_from_left = i;
    m.lanelets.push_back(ll);
  }
  return m;
}

std::string coverageOf(const json& skeleton_geojson, int64_t road_id) {
  for (const auto& f : skeleton_geojson["features"]) {
    if (f["properties"]["road_id"] == road_id) return f["properties"]["coverage"];
  }
  return "absent";
}

TEST(ViewerState, CoverageGoesFromNeverDrivenToDrivenToMapped) {
  auto sk = westOakland();
  viewer::ViewerState state(sk);
  const auto& a = sk->roads()[0];
  const auto& b = longRoad(*sk);
  ASSERT_NE(a.id, b.id);
  json g = json::parse(state.skeletonGeoJson());
  ASSERT_EQ(g["features"].size(), sk->roads().size());
  EXPECT_EQ(coverageOf(g, a.id), "never_driven");
  json s = state.stateValue(0.0);
  EXPECT_EQ(s["coverage"]["never_driven"], sk->roads().size());
  EXPECT_EQ(s["coverage"]["driven"], 0);

  state.onRoadEntered(a.id);
  EXPECT_EQ(state.stateValue(0.0)["open_road"], a.id);
  state.onRoadEntered(b.id);
  state.onRoadClosed(b.id);
  state.setRoadLanes(b.id, lanesAlong(*sk, b, 2));
  g = json::parse(state.skeletonGeoJson());
  EXPECT_EQ(coverageOf(g, a.id), "driven");
  EXPECT_EQ(coverageOf(g, b.id), "mapped");
  s = state.stateValue(0.0);
  EXPECT_EQ(s["coverage"]["driven"], 1);
  EXPECT_EQ(s["coverage"]["mapped"], 1);
  EXPECT_EQ(s["coverage"]["never_driven"], sk->roads().size() - 2);
  EXPECT_EQ(s["open_road"], -1);  // b was entered last, then closed
  EXPECT_EQ(s["closed_roads"], json::array({b.id}));
  // Every skeleton feature is a WGS84 line inside the OSM extract (West Oakland: ~37.8 N, 122.3 W).
  for (const auto& f : g["features"]) {
    ASSERT_EQ(f["geometry"]["type"], "LineString");
    for (const auto& c : f["geometry"]["coordinates"]) {
      EXPECT_NEAR(c[0].get<double>(), -122.3, 0.05);
      EXPECT_NEAR(c[1].get<double>(), 37.81, 0.05);
    }
  }
}

TEST(ViewerState, RoadLanesAppearInGeoJsonAndLanelet2) {
  auto sk = westOakland();
  viewer::ViewerState state(sk);
  const auto& road = longRoad(*sk);
  EXPECT_EQ(state.lanelet2Xml(), "");  // nothing mapped: the download says so (404)
  const uint64_t v0 = state.version();
  state.setRoadLanes(road.id, lanesAlong(*sk, road, 2));
  EXPECT_GT(state.version(), v0);
  EXPECT_EQ(state.roadLaneCount(road.id), 2u);
  json g = json::parse(state.lanesGeoJson());
  int polygons = 0, centres = 0, boundaries = 0;
  for (const auto& f : g["features"]) {
    const auto& p = f["properties"];
    if (p["feature"] == "lanelet") {
      ++polygons;
      EXPECT_EQ(p["road_id"], road.id);
      EXPECT_EQ(p["kind"], "road");
      EXPECT_EQ(f["geometry"]["type"], "Polygon");
    }
    if (p["feature"] == "centre_line") ++centres;
    if (p["feature"] == "boundary") ++boundaries;
  }
  EXPECT_EQ(polygons, 2);
  EXPECT_EQ(centres, 2);
  EXPECT_EQ(boundaries, 3);
  json s = state.stateValue(0.0);
  EXPECT_EQ(s["map"]["roads"], 1);
  EXPECT_EQ(s["map"]["road_lanes"], 2);
  EXPECT_EQ(s["map"]["lanes_by_road"][std::to_string(road.id)], 2);

  // The first centre point, in WGS84, is where the frame puts it.
  const map::LaneMap lanes = lanesAlong(*sk, road, 2);
  const geo::LatLonAlt want = sk->frame().toWgs84(lanes.lanelets[0].centre[0]);
  bool found = false;
  for (const auto& f : g["features"]) {
    if (f["properties"]["feature"] != "centre_line" || f["properties"]["index_from_left"] != 0) continue;
    EXPECT_NEAR(f["geometry"]["coordinates"][0][0].get<double>(), want.lon, 1e-8);
    EXPECT_NEAR(f["geometry"]["coordinates"][0][1].get<double>(), want.lat, 1e-8);
    found = true;
  }
  EXPECT_TRUE(found);

  // A road mapped again replaces its lanes.
  state.setRoadLanes(road.id, lanesAlong(*sk, road, 3));
  EXPECT_EQ(state.roadLaneCount(road.id), 3u);
  EXPECT_EQ(state.stateValue(0.0)["map"]["road_lanes"], 3);

  // The Lanelet2 download reads back with the same three lanes.
  const std::string xml = state.lanelet2Xml();
  ASSERT_FALSE(xml.empty());
  const std::string path = ::testing::TempDir() + "viewer_state_lanes.osm";
  { std::ofstream(path) << xml; }
  const map::LaneMap back = io::readLanelet2(path, sk->frame().origin().lat, sk->frame().origin().lon);
  EXPECT_EQ(back.lanelets.size(), 3u);
}

// The lane mapper's confidence per lane and a road mapped only as far as driven (LANE_MAP carries
// both) are in the page's GeoJSON, which styles lanes by them.
TEST(ViewerState, LaneConfidenceAndPartialRoadAreInTheGeoJson) {
  auto sk = westOakland();
  viewer::ViewerState state(sk);
  const auto& road = longRoad(*sk);
  map::LaneMap lanes = lanesAlong(*sk, road, 2);
  lanes.lanelets[0].confidence = 0.9;
  lanes.lanelets[1].confidence = 0.25;
  for (auto& ll : lanes.lanelets) ll.partial = map::PartialRoad{40.0, road.s_end};
  state.setRoadLanes(road.id, lanes);
  const json g = json::parse(state.lanesGeoJson());
  std::map<int64_t, double> confidence;
  int partial = 0;
  for (const auto& f : g["features"]) {
    const auto& p = f["properties"];
    if (p["feature"] != "lanelet") continue;
    confidence[p["id"].get<int64_t>()] = p["confidence"].get<double>();
    if (p["partial"] == true && p["partial_station_m"] == 40.0) ++partial;
  }
  ASSERT_EQ(confidence.size(), 2u);
  EXPECT_DOUBLE_EQ(confidence[lanes.lanelets[0].id], 0.9);
  EXPECT_DOUBLE_EQ(confidence[lanes.lanelets[1].id], 0.25);
  EXPECT_EQ(partial, 2);
  // Mapped whole on a later drive: no longer partial.
  state.setRoadLanes(road.id, lanesAlong(*sk, road, 2));
  for (const auto& f : json::parse(state.lanesGeoJson())["features"]) {
    if (f["properties"]["feature"] == "lanelet") {
      EXPECT_EQ(f["properties"]["partial"], false);
      EXPECT_TRUE(f["properties"]["confidence"].is_null());
    }
  }
}

TEST(ViewerState, TwoMappedRoadsThroughAnIntersectionGetConnections) {
  auto sk = westOakland();
  // A road into an intersection and one out of it (not its own reverse), both longer than 40 m.
  const skeleton::AtomicRoad *in = nullptr, *out = nullptr;
  for (const auto& a : sk->roads()) {
    if (a.length < 40.0 || in) continue;
    for (const auto& b : sk->roads()) {
      if (b.from == a.to && b.id != a.reverse_id && b.length > 40.0) {
        in = &a;
        out = &b;
        break;
      }
    }
  }
  ASSERT_TRUE(in && out);
  viewer::ViewerState state(sk);
  state.setRoadLanes(in->id, lanesAlong(*sk, *in, 1));
  EXPECT_EQ(state.stateValue(0.0)["map"]["connections"], 0);  // one road: no intersection yet
  state.setRoadLanes(out->id, lanesAlong(*sk, *out, 1));
  const json s = state.stateValue(0.0);
  EXPECT_EQ(s["map"]["road_lanes"], 2);
  EXPECT_GE(s["map"]["connections"].get<int>(), 1);
  int junction_polygons = 0;
  const json g = json::parse(state.lanesGeoJson());
  for (const auto& f : g["features"]) {
    if (f["properties"]["feature"] == "lanelet" && f["properties"]["kind"] == "intersection") {
      ++junction_polygons;
      EXPECT_EQ(f["properties"]["intersection_id"], in->to);
    }
  }
  EXPECT_EQ(junction_polygons, s["map"]["connections"].get<int>());
}

TEST(ViewerState, LanesInAnotherOriginAreMovedIntoTheSkeletonFrame) {
  auto sk = westOakland();
  const auto& road = longRoad(*sk);
  map::LaneMap lanes = lanesAlong(*sk, road, 1);
  const geo::LatLonAlt want = sk->frame().toWgs84(lanes.lanelets[0].centre[0]);
  // The same lanes expressed around an origin 500 m away.
  const geo::LatLonAlt other = sk->frame().toWgs84(Eigen::Vector3d(400.0, -300.0, 0.0));
  const geo::LocalFrame of(other);
  for (auto& l : lanes.lines) for (auto& p : l.points) p = of.toEnu(sk->frame().toWgs84(p));
  for (auto& ll : lanes.lanelets) for (auto& p : ll.centre) p = of.toEnu(sk->frame().toWgs84(p));
  lanes.origin_lat = other.lat;
  lanes.origin_lon = other.lon;
  lanes.origin_alt = other.alt;
  viewer::ViewerState state(sk);
  state.setRoadLanes(road.id, lanes);
  json g = json::parse(state.lanesGeoJson());
  bool found = false;
  for (const auto& f : g["features"]) {
    if (f["properties"]["feature"] != "centre_line") continue;
    EXPECT_NEAR(f["geometry"]["coordinates"][0][0].get<double>(), want.lon, 1e-8);
    EXPECT_NEAR(f["geometry"]["coordinates"][0][1].get<double>(), want.lat, 1e-8);
    found = true;
  }
  EXPECT_TRUE(found);
}

TEST(ViewerState, TrailKeepsPointsApartCapsAndPages) {
  auto sk = westOakland();
  viewer::ViewerOptions o;
  o.trail_spacing_m = 0.9;  // poses come 0.5 m apart: every second one is kept
  o.max_trail_points = 15;
  viewer::ViewerState state(sk, {}, {}, o);
  // 41 poses 0.5 m apart eastwards: every second one is kept (21 points over 20 m).
  for (int i = 0; i <= 40; ++i) {
    const geo::LatLonAlt g = sk->frame().toWgs84(Eigen::Vector3d(0.5 * i, 0.0, 0.0));
    state.onPose(1000 + i, g.lat, g.lon, 0.0);
  }
  json s = state.stateValue(0.0);
  EXPECT_EQ(s["trail_count"], 21);
  EXPECT_EQ(s["car"]["poses"], 41);
  const geo::LatLonAlt last = sk->frame().toWgs84(Eigen::Vector3d(20.0, 0.0, 0.0));
  EXPECT_NEAR(s["car"]["lat"].get<double>(), last.lat, 1e-6);
  EXPECT_NEAR(s["car"]["lon"].get<double>(), last.lon, 1e-6);
  // Capped at 15: the first 6 are gone; paging from 0 starts at 6, from 18 gives 3.
  json t = state.trail(0);
  EXPECT_EQ(t["from"], 6);
  EXPECT_EQ(t["points"].size(), 15u);
  t = state.trail(18);
  EXPECT_EQ(t["from"], 18);
  EXPECT_EQ(t["points"].size(), 3u);
  EXPECT_EQ(state.trail(21)["points"].size(), 0u);
  // Not a position: ignored.
  state.onPose(2000, std::nan(""), 0.0, 0.0);
  state.onPose(2001, 95.0, 0.0, 0.0);
  EXPECT_EQ(state.stateValue(0.0)["car"]["poses"], 41);
}

TEST(ViewerState, BevPictureIsTransparentWhereUnobservedFaintOnBackgroundAndPlacedByItsCells) {
  auto sk = westOakland();
  viewer::ViewerState state(sk);
  EXPECT_EQ(state.bevPng(), "");
  bev::BevGrid grid;  // 0.1 m cells, 128-cell tiles
  // A 10 m x 4 m drivable strip from (2, 2) m east/north, inside the first tile.
  for (int i = 20; i < 120; ++i) {
    for (int j = 20; j < 60; ++j) {
      grid.add({i, j}, bev::Layer::kObserved, 4);
      grid.add({i, j}, bev::Layer::kDrivable, 4);
    }
  }
  grid.add({10, 10}, bev::Layer::kObserved, 4);  // seen, background only
  EXPECT_THROW(state.setBev(7, bev::BevGrid()), bev::BevError);
  state.setBev(7, grid);
  const std::string png = state.bevPng();
  ASSERT_FALSE(png.empty());
  const cv::Mat img = cv::imdecode(std::vector<uchar>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(img.channels(), 4);
  // The picture covers the allocated tiles: one tile, 128 x 128 cells.
  EXPECT_EQ(img.cols, 128);
  EXPECT_EQ(img.rows, 128);
  // North up: ENU cell (100, 40) is at row 127 - 40; cell (10, 100) was never observed.
  EXPECT_EQ(img.at<cv::Vec4b>(127 - 40, 100)[3], 255);
  EXPECT_EQ(img.at<cv::Vec4b>(127 - 100, 10)[3], 0);
  const uint8_t faint = img.at<cv::Vec4b>(127 - 10, 10)[3];  // background: faint, neither hidden nor opaque
  EXPECT_GT(faint, 0);
  EXPECT_LT(faint, 128);
  const json s = state.stateValue(0.0);
  EXPECT_EQ(s["bev"]["road_id"], 7);
  const geo::LatLonAlt sw = sk->frame().toWgs84(Eigen::Vector3d(0, 0, 0));
  const geo::LatLonAlt ne = sk->frame().toWgs84(Eigen::Vector3d(12.8, 12.8, 0));
  EXPECT_NEAR(s["bev"]["bounds"][0][0].get<double>(), sw.lat, 1e-9);
  EXPECT_NEAR(s["bev"]["bounds"][0][1].get<double>(), sw.lon, 1e-9);
  EXPECT_NEAR(s["bev"]["bounds"][1][0].get<double>(), ne.lat, 1e-9);
  EXPECT_NEAR(s["bev"]["bounds"][1][1].get<double>(), ne.lon, 1e-9);
}

TEST(ViewerState, OpenRoadPictureIsShownWhileItsRoadIsOpenAndNeverHidesAClosedRoadsBev) {
  auto sk = westOakland();
  viewer::ViewerState state(sk);
  ASSERT_GE(sk->roads().size(), 2u);
  const int64_t a = sk->roads()[0].id, b = sk->roads()[1].id;
  bev::BevGrid grid;
  for (int i = 0; i < 50; ++i) {
    grid.add({i, 3}, bev::Layer::kObserved, 2);
    grid.add({i, 3}, bev::Layer::kDrivable, 2);
  }
  bev::BevPicture pic = bev::bevPicture(grid, 64);
  EXPECT_THROW(state.setOpenRoadBev(a, bev::BevPicture()), bev::BevError);
  state.onRoadEntered(a);
  ASSERT_TRUE(state.setOpenRoadBev(a, pic));
  json s = state.stateValue(0.0);
  EXPECT_EQ(s["bev"]["road_id"], a);
  EXPECT_EQ(s["bev"]["open"], true);
  EXPECT_EQ(state.bevPng(), std::string(pic.png.begin(), pic.png.end()));
  const auto v1 = s["bev"]["version"].get<uint64_t>();
  // A picture of another road than the open one is not shown.
  EXPECT_FALSE(state.setOpenRoadBev(b, pic));
  EXPECT_EQ(state.stateValue(0.0)["bev"]["version"].get<uint64_t>(), v1);
  // Refreshed: each new picture is a new version.
  ASSERT_TRUE(state.setOpenRoadBev(a, pic));
  EXPECT_GT(state.stateValue(0.0)["bev"]["version"].get<uint64_t>(), v1);
  // The road closes and its full BEV comes: a late picture of it does not replace that.
  state.onRoadClosed(a);
  state.setBev(a, grid);
  s = state.stateValue(0.0);
  EXPECT_EQ(s["bev"]["open"], false);
  const auto v2 = s["bev"]["version"].get<uint64_t>();
  EXPECT_FALSE(state.setOpenRoadBev(a, pic));
  EXPECT_EQ(state.stateValue(0.0)["bev"]["version"].get<uint64_t>(), v2);
  // The next road's pictures are shown again, placed by their ENU extent.
  state.onRoadEntered(b);
  pic.enu = Eigen::AlignedBox2d(Eigen::Vector2d(100, 200), Eigen::Vector2d(150, 210));
  ASSERT_TRUE(state.setOpenRoadBev(b, pic));
  s = state.stateValue(0.0);
  EXPECT_EQ(s["bev"]["road_id"], b);
  EXPECT_EQ(s["bev"]["open"], true);
  const geo::LatLonAlt ne = sk->frame().toWgs84(Eigen::Vector3d(150, 210, 0));
  EXPECT_NEAR(s["bev"]["bounds"][1][0].get<double>(), ne.lat, 1e-9);
  EXPECT_NEAR(s["bev"]["bounds"][1][1].get<double>(), ne.lon, 1e-9);
}

json processNamed(const json& s, const std::string& name) {
  for (const auto& p : s["processes"]) {
    if (p["process"] == name) return p;
  }
  return nullptr;
}

TEST(ViewerState, StatusPanelCallsAProcessBehindWhenSilentDroppingOrSaturated) {
  auto sk = westOakland();
  viewer::ViewerState state(sk);
  viewer::ProcessStatus seg;
  seg.process = "segmenter";
  seg.host = "car";
  seg.pid = 42;
  seg.cpu_fraction = 0.5;
  seg.latency_p50_ms = 30.0;
  seg.latency_p99_ms = std::nan("");
  seg.counters = {{"frames_dropped", 0}, {"frames_segmented", 10}};
  state.onStatus(seg, 100.0);
  json p = processNamed(state.stateValue(100.5), "segmenter");
  ASSERT_FALSE(p.is_null());
  EXPECT_FALSE(p["behind"].get<bool>());
  EXPECT_EQ(p["drops"], 0);
  EXPECT_EQ(p["latency_p50_ms"], 30.0);
  EXPECT_TRUE(p["latency_p99_ms"].is_null());
  // Silent for longer than status_stale_s (3 s).
  p = processNamed(state.stateValue(104.0), "segmenter");
  EXPECT_TRUE(p["behind"].get<bool>());
  // Dropped 2 frames: behind for the loss window (10 s), then not.
  seg.counters["frames_dropped"] = 2;
  state.onStatus(seg, 105.0);
  p = processNamed(state.stateValue(105.5), "segmenter");
  EXPECT_TRUE(p["behind"].get<bool>());
  EXPECT_EQ(p["drops"], 2);
  EXPECT_NE(p["reason"].get<std::string>().find("dropping"), std::string::npos);
  state.onStatus(seg, 116.0);
  EXPECT_FALSE(processNamed(state.stateValue(116.2), "segmenter")["behind"].get<bool>());
  // A restart (new pid) starts its counters again: no drop growth from that.
  seg.pid = 43;
  seg.counters["frames_dropped"] = 5;
  state.onStatus(seg, 117.0);
  EXPECT_FALSE(processNamed(state.stateValue(117.1), "segmenter")["behind"].get<bool>());
  // A saturated core.
  seg.cpu_fraction = 0.99;
  state.onStatus(seg, 118.0);
  EXPECT_TRUE(processNamed(state.stateValue(118.1), "segmenter")["behind"].get<bool>());
  EXPECT_TRUE(viewer::isLossCounter("frames_queue_full"));
  EXPECT_FALSE(viewer::isLossCounter("frames_projected"));
}

}  // namespace
