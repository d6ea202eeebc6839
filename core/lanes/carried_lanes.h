// Lanes carried through a short road (issue 16). A link between two close junctions is seen almost
// only from inside them: frames taken in a junction name no ego lane, so its BEV holds kerbs and
// junction ground, and often not one cell labelled drivable. Exploring it cannot find its lanes;
// the road the car came from, a moment earlier, showed them. Its lanes, where they end at the
// junction, keep their offsets from the OSM road line (the way runs on through the node) and run
// on through the short road.
// - When: the road's stretch between its ROIs is shorter than carry_lanes_max_m and exploring
//   found no lane on it. Where it found any, the road keeps them: its own evidence says where its
//   lanes are, and a road's lanes are where they are relative to its own OSM line (the line is the
//   carriageway's middle: where the lane count changes at the junction, every offset moves by
//   half a lane, so carried offsets cannot be checked against explored ones lane by lane).
// - What: one lane per carried lane over the road's explored stretch (explorationStretch), its
//   centre at the carried offset d, its bounds at the carried half-widths with the carried line
//   types. No particle supports them (particle_samples 0), which their confidence says.
// Which road leads into the short one, and its lanes there, is core/mapping/carried_lanes.h.
#pragma once

#include "core/lanes/explorer.h"
#include "core/map/lane_map.h"

#include <vector>

namespace lanemap::lanes {

// A lane of the road before, where it ends at the junction into the short road.
struct CarriedLane {
  double d = 0.0;                  // centre's offset from its road's line (its Frenet frame), m
  double half_left_m = 1.75;       // its left bound's offset from the centre
  double half_right_m = 1.75;      // its right bound's offset from the centre
  map::LineType left_type = map::LineType::kVirtual;
  map::LineType right_type = map::LineType::kVirtual;
  bool seen = true;                // false: made from the road's own OSM way (nothing seen of it)
};

// Whether `explored` (exploreRoad on `road`) gives way to `carried` lanes, as described above.
bool takesCarriedLanes(const RoadGeometry& road, const ExplorationResult& explored, size_t carried,
                       const ExplorerOptions& options);

// The road's lanes made of the carried ones (left to right, one of two closer than same_lane_m
// dropped). Throws LanesError for a road without a polyline or with nothing carried.
ExplorationResult carryLanesThrough(const RoadGeometry& road, std::vector<CarriedLane> carried,
                                    const ExplorerOptions& options);

// A short road's explored lanes apart from those that run on into it. On a link between close
// junctions the explored stretch is a few metres, too short for the carriageway walk (buildRaster)
// to see the kerb of an island along most of a bin: the other carriageway of a divided road across
// the island (a "sausage link") is then explored as lanes of ours. So, where exploring a road
// shorter than carry_lanes_max_m found more lanes than `carried` (the road before's lanes, seen:
// not its OSM way's; of those, the ones side by side nearest the road's line, as a lane more than
// lane_width_max_m from the rest was itself explored across an island), the explored lanes are
// matched to the carried ones under one common shift of at most lane_width_max_m / 2 (on a
// one-way road the OSM line is the carriageway's middle, which moves by half a lane where the lane
// count changes), the shift matching the most lanes within same_lane_m (of equals the smallest;
// each lane's offset its centre's mean over its stretch); from the matched lanes outwards a lane whose centre
// lies within lane_width_max_m of a kept one is kept (a lane added beside them: a pocket, a
// flare); the rest lie over a lane's width beyond every kept lane and are dropped. Nothing matched,
// or options.drop_lanes_apart_from_carried off: nothing dropped. Returns how many were dropped.
int dropLanesApartFromCarried(const RoadGeometry& road, const std::vector<CarriedLane>& carried,
                              const ExplorerOptions& options, ExplorationResult* explored);

// A short road's lanes that exploring missed but the road before runs on with. Over a link's few
// explored metres, seen mostly from inside the junctions, a lane whose ground the segmentation
// labelled background there (the ego lane's cross-section only is named) is not explored. So,
// where exploring a road shorter than carry_lanes_max_m found fewer lanes than `carried` (the same
// carried lanes as above: seen ones, the group side by side nearest the road's line) and every
// explored lane lies within same_lane_m / 2 of a carried one under one common shift of at most as
// much (where they fit only with a one-way road's line moved by half a lane, the lane count
// changed at the junction: nothing is added), each carried lane with no explored lane within
// lane_width_min_m of its shifted offset is added, over the explored lanes' stretch, as wide as it
// was carried and with its line types, against the lane inside it (its near bound that lane's
// bound, so the two share a border; outwards from the explored lanes; one between two explored
// lanes at its shifted offset); no particle supports it, which its confidence says. None beyond a
// kerb: where the outermost explored lane's outer bound is a kerb, the carriageway ends there. The
// carried lanes are the road before's through lanes (core/mapping/carried_lanes.h): a turn pocket
// ending at the junction is not among them.
// options.add_carried_lanes_not_found off: nothing added. Returns how many were added.
int addCarriedLanesNotFound(const RoadGeometry& road, const std::vector<CarriedLane>& carried,
                            const ExplorerOptions& options, ExplorationResult* explored);

}  // namespace lanemap::lanes
