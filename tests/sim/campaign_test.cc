// Many drives of one world (issue 14): lanemap-sim --world-seed fixes the world, --seed the drive;
// a drive of a campaign carries its own constant pose offset.
#include "core/geo/local_frame.h"
#include "lanemap/pose_t.hpp"
#include "processes/framework/pose_conversion.h"
#include "tests/common/lcm_log.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace lt = lanemap::testing;
using lanemap::testing::readFile;

namespace {

std::vector<lanemap::EnuPose> poses(const std::string& dir, const lanemap::geo::LocalFrame& frame) {
  std::vector<lanemap::EnuPose> out;
  for (const auto& m : lt::readLcmLog(dir + "/drive.lcmlog")) {
    if (m.channel != "POSE") continue;
    lanemap::pose_t p;
    if (p.decode(m.data.data(), 0, static_cast<int>(m.data.size())) < 0) continue;
    out.push_back(lanemap::toEnuPose(p, frame));
  }
  return out;
}

}  // namespace

TEST(Campaign, TheWorldSeedFixesTheWorldAndEachDriveHasItsOwnOffset) {
  lt::TempDir tmp("campaign");
  const std::string base = lt::binPath("lanemap-sim") + " -q --osm " + lt::dataPath("osm/west-oakland.osm") +
                           " --duration 6 --no-lidar --camera-hz 1 ";
  // alone: seed 3 on its own; a, b: two drives of world 3 (a with the same drive seed as alone).
  for (const auto& [name, args] : {std::pair<std::string, std::string>{"alone", "--seed 3"},
                                   {"a", "--world-seed 3 --seed 3"},
                                   {"b", "--world-seed 3 --seed 4"}}) {
    const auto r = lt::runCommand(base + args + " --out " + tmp.str(name));
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
  }
  const std::string truth = readFile(tmp.str("alone/groundtruth.osm"));
  ASSERT_GT(truth.size(), 1000u);
  EXPECT_EQ(readFile(tmp.str("a/groundtruth.osm")), truth);
  EXPECT_EQ(readFile(tmp.str("b/groundtruth.osm")), truth) << "another drive seed changed the world";
  EXPECT_NE(readFile(tmp.str("a/drive.lcmlog")), readFile(tmp.str("b/drive.lcmlog")));

  const auto sa = nlohmann::json::parse(readFile(tmp.str("a/scenario.json")));
  const auto sb = nlohmann::json::parse(readFile(tmp.str("b/scenario.json")));
  const auto s0 = nlohmann::json::parse(readFile(tmp.str("alone/scenario.json")));
  EXPECT_EQ(sa["world_seed"], 3);
  EXPECT_EQ(sb["world_seed"], 3);
  EXPECT_EQ(s0["pose_offset"]["east_m"], 0.0);  // a drive on its own: no offset
  const Eigen::Vector2d off_a(sa["pose_offset"]["east_m"].get<double>(), sa["pose_offset"]["north_m"].get<double>());
  const Eigen::Vector2d off_b(sb["pose_offset"]["east_m"].get<double>(), sb["pose_offset"]["north_m"].get<double>());
  EXPECT_GT(off_a.norm(), 0.01);
  EXPECT_LT(off_a.cwiseAbs().maxCoeff(), 2.5);  // 5 sigma of 0.5 m
  EXPECT_GT((off_a - off_b).norm(), 0.01) << "two drives drew the same offset";

  // The campaign drive's poses are the lone drive's (same drive seed, same noise draws) moved by
  // exactly its offset, and turned by its heading offset.
  const lanemap::geo::LocalFrame frame({s0["origin"]["lat"].get<double>(), s0["origin"]["lon"].get<double>(), 0.0});
  const auto p0 = poses(tmp.str("alone"), frame);
  const auto pa = poses(tmp.str("a"), frame);
  ASSERT_EQ(p0.size(), pa.size());
  ASSERT_GT(p0.size(), 500u);
  const double heading_off = sa["pose_offset"]["heading_deg"].get<double>() * M_PI / 180.0;
  EXPECT_GT(std::abs(heading_off), 1e-6);
  double worst = 0, worst_heading = 0;
  for (size_t i = 0; i < p0.size(); ++i) {
    worst = std::max(worst, (pa[i].position.head<2>() - p0[i].position.head<2>() - off_a).norm());
    worst_heading = std::max(worst_heading, std::abs(std::remainder(pa[i].heading - p0[i].heading - heading_off, 2 * M_PI)));
  }
  EXPECT_LT(worst, 1e-3);
  EXPECT_LT(worst_heading, 1e-6);
}
