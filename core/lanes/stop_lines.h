// Stop lines from the BEV (issue 15): at the end of every lane of a road's lane map that ends
// there (a lanelet with no successor), the band across the lane whose cells the segmentation saw
// as stop-line paint. Scanned from the lanelet's end backwards over `search_m` in `step_m`
// stations; at each station `samples` points spread across the lane (10 % .. 90 % of its width)
// count as paint when their cell was observed at least `min_observed` times and its kStopLine
// fraction is at least `min_fraction`. A station is paint when at least `min_cover` of its samples
// are; the stop line lies at the middle of the run of paint stations nearest the lane's end.
// Lanes whose stop lines lie within `merge_m` of each other along the road share one stop line
// from the left bound of the left-most to the right bound of the right-most (as one painted bar
// across an approach). The lanelets get stop_line_id; the lines (type kStopLine) get fresh ids.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/map/lane_map.h"

#include <cstddef>
#include <vector>

namespace lanemap::lanes {

struct StopLineOptions {
  double search_m = 15.0;
  double step_m = 0.1;
  int samples = 9;
  int min_observed = 3;
  double min_fraction = 0.3;
  double min_cover = 0.6;
  double merge_m = 1.0;
};

// Adds the stop lines found to `road_map` (one road's lanes, e.g. from toLaneMap). Returns how many.
size_t addStopLines(const bev::BevGrid& grid, map::LaneMap& road_map, const StopLineOptions& options = {});

// Crosswalks from the BEV: at both ends of a road's lanes (the first and last `search_m`), the
// stations along the road where at least `min_cover` of the samples across its lanes (every
// `step_m`) are crosswalk paint (kCrosswalk fraction >= min_fraction of >= min_observed
// observations; the stripes cover about half of a crossing). A run of such stations (gaps up to
// `max_gap_m`) at least `min_depth_m` long is a crosswalk: its edges are the run's first and last
// stations, reaching across the road's lanes and on beyond them as far as the paint goes (gaps
// up to max_gap_m, at most `beyond_m`), so a crossing seen over both directions spans both. A
// run's end stations whose edge would be under `min_edge_m` long (a lane tapering to its end, no
// paint beyond it) are left out of it: an edge millimetres long is Lanelet2's points_too_close.
struct CrosswalkOptions {
  double search_m = 15.0;
  double step_m = 0.1;
  int min_observed = 3;
  double min_fraction = 0.3;
  double min_cover = 0.3;
  double max_gap_m = 0.8;
  double min_depth_m = 1.5;
  double beyond_m = 10.0;
  double min_edge_m = 1.0;
};

// The crosswalks found over one road's lanes (crossing = those lanes' lanelets), ids from `first_id`.
std::vector<map::Crosswalk> findCrosswalks(const bev::BevGrid& grid, const map::LaneMap& road_map,
                                           int64_t first_id, const CrosswalkOptions& options = {});

// Crosswalks of several roads that are one crossing (centres closer than `merge_m`, e.g. found
// from both directions of a road) become one: the wider, crossing the lanelets of both.
void mergeCrosswalks(std::vector<map::Crosswalk>& crosswalks, double merge_m = 3.0);

// Adds crosswalks found road by road to the assembled map: fresh ids above every id of the map,
// `crossing` kept to the lanelets the map has, merged with mergeCrosswalks. Returns how many.
size_t addCrosswalks(map::LaneMap& map, std::vector<map::Crosswalk> found, double merge_m = 3.0);

}  // namespace lanemap::lanes
