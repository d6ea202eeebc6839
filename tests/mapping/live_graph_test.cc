// The live process graph (lanemap-launch config/launch/demo.yaml: lcm-logplayer at 1x ->
// road_tracker -> bev_builder -> lane_mapper over udpm, in a private network namespace) maps a
// simulated drive like the offline runner does: the same roads and lanes, centre lines within
// 0.15 m (the live bev_builder builds LIDAR meshes in a worker thread, so a frame may use the
// previous sweep's mesh: close, not byte-equal), and the truth scores of tests/mapping/offline_test.
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "core/io/lanelet2.h"
#include "tests/bev/bev_replay.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace {

namespace lt = lanemap::testing;

TEST(LiveGraph, MapsTheDriveLikeTheOfflineRunner) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  lt::TempDir out("live-graph");
  const auto offline = lt::runCommand(lt::binPath("lanemap-offline") + " -q --log " + drive + "/drive.lcmlog --osm " + drive +
                                      "/roads.osm --out " + out.str("offline"));
  ASSERT_EQ(offline.exit_code, 0) << offline.output;
  const auto live = lt::runCommand(lt::binPath("lanemap-launch") + " " + LANEMAP_SOURCE_DIR +
                                   "/config/launch/demo.yaml --all-hosts --status-interval 0 --set drive=" + drive +
                                   " --set store=" + out.str("live") + " --log-dir " + out.str("logs"));
  ASSERT_EQ(live.exit_code, 0) << live.output;
  ASSERT_TRUE(std::filesystem::exists(out.str("live/lane_map.osm"))) << live.output;

  const auto origin = lanemap::eval::lanelet2Origin(drive + "/groundtruth.osm");
  const auto truth = lanemap::io::readLanelet2(drive + "/groundtruth.osm", origin.lat, origin.lon);
  const auto offline_map = lanemap::io::readLanelet2(out.str("offline/map.osm"), origin.lat, origin.lon);
  const auto live_map = lanemap::io::readLanelet2(out.str("live/lane_map.osm"), origin.lat, origin.lon);

  lanemap::eval::EvalOptions tight;
  tight.rms_threshold_m = 0.15;
  const auto same = lanemap::eval::evaluate(offline_map, live_map, tight);
  std::printf("live vs offline: lanes P %.3f R %.3f RMS %.3f m; intersections P %.3f R %.3f\n", same.lane_precision.value(),
              same.lane_recall.value(), same.lane_rms_m, same.intersection_precision.value(), same.intersection_recall.value());
  EXPECT_DOUBLE_EQ(same.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(same.lane_recall.value(), 1.0);
  EXPECT_LT(same.lane_rms_m, 0.15);

  const auto vs_truth = lanemap::eval::evaluate(lanemap::eval::restrictToMappedRoads(truth, live_map), live_map);
  std::printf("live vs truth: lanes P %.3f R %.3f RMS %.3f m\n", vs_truth.lane_precision.value(),
              vs_truth.lane_recall.value(), vs_truth.lane_rms_m);
  EXPECT_GE(vs_truth.lane_recall.value(), 0.73);  // as tests/mapping/offline_test.cc
  EXPECT_LT(vs_truth.lane_rms_m, 0.24);
}

}  // namespace
