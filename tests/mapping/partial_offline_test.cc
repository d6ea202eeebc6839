// The road a drive ends on (issue 14), end to end: lanemap-offline maps it as far as the car drove
// (lanelets tagged partial, ending where the car stopped, with the station in the GeoJSON and
// summary.json), lanemap-eval --driven scores it on its driven part, and a second drive that
// closes the road makes it complete (its partial evidence merged).
#include "core/lanes/options.h"
#include "core/mapping/partial_road.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/sim_drive.h"

#include <Eigen/Core>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace lt = lanemap::testing;

namespace {

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The car's last position (trajectory.csv's last row), in the skeleton's frame.
Eigen::Vector2d lastPosition(const std::string& drive, const lanemap::geo::LocalFrame& frame) {
  std::ifstream csv(drive + "/trajectory.csv");
  std::string line, last;
  while (std::getline(csv, line)) last = line;
  std::stringstream ss(last);
  std::string item;
  std::vector<double> v;
  while (std::getline(ss, item, ',')) v.push_back(std::stod(item));
  const auto o = readJson(drive + "/scenario.json")["origin"];
  const lanemap::geo::LocalFrame sim({o["lat"].get<double>(), o["lon"].get<double>(), o["alt"].get<double>()});
  return frame.toEnu(sim.toWgs84(Eigen::Vector3d(v[2], v[3], v[4]))).head<2>();
}

// The road lanelets of `road_id` in a map.geojson.
std::vector<nlohmann::json> laneletsOf(const std::string& geojson, int64_t road_id) {
  std::vector<nlohmann::json> out;
  const auto g = readJson(geojson);  // kept: a range over a temporary's member would dangle
  for (const auto& f : g["features"]) {
    const auto& p = f["properties"];
    if (p["feature"] == "lanelet" && p["kind"] == "road" && p["road_id"] == road_id) out.push_back(f);
  }
  return out;
}

// Frenet station (skeleton road, the explorer's frame) of the last point of each centre line.
std::vector<double> centreEndStations(const std::string& geojson, int64_t road_id, const lanemap::skeleton::AtomicRoad& road,
                                      const lanemap::geo::LocalFrame& frame) {
  std::vector<double> out;
  const auto g = readJson(geojson);  // kept: a range over a temporary's member would dangle
  for (const auto& f : g["features"]) {
    const auto& p = f["properties"];
    if (p["feature"] != "centre_line" || p["kind"] != "road" || p["road_id"] != road_id) continue;
    const auto& c = f["geometry"]["coordinates"].back();
    const Eigen::Vector3d enu = frame.toEnu(c[1].get<double>(), c[0].get<double>(), c[2].get<double>());
    out.push_back(lanemap::mapping::roadStation(road, enu.head<2>(), lanemap::lanes::ExplorerOptions{}));
  }
  return out;
}

}  // namespace

TEST(PartialOffline, TheRoadALogEndsOnIsMappedAsFarAsDrivenThenCompletedByALaterDrive) {
  const std::string args = "--world-seed 11 --no-lidar --camera-hz 5";
  const std::string d1 = lt::sharedSimDrive("osm/west-oakland.osm", 20.0, 1, args);
  const auto s1 = readJson(d1 + "/scenario.json");
  const auto& last = s1["route"].back();
  ASSERT_TRUE(last["left_utime"].is_null()) << "drive 1 must end on a road";
  const int64_t road_id = last["road_id"].get<int64_t>();
  const auto sk = lanemap::skeleton::Skeleton::build(lanemap::osm::readOsm(d1 + "/roads.osm"));
  // Drive 2 drives drive 1's route, through the end of the road drive 1 ended on, into the next
  // road (a route ending at an intersection stops short of it).
  std::string route;
  for (const auto& road : s1["route"]) route += std::to_string(road["from"].get<int64_t>()) + ",";
  route += std::to_string(last["to"].get<int64_t>());
  int64_t beyond = -1;
  for (const auto& r : sk.roads()) {
    if (r.from == last["to"].get<int64_t>() && r.to != last["from"].get<int64_t>() && beyond < 0) beyond = r.to;
  }
  ASSERT_GE(beyond, 0) << "no road leaves intersection " << last["to"];
  route += "," + std::to_string(beyond);
  const std::string d2 = lt::sharedSimDrive("osm/west-oakland.osm", 45.0, 2, args + " --route " + route);
  const auto s2 = readJson(d2 + "/scenario.json");
  bool closed_by_2 = false;
  for (const auto& r : s2["route"]) closed_by_2 |= r["road_id"] == road_id && !r["left_utime"].is_null();
  ASSERT_TRUE(closed_by_2) << "drive 2 must drive road " << road_id << " to its end";

  const auto* road = sk.road(road_id);
  ASSERT_NE(road, nullptr);
  const lanemap::lanes::ExplorerOptions explorer;
  const double car_station = lanemap::mapping::roadStation(*road, lastPosition(d1, sk.frame()), explorer);
  const double road_length = lanemap::mapping::roadFrameLength(*road, explorer);
  std::printf("road %lld: the car stopped at %.1f m of %.1f m (explored from %.1f m)\n", static_cast<long long>(road_id),
              car_station, road_length, road->s_begin);
  ASSERT_GT(car_station - road->s_begin, explorer.min_lane_length_m) << "too little driven to map";

  // Drive 1 alone: the road it ended on is mapped partial, to where the car stopped.
  lt::TempDir out("partial-offline");
  const std::string offline = lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --osm " + d1 + "/roads.osm";
  auto r = lt::runCommand(offline + " --log " + d1 + "/drive.lcmlog --out " + out.str("one"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto summary = readJson(out.str("one/summary.json"));
  const nlohmann::json* entry = nullptr;
  for (const auto& e : summary["roads"]) {
    if (e["road_id"] == road_id) entry = &e;
  }
  ASSERT_NE(entry, nullptr) << summary["roads"].dump() << " " << summary["partial_not_mapped"].dump();
  ASSERT_TRUE(entry->contains("partial")) << entry->dump();
  const double station = (*entry)["partial"]["station_m"].get<double>();
  EXPECT_NEAR(station, car_station, 2.0) << "the last pose (GNSS error about 0.5 m) vs the true position";
  EXPECT_NEAR((*entry)["partial"]["road_length_m"].get<double>(), road_length, 0.01);
  EXPECT_GE((*entry)["lanes"].get<int>(), 1);
  EXPECT_TRUE(std::filesystem::exists(out.str("one/bev/partial/road_" + std::to_string(road_id) + ".bev")));
  const auto lanelets = laneletsOf(out.str("one/map.geojson"), road_id);
  ASSERT_FALSE(lanelets.empty());
  for (const auto& f : lanelets) {
    EXPECT_EQ(f["properties"]["partial"], true);
    EXPECT_NEAR(f["properties"]["partial_station_m"].get<double>(), station, 1e-9);
    EXPECT_NEAR(f["properties"]["road_length_m"].get<double>(), road_length, 0.01);
  }
  // The lanes stop where the car stopped: nothing past it, the longest within a few metres of it.
  const auto ends = centreEndStations(out.str("one/map.geojson"), road_id, *road, sk.frame());
  ASSERT_FALSE(ends.empty());
  double furthest = 0.0;
  for (const double e : ends) {
    EXPECT_LT(e, car_station + 2.0) << "a lane goes past where the car stopped";
    furthest = std::max(furthest, e);
  }
  EXPECT_GT(furthest, car_station - 4.0);
  // The closed roads are complete.
  for (const auto& e : summary["roads"]) {
    if (e["road_id"] != road_id) { EXPECT_FALSE(e.contains("partial")) << e.dump(); }
  }

  // lanemap-eval --driven: the partial road is scored against its truth as far as driven (cut where
  // the car stopped), and its lanes cover that truth. (Whether they are detections depends on the
  // drive's pose offset, about 0.9 m here: lanemap-sim --world-seed draws one per drive.)
  const std::string eval = lt::binPath("lanemap-eval") + " -q --truth " + d1 + "/groundtruth.osm --map " + out.str("one/map.osm");
  r = lt::runCommand(eval + " --driven " + d1 + "/scenario.json --json " + out.str("one/eval.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto report = readJson(out.str("one/eval.json"));
  EXPECT_EQ(report["partial_roads"], 1);
  const nlohmann::json* detail = nullptr;
  for (const auto& d : report["roads"]) {
    if (d["from_node"] == last["from"] && d["to_node"] == last["to"]) detail = &d;
  }
  ASSERT_NE(detail, nullptr) << "the partial road's truth is scored";
  EXPECT_GE((*detail)["truth_lanes"].get<int>(), 1);
  EXPECT_EQ((*detail)["matched"], (*detail)["truth_lanes"]) << detail->dump();
  int partial_truth = 0;
  for (const auto& l : report["lanes_detail"]) {
    if (l["road_id"] != road_id) continue;
    ++partial_truth;
    EXPECT_LT(l["length_m"].get<double>(), car_station - road->s_begin + 8.0) << "the truth is cut where the car stopped: " << l.dump();
    EXPECT_GT(l["coverage"].get<double>(), 0.9) << "the partial lanes cover the driven truth: " << l.dump();
    EXPECT_LT(l["rms_m"].get<double>(), 0.6) << l.dump();
  }
  EXPECT_EQ(partial_truth, (*detail)["truth_lanes"].get<int>());
  // The same from the log (its POSE map-matched by the road tracker): the same truth.
  r = lt::runCommand(eval + " --driven " + d1 + "/drive.lcmlog --osm " + d1 + "/roads.osm --json " + out.str("one/eval_log.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto by_log = readJson(out.str("one/eval_log.json"));
  EXPECT_EQ(by_log["partial_roads"], 1);
  EXPECT_EQ(by_log["lanes"]["truth"], report["lanes"]["truth"]);

  // Drive 1 then drive 2, which closes the road: complete, its lanes past where drive 1 stopped.
  r = lt::runCommand(offline + " --log " + d1 + "/drive.lcmlog --log " + d2 + "/drive.lcmlog --out " + out.str("two"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto two = readJson(out.str("two/summary.json"));
  bool completed = false;
  for (const auto& m : two["drives"][1]["merged"]) {
    if (m["road_id"] == road_id) completed = m["completed_partial"].get<bool>();
  }
  EXPECT_TRUE(completed) << two["drives"].dump();
  EXPECT_FALSE(std::filesystem::exists(out.str("two/bev/partial/road_" + std::to_string(road_id) + ".bev")));
  const auto complete = laneletsOf(out.str("two/map.geojson"), road_id);
  ASSERT_FALSE(complete.empty());
  for (const auto& f : complete) {
    EXPECT_EQ(f["properties"]["partial"], false);
    EXPECT_TRUE(f["properties"]["partial_station_m"].is_null());
  }
  double furthest2 = 0.0;
  for (const double e : centreEndStations(out.str("two/map.geojson"), road_id, *road, sk.frame())) furthest2 = std::max(furthest2, e);
  EXPECT_GT(furthest2, station + 5.0) << "the completed road's lanes reach past where drive 1 stopped";
  EXPECT_GT(furthest2, road->s_end - 8.0) << "... to near the end intersection";
}
