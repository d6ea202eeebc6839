// A short road that lanemap-offline maps before the road it leads into (issue 16,
// core/mapping/carried_lanes.h): on Roosevelt's cycle-track corridor (data/osm/dev, a 30 s drive,
// seed 1, camera only, truth labels) the car turns into a link between two junctions (road 19,
// 10 m between their ROIs) that no frame shows as drivable; exploring finds nothing and no mapped
// road runs straight into it, so it is left with no lane. When the road it runs straight into is
// mapped, a little later, the link is mapped again and takes that road's lanes (summary.json: the
// link listed before its source, with lanes_carried_from naming it), and they lie on the link's
// true lanes. (The broad benchmark's 150 s drive of this seed drives the same link; ~25 s here.)
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "core/io/lanelet2.h"
#include "tests/common/sim_drive.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <map>
#include <set>

namespace {

namespace lt = lanemap::testing;

TEST(ShortRoadOffline, ALinkMappedWithNoLaneTakesTheLanesOfTheRoadAfterItOnceThatIsMapped) {
  const std::string drive = lt::sharedSimDrive("osm/dev/roosevelt_cycletrack.osm", 30.0, 1, "--no-lidar");
  ASSERT_FALSE(drive.empty());
  lt::TempDir out("short-road-offline");
  const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --log " + drive + "/drive.lcmlog --osm " +
                                drive + "/roads.osm --out " + out.str("map"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream sj(out.str("map/summary.json"));
  const auto summary = nlohmann::json::parse(sj);
  // Each road's place in the mapping order and its entry.
  std::map<int64_t, size_t> order;
  std::map<int64_t, nlohmann::json> entry;
  for (size_t i = 0; i < summary["roads"].size(); ++i) {
    const auto& e = summary["roads"][i];
    const int64_t id = e["road_id"].get<int64_t>();
    if (!order.count(id)) order[id] = i;
    entry[id] = e;
  }
  // The links that took the lanes of the road after them, mapped after them.
  std::set<lanemap::eval::RoadKey> links;
  for (const auto& [id, e] : entry) {
    if (!e.contains("lanes_carried_from")) continue;
    const int64_t from = e["lanes_carried_from"].get<int64_t>();
    ASSERT_TRUE(entry.count(from)) << "road " << id << " carried lanes from road " << from << ", which is not mapped";
    if (entry[from]["from"] != e["to"]) continue;  // the road before it
    EXPECT_LT(order[id], order[from]) << "road " << id << " was mapped after the road it took its lanes from";
    EXPECT_GE(e["lanes"].get<int>(), 1);
    links.insert({e["from"].get<int64_t>(), e["to"].get<int64_t>()});
  }
  ASSERT_GE(links.size(), 1u) << "no short road took the lanes of the road after it";

  // Their lanes lie on the links' true lanes (detected: IoU or centre RMS within the thresholds).
  const auto origin = lanemap::eval::lanelet2Origin(drive + "/groundtruth.osm");
  const auto truth = lanemap::io::readLanelet2(drive + "/groundtruth.osm", origin.lat, origin.lon);
  const auto built = lanemap::io::readLanelet2(out.str("map/map.osm"), origin.lat, origin.lon);
  const auto report = lanemap::eval::evaluate(lanemap::eval::restrictToRoads(truth, links), built);
  ASSERT_GT(report.lane_recall.total, 0u);
  EXPECT_EQ(report.lane_recall.hits, report.lane_recall.total) << "a carried lane off its link's true lane";
}

}  // namespace
