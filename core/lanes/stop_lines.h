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

}  // namespace lanemap::lanes
