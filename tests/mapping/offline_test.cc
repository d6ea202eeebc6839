// lanemap-offline end to end on a simulated drive (camera labels from the simulator's truth, LIDAR
// mesh): the map it writes loads, covers the roads the car drove to their end and, as far as it
// was driven, the road the drive ended on (tests/mapping/partial_offline_test.cc has the details),
// and lanemap-eval scores it against groundtruth.osm on what was driven. The drive is the BEV
// tests' (tests/bev).
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "core/io/lanelet2.h"
#include "tests/bev/bev_replay.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <set>

namespace {

namespace lt = lanemap::testing;

TEST(Offline, MapsTheDrivenRoadsAndScoresAgainstTheTruth) {
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  lt::TempDir out("offline");
  const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --log " + drive + "/drive.lcmlog --osm " + drive +
                                "/roads.osm --out " + out.str("map"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"map.osm", "map.geojson", "map.png"}) EXPECT_TRUE(std::filesystem::exists(out.str("map/") + f)) << f;

  std::set<int64_t> closed;  // roads the car drove to their end
  std::ifstream js(drive + "/scenario.json");
  const auto scenario = nlohmann::json::parse(js);
  for (const auto& road : scenario["route"]) {
    if (!road["left_utime"].is_null()) closed.insert(road["road_id"].get<int64_t>());
  }
  ASSERT_FALSE(closed.empty());

  // summary.json: every road explored, with its lanes, none failed; the labels it mapped on. The
  // road the drive ended on (route's last entry, not left) is mapped partial when enough of it
  // was driven.
  std::ifstream sj(out.str("map/summary.json"));
  const auto summary = nlohmann::json::parse(sj);
  std::set<int64_t> partial;
  for (const auto& r : summary["roads"]) {
    if (r.contains("partial")) partial.insert(r["road_id"].get<int64_t>());
  }
  ASSERT_LE(partial.size(), 1u);
  if (!partial.empty()) {
    EXPECT_TRUE(scenario["route"].back()["left_utime"].is_null());
    EXPECT_EQ(*partial.begin(), scenario["route"].back()["road_id"].get<int64_t>());
  }
  std::set<int64_t> driven = closed;
  driven.insert(partial.begin(), partial.end());

  const auto origin = lanemap::eval::lanelet2Origin(drive + "/groundtruth.osm");
  const auto truth = lanemap::io::readLanelet2(drive + "/groundtruth.osm", origin.lat, origin.lon);
  const auto built = lanemap::io::readLanelet2(out.str("map/map.osm"), origin.lat, origin.lon);
  std::set<int64_t> mapped;
  for (const auto& l : built.lanelets) {
    if (l.kind == lanemap::map::LaneletKind::kRoad) {
      mapped.insert(l.road_id);
      EXPECT_EQ(l.partial.has_value(), partial.count(l.road_id) > 0) << l.id;
      ASSERT_TRUE(l.confidence.has_value()) << l.id;
      EXPECT_GE(*l.confidence, 0.0);
      EXPECT_LE(*l.confidence, 1.0);
    }
  }
  EXPECT_EQ(mapped, driven);

  // Scored on what was driven: the closed roads and the partial one as far as the car went.
  const auto area = lanemap::eval::drivenAreaFromScenario(drive + "/scenario.json", lanemap::geo::LocalFrame(origin));
  const auto report = lanemap::eval::evaluate(lanemap::eval::restrictToDriven(truth, area), built);
  std::printf("offline on oracle labels: lanes P %.3f R %.3f RMS %.3f m mIoU %.3f\n", report.lane_precision.value(),
              report.lane_recall.value(), report.lane_rms_m, report.lane_miou);
  // The paper's best (Berkeley, LIDAR + camera): P 0.84, R 0.73, RMS 0.24 m, mIoU 0.79. On this
  // short drive (one road closed) every true lane is found within the paper's RMS, but the
  // camera-projected BEV gives one spurious extra lane (measured: P 0.667, mIoU 0.68), a known
  // weakness noted on issue 6: precision and mIoU are held at what is reached, not the paper's.
  EXPECT_GE(report.lane_recall.value(), 0.73);
  EXPECT_LT(report.lane_rms_m, 0.24);
  EXPECT_GE(report.lane_precision.value(), 0.6);
  EXPECT_GE(report.lane_miou, 0.6);

  EXPECT_EQ(summary["labels"], "SEMANTIC_FRONT_TRUTH");
  EXPECT_EQ(summary["roads_failed"], 0);
  EXPECT_EQ(summary["roads_mapped"].get<size_t>(), summary["roads"].size());
  std::set<int64_t> explored;
  for (const auto& r : summary["roads"]) {
    explored.insert(r["road_id"].get<int64_t>());
    EXPECT_GE(r["lanes"].get<int>(), 1) << r.dump();
  }
  EXPECT_EQ(explored, driven);

  // lanemap-eval --driven: the route from scenario.json and the route map-matched from the log's
  // POSE by the road tracker are the same roads, so the same truth is scored.
  const std::string eval = lt::binPath("lanemap-eval") + " -q --truth " + drive + "/groundtruth.osm --map " + out.str("map/map.osm");
  const auto a = lt::runCommand(eval + " --driven " + drive + "/scenario.json --json " + out.str("a.json"));
  const auto b = lt::runCommand(eval + " --driven " + drive + "/drive.lcmlog --osm " + drive + "/roads.osm --json " + out.str("b.json"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  ASSERT_EQ(b.exit_code, 0) << b.output;
  std::ifstream ja(out.str("a.json")), jb(out.str("b.json"));
  const auto ra = nlohmann::json::parse(ja), rb = nlohmann::json::parse(jb);
  EXPECT_EQ(ra["scored_area"], "driven");
  EXPECT_EQ(ra["driven_roads"].get<size_t>(), closed.size());
  EXPECT_EQ(rb["driven_roads"], ra["driven_roads"]);
  EXPECT_EQ(rb["lanes"]["truth"], ra["lanes"]["truth"]);
  EXPECT_EQ(rb["intersections"]["truth_pairs"], ra["intersections"]["truth_pairs"]);
  EXPECT_EQ(ra["partial_roads"], rb["partial_roads"]);
  // The road the drive began on is cut at where it began either way (the log's first road entered).
  EXPECT_EQ(ra["entered_roads"].get<int>(), 1);
  EXPECT_EQ(rb["entered_roads"], ra["entered_roads"]);
  // Every driven road was mapped here, so --driven scores the truth lanes scored above.
  EXPECT_EQ(ra["lanes"]["truth"].get<size_t>(), report.truth_lanes.size());
  const auto bad = lt::runCommand(eval + " --driven " + drive + "/drive.lcmlog");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--osm"), std::string::npos) << bad.output;
}

// The LIDAR meshes on a second core (the default: the reader goes on while the worker meshes, see
// BevBuilderOptions::offline_pipeline) against the meshes built in the main thread: the same frames
// on the same meshes into the same roads, so the same grids and map byte for byte. The drive is
// the demo's kind (10 Hz camera and LIDAR, 40 s, three roads closed): the pipelined reader runs up
// to four sweeps ahead of the worker, so a frame's mesh, a road's close and a road's history replay
// all happen while frames wait for the worker.
TEST(Offline, MeshesOnASecondCoreGiveTheMapOfTheMainThreadByteForByte) {
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", 40.0, 1);
  lt::TempDir out("offline-pipeline");
  const std::string cmd = lt::binPath("lanemap-offline") + " -q --oracle --log " + drive + "/drive.lcmlog --osm " + drive +
                          "/roads.osm --out ";
  const auto a = lt::runCommand(cmd + out.str("pipelined"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const auto b = lt::runCommand(cmd + out.str("main") + " --mesh-in-main-thread");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  auto bytes = [](const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    EXPECT_TRUE(f.good()) << path;
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  auto summary = [&](const std::string& dir) { return nlohmann::json::parse(bytes(dir + "/summary.json")); };
  const auto sa = summary(out.str("pipelined")), sb = summary(out.str("main"));
  EXPECT_GT(sa["frames_mesh"].get<int>(), 300);  // 10 Hz over most of 40 s on the mesh
  EXPECT_EQ(sa["frames_mesh"], sb["frames_mesh"]);
  EXPECT_EQ(sa["frames_projected"], sb["frames_projected"]);
  ASSERT_GE(sa["roads_mapped"].get<int>(), 2);
  EXPECT_EQ(bytes(out.str("pipelined/map.osm")), bytes(out.str("main/map.osm")));
  EXPECT_EQ(bytes(out.str("pipelined/map.geojson")), bytes(out.str("main/map.geojson")));
  int grids = 0;
  for (const auto& e : std::filesystem::directory_iterator(out.str("main/bev"))) {
    if (e.path().extension() != ".bev") continue;
    EXPECT_EQ(bytes(e.path().string()), bytes(out.str("pipelined/bev/") + e.path().filename().string())) << e.path();
    ++grids;
  }
  EXPECT_GE(grids, 2);
}

TEST(Offline, MissingLogOrOsmGiveClearErrors) {
  lt::TempDir out("offline-bad");
  const auto a = lt::runCommand(lt::binPath("lanemap-offline") + " -q --log /nonexistent.lcmlog --osm " + lt::dataPath("osm/west-oakland.osm") +
                                " --out " + out.str("m"));
  EXPECT_EQ(a.exit_code, 2);
  EXPECT_NE(a.output.find("/nonexistent.lcmlog"), std::string::npos) << a.output;
  const auto b = lt::runCommand(lt::binPath("lanemap-offline") + " -q --log /dev/null --osm /nonexistent.osm --out " + out.str("m"));
  EXPECT_NE(b.exit_code, 0);
  EXPECT_NE(b.output.find("/nonexistent.osm"), std::string::npos) << b.output;
}

}  // namespace
