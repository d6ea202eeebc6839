// lanemap-sim --cover (issue 14): a second drive planned on a coverage file that lists the first
// drive's roads as mapped follows its coverage plan (core/mapping/coverage.h planCoverage) and
// drives mostly roads the first did not; a coverage file of another skeleton is refused, naming the
// road that does not fit.
#include "core/config/map_config.h"
#include "core/mapping/coverage.h"
#include "core/osm/osm_data.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

namespace {

const std::string kOsm = std::string(LANEMAP_SOURCE_DIR) + "/tests/replay/roads.osm";

nlohmann::json readJson(const std::string& path) {
  std::ifstream f(path);
  return nlohmann::json::parse(f);
}

// Its exit status; stdout and stderr go to `log`.
int sim(const std::string& args, const std::string& log) {
  return lanemap::testing::runCommand(std::string(LANEMAP_BIN_DIR) + "/lanemap-sim -q --osm " + kOsm + " --no-lidar --camera-hz 1 " +
                                      args + " > " + log)
      .exit_code;
}

TEST(SimCover, ASecondDriveFollowsTheCoveragePlanOverRoadsTheFirstDidNotDrive) {
  lanemap::testing::TempDir tmp("sim-cover");
  ASSERT_EQ(sim("--seed 1 --duration 60 --out " + tmp.str("d1"), tmp.str("d1.log")), 0);
  const auto s1 = readJson(tmp.str("d1/scenario.json"));
  std::set<int64_t> first;
  for (const auto& r : s1["route"]) first.insert(r["road_id"].get<int64_t>());
  ASSERT_GE(first.size(), 3u);

  // The coverage file lanemap-coverage would write after the first drive: its roads mapped.
  const auto sk = lanemap::skeleton::Skeleton::build(
      lanemap::osm::readOsm(kOsm), lanemap::config::MapConfig::fromYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/map.yaml").skeleton);
  nlohmann::json cov{{"roads", nlohmann::json::array()}};
  for (const auto& r : sk.roads()) {
    const bool mapped = first.count(r.id) > 0;
    cov["roads"].push_back({{"road_id", r.id}, {"from", r.from}, {"to", r.to}, {"state", mapped ? "mapped" : "never_driven"},
                            {"length_m", r.length}, {"mapped_m", mapped ? r.length : 0.0}});
  }
  std::ofstream(tmp.str("cov.json")) << cov.dump();

  // From a junction (the default start, out of a dead end, may be a road longer than the drive:
  // core/mapping/coverage_test.cc tests it): the start of the first road the first drive missed.
  int64_t from = -1;
  for (const auto& r : sk.roads()) {
    if (!first.count(r.id) && !sk.intersection(r.from)->dead_end && !sk.intersection(r.to)->dead_end) {
      from = r.from;
      break;
    }
  }
  ASSERT_GE(from, 0);
  ASSERT_EQ(sim("--seed 2 --duration 60 --cover " + tmp.str("cov.json") + " --cover-from " + std::to_string(from) + " --out " + tmp.str("d2"),
                tmp.str("d2.log")),
            0)
      << tmp.str("d2.log");
  const auto s2 = readJson(tmp.str("d2/scenario.json"));
  ASSERT_TRUE(s2.contains("cover"));
  EXPECT_EQ(s2["cover"]["from"].get<int64_t>(), from);
  const auto plan = s2["cover"]["roads"].get<std::vector<int64_t>>();
  ASSERT_FALSE(plan.empty());
  double driven = 0.0, fresh = 0.0;
  size_t i = 0;
  for (const auto& r : s2["route"]) {
    const int64_t id = r["road_id"].get<int64_t>();
    ASSERT_LT(i, plan.size());
    EXPECT_EQ(id, plan[i]) << "road " << i << " of the drive is the plan's";
    ++i;
    const double len = sk.road(id)->length;
    driven += len;
    if (!first.count(id)) fresh += len;
  }
  std::printf("second drive: %zu roads, %.0f m, %.0f m not in the first drive (%zu roads)\n", i, driven, fresh, first.size());
  EXPECT_GE(i, 2u);
  EXPECT_GE(fresh, 0.7 * driven);

  // A coverage file of another skeleton: a road whose ends are not this skeleton's.
  cov["roads"][0]["to"] = cov["roads"][0]["to"].get<int64_t>() + 1;
  std::ofstream(tmp.str("other.json")) << cov.dump();
  EXPECT_NE(sim("--seed 2 --duration 10 --cover " + tmp.str("other.json") + " --out " + tmp.str("d3"), tmp.str("d3.log")), 0);
  const std::string err = lanemap::testing::readFile(tmp.str("d3.log"));
  EXPECT_NE(err.find("another OSM file or map config"), std::string::npos) << err;
  EXPECT_NE(sim("--seed 2 --duration 10 --cover " + tmp.str("cov.json") + " --route 1,2 --out " + tmp.str("d4"), tmp.str("d4.log")), 0)
      << "--cover and --route exclude each other";
}

}  // namespace
