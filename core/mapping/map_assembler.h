// The lane-level map as it grows during a drive: the lanes of every closed atomic road (from
// core/lanes) and the intersections joining them (core/intersections, METHOD.md section 5), built
// for every intersection with at least one mapped road in and one out. One place for the
// lane_mapper process, the viewer and the offline runner, so all write the same map for the same
// roads.
//
// Incremental (issue 14: closing a road costs the same in a store of 100 roads as of 3,000): an
// intersection depends on the lanes of its own incoming and outgoing roads only, so setRoad marks
// the two intersections at the road's ends, and update() rebuilds those and keeps every other
// one as built. map() assembles the whole map from the roads and the kept intersections (linear in
// the map's size, no intersection rebuilt): for an export, not per road.
#pragma once

#include "core/intersections/intersections.h"
#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace lanemap::mapping {

class MapAssembler {
 public:
  // The skeleton must outlive the assembler. `restrictions`: the OSM turn restrictions
  // (osm::OsmData::restrictions), which the skeleton does not keep.
  MapAssembler(const skeleton::Skeleton& skeleton, intersections::IntersectionOptions options = {},
               std::vector<osm::Restriction> restrictions = {});

  // Replaces the lanes of one road (a road driven again is mapped again on everything seen) and
  // marks the intersections at its two ends for update(). A two-way link's two directions, once
  // both are set, are cut to the stretch both cover (two_way_links.h; both set again from the
  // lanes as given, so the outcome does not depend on the order).
  void setRoad(int64_t road_id, map::LaneMap lanes);
  // Every road's lanes as in the map (two-way links cut).
  const std::map<int64_t, map::LaneMap>& roads() const { return roads_; }
  // How often setting a road cut a two-way link's two directions to one stretch.
  size_t twoWayLinksCut() const { return two_way_links_cut_; }

  // The car's path from one road to the next through their intersection (driven_passage.h): it
  // shapes that road pair's connections; marks the intersection for update(). Kept in a fixed
  // order (roads, then the path), so the map is the same whatever order passages come in. One
  // whose roads do not meet at an intersection is ignored (false).
  bool addPassage(intersections::DrivenPassage passage);
  // Every passage added, by intersection (skeleton order), each intersection's in their fixed order.
  std::vector<intersections::DrivenPassage> passages() const;
  size_t passageCount() const;

  // Builds the intersections marked since the last call; returns how many it built (a failure
  // counts). Costs what those intersections cost, whatever the number of roads.
  size_t update();

  // The intersections as built (update() first), in the skeleton's intersection order, and the
  // ones that failed ("intersection ID: reason").
  std::vector<const intersections::IntersectionResult*> intersections();
  std::vector<std::string> failures();

  // Every road's lanelets (roads in id order) plus the intersections (update() first), in the
  // skeleton's ENU origin: deterministic for the same roads, whatever order they were set in. An
  // intersection that cannot be built is left out and named in `failures` (when given).
  map::LaneMap map(std::vector<std::string>* failures = nullptr);

 private:
  struct Built {
    std::optional<intersections::IntersectionResult> result;  // none: connects nothing
    std::string failure;                                      // why building it threw
  };
  const skeleton::Skeleton& skeleton_;
  intersections::IntersectionOptions options_;
  std::vector<osm::Restriction> restrictions_;
  void markEnds(int64_t road_id);
  std::map<int64_t, map::LaneMap> roads_;   // as in the map
  std::map<int64_t, map::LaneMap> as_set_;  // as setRoad was given them: two-way links only
  size_t two_way_links_cut_ = 0;
  std::map<int64_t, size_t> index_of_intersection_;  // intersection id -> index in the skeleton's list
  std::map<size_t, Built> built_;                     // by that index: ordered as the skeleton's list
  std::map<size_t, std::vector<intersections::DrivenPassage>> passages_;  // by that index
  std::set<size_t> marked_;
};

}  // namespace lanemap::mapping
