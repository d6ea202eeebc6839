// speedLimitsKmh (core/io/speed_limits.h): OSM maxspeed of the atomic roads' ways, in km/h, and
// the simulator's ground truth carries it as Lanelet2's speed_limit.
#include "core/io/lanelet2.h"
#include "core/io/speed_limits.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <fstream>

namespace {

namespace lt = lanemap::testing;

TEST(SpeedLimits, FromMaxspeedOfTheRoadsWays) {
  std::string text = lt::readFile(lt::dataPath("osm/west-oakland.osm"));
  // The extract has no maxspeed: give the secondary roads 25 mph.
  size_t tagged = 0;
  const std::string secondary = "<tag k=\"highway\" v=\"secondary\"/>";
  for (size_t at = text.find(secondary); at != std::string::npos; at = text.find(secondary, at + 80)) {
    text.insert(at, "<tag k=\"maxspeed\" v=\"25 mph\"/>");
    ++tagged;
  }
  ASSERT_EQ(tagged, 5u);
  lt::TempDir dir("speed");
  std::ofstream(dir.str("wo.osm")) << text;
  const auto sk = lanemap::skeleton::Skeleton::build(lanemap::osm::readOsm(dir.str("wo.osm")));
  const auto limits = lanemap::io::speedLimitsKmh(sk);
  size_t secondary_roads = 0;
  for (const auto& road : sk.roads()) {
    const auto it = road.tags.find("highway");
    const bool is_secondary = it != road.tags.end() && it->second == "secondary";
    secondary_roads += is_secondary;
    if (is_secondary) {
      ASSERT_TRUE(limits.count(road.id)) << road.id;
      EXPECT_NEAR(limits.at(road.id), 40.2336, 1e-4);
    } else {
      EXPECT_FALSE(limits.count(road.id)) << road.id;
    }
  }
  EXPECT_GT(secondary_roads, 0u);
  EXPECT_EQ(limits.size(), secondary_roads);
  EXPECT_TRUE(lanemap::io::speedLimitsKmh(lanemap::skeleton::Skeleton::build(
                  lanemap::osm::readOsm(lt::dataPath("osm/west-oakland.osm"))))
                  .empty());
}

}  // namespace
