// One line string for the line between opposite lanes. Each direction of a road is explored on its
// own (its own BEV, its own particles), so each has its own bound along the line between the two
// directions; likewise each connection through a junction has its own bounds. Where two such bounds
// lie on top of each other (the simulator's centre paint found to a few centimetres from both
// sides, a link's lanes from its OSM way bounded on the way's line beside explored ones, the
// virtual bounds of two opposite connections along the road's line through a junction), the map
// held two line strings where Lanelet2 expects one shared by the two lanelets (lanemap-check's
// shared_borders: 10 of the broad benchmark's 60 maps failed it on 2026-12-07, and
// aurora_sausage_link's 40 s drive that turns round at a dead end). Such a pair becomes one line:
// - Which pairs: a bound of a road's lanelets and a bound of its reverse's (skeleton reverse_id),
//   or two bounds of one intersection's lanelets, that run against each other, whose ends meet
//   within end_gap_max_m (one's start at the other's end, and back), and of which each has at
//   least `share` of its points every metre within tolerance_m of the other (lanemap-check flags
//   two lines at 0.9 within 0.1 m).
// - Which one stays: an observed line (not virtual) over a virtual one, else the first (the lower
//   road's; the lower line id in a junction). The other's lanelets take it as their bound, running
//   against them as Lanelet2 allows for a line shared by opposite directions (its loader aligns
//   bounds); a merge after which io::orientationProblem would find one of them misread is not made.
// - Lines that ended where the dropped line ended (the connections at the junctions, a stop line)
//   end where the kept line ends now, so the lanelets still meet node to node; their points
//   within taper_m of that end move by less and less (a line moved at its end alone would kink
//   there: Lanelet2's curvature warning).
// - Two bounds of one intersection's lanelets that run the same way, start within end_gap_max_m of
//   each other and end so, and lie on top of each other as above: one border of two neighbouring
//   connections drawn twice (the lanes they leave share no border at the road's end where their
//   probes of one painted line differ by its width: seattle_slip_lane, 2026-12-07) become one
//   line the same way, the lines ending at the dropped one's ends moved to the kept one's.
// Lines of one road's direction on top of each other are left as they are (toLaneMap shares the
// borders of neighbouring lanes).
#pragma once

#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"

#include <cstddef>

namespace lanemap::mapping {

struct SharedDividerOptions {
  double tolerance_m = 0.12;   // a point of one line this close to the other lies on it
  double share = 0.85;         // ... and this share of each line's points (every metre) does
  double end_gap_max_m = 0.5;  // one line's start within this of the other's end, and back
  double taper_m = 4.0;        // a line that ended at the dropped line's end is moved to the kept
                               //   line's, its points within this of that end by less and less
};

// Merges every such pair in `map` (the assembled map: roads and intersections); returns how many
// lines were dropped.
size_t shareDividers(map::LaneMap& map, const skeleton::Skeleton& skeleton, const SharedDividerOptions& options = {});

}  // namespace lanemap::mapping
