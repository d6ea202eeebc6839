// The simulator's West Oakland world (seed 3) as the map-level tests use it: the OSM data, its
// skeleton, the world, and its truth's road lanelets by road id (standing for mapped roads). Built
// once per test binary.
#pragma once

#include "core/intersections/intersections.h"
#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/sim_drive.h"

#include <cstdint>
#include <map>
#include <memory>

namespace lanemap::testing {

struct TruthWorld {
  osm::OsmData data;
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<sim::SimWorld> world;
  std::map<int64_t, map::LaneMap> roads;  // the truth's road lanelets by road id
};

inline const TruthWorld& westOaklandTruthWorld() {
  static const TruthWorld w = [] {
    TruthWorld w;
    w.data = osm::readOsm(dataPath("osm/west-oakland.osm"));
    w.sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(w.data));
    sim::WorldOptions wo;
    wo.seed = 3;
    w.world = sim::buildWorld(*w.sk, wo);
    w.roads = intersections::roadsOf(w.world->truth());
    return w;
  }();
  return w;
}

}  // namespace lanemap::testing
