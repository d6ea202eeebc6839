// A two-way link's two directions end their lanes at one place. Each direction of a road is
// explored on its own evidence, and a short link between close junctions is explored where its
// painted lines run (lanes::exploreRoad's short-link stretch): two views of the same paint give
// ends a few decimetres to a metre apart, and the line between the two directions is then two line
// strings, one partly on top of the other, that mapping::shareDividers cannot make one (its ends
// do not meet) - lanemap-check's shared_borders, or a centre line past a bound shared anyway.
// Both directions are cut to the stretch they share, so their bounds start and end together.
// - Which roads: a road and its reverse (skeleton reverse_id), both mapped, each wholly road
//   lanelets of that road (none partial), each lanelet running over its direction's whole stretch
//   (within piece_tolerance_m: one piece per lane, as on a short link), each stretch at most
//   max_length_m long (short links only: a long road's lanes are not cut to the other direction's).
// - When: the two stretches (along the road's polyline) differ at an end by more than
//   same_end_m and at most max_difference_m, and share at least min_shared_m.
// - The cut: every bound and centre line ends at the shared stretch's ends (points interpolated
//   there); a stop line at a lanelet's end moves with that end.
#pragma once

#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <optional>
#include <utility>

namespace lanemap::mapping {

struct TwoWayLinkOptions {
  double max_length_m = 10.0;      // a longer stretch is no short link: left alone
  double same_end_m = 0.05;        // ends this close are one end already
  double max_difference_m = 2.5;   // ends further apart are two different findings: left alone
  double min_shared_m = 2.0;       // the stretch both cover, at least
  double piece_tolerance_m = 0.3;  // a lanelet ending further than this from its direction's ends
                                   //   is a piece of a lane (a pocket, a split): left alone
};

// The stretch [s0, s1] along road `road_id`'s polyline that a road's map covers (its road lanelets'
// centre lines projected on that road), measured on the polyline of `on_road` (the road itself or
// its reverse). nullopt when the map does not qualify (see above).
std::optional<std::pair<double, double>> laneletStretch(const map::LaneMap& lanes, const skeleton::Skeleton& skeleton,
                                                        int64_t road_id, int64_t on_road, const TwoWayLinkOptions& options);

// Cuts every lanelet's bounds and centre line of `lanes` to [s0, s1] along `on_road`'s polyline
// (stop lines at a cut end move with it).
void cutToStretch(map::LaneMap& lanes, const skeleton::Skeleton& skeleton, int64_t on_road, double s0, double s1);

// Whether a road's lanes could be cut with its reverse's: a two-way road whose map qualifies.
bool mayMatchTwoWayLink(const map::LaneMap& lanes, const skeleton::Skeleton& skeleton, int64_t road_id,
                        const TwoWayLinkOptions& options = {});

// `a` (road a) and `b` (its reverse) cut to the stretch both cover, when they qualify; true when
// either was cut.
bool matchTwoWayLink(map::LaneMap& a, int64_t road_a, map::LaneMap& b, int64_t road_b,
                     const skeleton::Skeleton& skeleton, const TwoWayLinkOptions& options = {});

}  // namespace lanemap::mapping
