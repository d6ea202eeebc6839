// The lane-level map as it grows during a drive: the lanes of every closed atomic road (from
// core/lanes) and the intersections joining them (core/intersections, METHOD.md section 5), built
// for every intersection with at least one mapped road in and one out. One place for the
// lane_mapper process and the offline runner, so both write the same map for the same roads.
#pragma once

#include "core/intersections/intersections.h"
#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lanemap::mapping {

class MapAssembler {
 public:
  // The skeleton must outlive the assembler. `restrictions`: the OSM turn restrictions
  // (osm::OsmData::restrictions), which the skeleton does not keep.
  MapAssembler(const skeleton::Skeleton& skeleton, intersections::IntersectionOptions options = {},
               std::vector<osm::Restriction> restrictions = {});

  // Replaces the lanes of one road (a road driven again is mapped again on everything seen).
  void setRoad(int64_t road_id, map::LaneMap lanes);
  const std::map<int64_t, map::LaneMap>& roads() const { return roads_; }

  // Every road's lanelets (roads in id order) plus the intersections built from them, in the
  // skeleton's ENU origin: deterministic for the same roads. An intersection that cannot be built
  // is left out and named in `failures` (when given).
  map::LaneMap map(std::vector<std::string>* failures = nullptr) const;

 private:
  const skeleton::Skeleton& skeleton_;
  intersections::IntersectionOptions options_;
  std::vector<osm::Restriction> restrictions_;
  std::map<int64_t, map::LaneMap> roads_;
};

}  // namespace lanemap::mapping
