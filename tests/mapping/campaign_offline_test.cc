// lanemap-offline with several drives of one world (issue 14): each later drive's BEV is aligned
// to the earlier evidence of every road it closes again, and the shift found is the difference of
// the drives' pose offsets (which lanemap-sim --world-seed draws and names in scenario.json).
#include "tests/common/sim_drive.h"

#include <Eigen/Core>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace lt = lanemap::testing;

namespace {

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

Eigen::Vector2d offsetOf(const nlohmann::json& scenario) {
  return {scenario["pose_offset"]["east_m"].get<double>(), scenario["pose_offset"]["north_m"].get<double>()};
}

}  // namespace

TEST(CampaignOffline, LaterDrivesAreAlignedByTheDifferenceOfTheirPoseOffsets) {
  lt::TempDir tmp("campaign-offline");
  const std::string sim = lt::binPath("lanemap-sim") + " -q --osm " + lt::dataPath("osm/west-oakland.osm") +
                          " --world-seed 11 --duration 20 --no-lidar --camera-hz 5 ";
  auto r = lt::runCommand(sim + "--seed 1 --out " + tmp.str("d1"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s1 = readJson(tmp.str("d1/scenario.json"));
  std::string route;  // drive 2 passes the intersections drive 1 passed
  for (const auto& road : s1["route"]) route += std::to_string(road["from"].get<int64_t>()) + ",";
  route += std::to_string(s1["route"].back()["to"].get<int64_t>());
  r = lt::runCommand(sim + "--seed 2 --route " + route + " --out " + tmp.str("d2"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s2 = readJson(tmp.str("d2/scenario.json"));
  const Eigen::Vector2d expected = offsetOf(s1) - offsetOf(s2);  // drive 2's evidence onto drive 1's
  ASSERT_GT(expected.norm(), 0.2) << "the two drives' offsets are too close to tell alignment from none";

  const std::string offline = lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --log " + tmp.str("d1/drive.lcmlog") +
                              " --log " + tmp.str("d2/drive.lcmlog") + " --osm " + tmp.str("d1/roads.osm");
  r = lt::runCommand(offline + " --out " + tmp.str("fused"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto summary = readJson(tmp.str("fused/summary.json"));
  ASSERT_EQ(summary["drives"].size(), 2u);
  EXPECT_TRUE(summary["drives"][0]["merged"].empty());  // the first drive: nothing earlier
  const auto& merged = summary["drives"][1]["merged"];
  ASSERT_FALSE(merged.empty()) << "drive 2 closed no road drive 1 had closed";
  for (const auto& m : merged) {
    ASSERT_TRUE(m["aligned"].get<bool>()) << m.dump();
    EXPECT_EQ(m["traversals_before"], 1);
    const Eigen::Vector2d shift(m["shift_m"][0].get<double>(), m["shift_m"][1].get<double>());
    // Within the wandering GNSS bias (0.1 m sigma) and a cell, of the offsets' difference.
    EXPECT_LT((shift - expected).norm(), 0.35) << "road " << m["road_id"] << ": shift " << shift.transpose()
                                                << ", offsets differ by " << expected.transpose();
  }
  EXPECT_GT(summary["lanelets"].get<int>(), 0);

  // --no-align: the same merges, none shifted.
  r = lt::runCommand(offline + " --no-align --out " + tmp.str("blurred"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto blurred = readJson(tmp.str("blurred/summary.json"));
  ASSERT_EQ(blurred["drives"][1]["merged"].size(), merged.size());
  for (const auto& m : blurred["drives"][1]["merged"]) {
    EXPECT_FALSE(m["aligned"].get<bool>());
    EXPECT_EQ(m["why"], "alignment off");
  }
}
