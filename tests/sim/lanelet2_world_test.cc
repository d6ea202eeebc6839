// The simulator's world from a Lanelet2 map (core/sim/lanelet2_world.h): a small hand-made map
// and the Lanelet2 project's Karlsruhe example.
#include "core/sim/lanelet2_world.h"

#include "core/sim/drive.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <set>

namespace {

using namespace lanemap;

const sim::Lanelet2World& karlsruhe() {
  static sim::Lanelet2World* w = [] {
    sim::WorldOptions o;
    geo::LatLonAlt origin;
    origin.lat = 49.0;
    origin.lon = 8.4;
    return new sim::Lanelet2World(sim::buildLanelet2World(
        lanemap::testing::dataPath("lanelet2/karlsruhe_mapping_example.osm"), origin, o));
  }();
  return *w;
}

TEST(Lanelet2World, KarlsruheStats) {
  const auto& w = karlsruhe();
  const auto& s = w.stats;
  std::printf("map %zu vehicle %zu split %zu road %zu junction %zu areas %zu roads %zu unassigned %zu cross %zu stop %zu lines %zu curbs %zu; skeleton %zu roads %zu inters\n",
              s.map_lanelets, s.map_vehicle_lanelets, s.two_way_split, s.road_lanelets, s.junction_lanelets,
              s.junction_areas, s.roads, s.unassigned_lanelets, s.crosswalks, s.stop_lines, s.painted_lines, s.curbs,
              w.skeleton->roads().size(), w.skeleton->intersections().size());
  // chains of junction lanelets
  const auto& t = w.world->truth();
  size_t chains = 0, road_to_road = 0;
  for (const auto& l : t.lanelets) {
    for (int64_t s2 : l.successors) {
      const auto* n = t.lanelet(s2);
      if (l.kind == map::LaneletKind::kIntersection && n->kind == map::LaneletKind::kIntersection) ++chains;
      if (l.kind == map::LaneletKind::kRoad && n->kind == map::LaneletKind::kRoad && n->road_id != l.road_id) ++road_to_road;
    }
  }
  std::printf("junction->junction %zu, road->other road %zu\n", chains, road_to_road);
  sim::DriveOptions o;
  o.duration_s = 90;
  const auto plan = sim::planDrive(*w.skeleton, t, o);
  std::printf("plan roads %zu legs %zu\n", plan.roads.size(), plan.legs.size());
}

}  // namespace
