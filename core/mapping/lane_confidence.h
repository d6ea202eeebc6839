// Per-lane confidence (issue 14): a number in [0, 1] from the evidence behind an explored lane, so
// a map user can tell the lanes to trust from those to check. The mean of five shares (four for a
// lane with no line to measure the agreement by):
// - observed: the share of the lane's way-points whose BEV cell was seen drivable;
// - bounds: the share of its boundary points that the probe found (a marking, curb or the end of
//   the drivable area) rather than put at default_half_width_m from the centre;
// - support: the lane's particle density (particle positions behind its regression per metre)
//   relative to the best-supported lane of its road (a spurious lane beside a real one is
//   carried by few particles);
// - repeat: the traversals behind the road's evidence, each counted by how well it agreed with
//   the evidence it joined (BevGrid::agreement: the alignment's correlation, 0 when merged
//   unaligned): 1 - 0.5^(1 + agreement). One drive gives 0.5, two that agree perfectly 0.75,
//   three 0.875. It is the road's, not the lane's: alignment measures the agreement of a road's
//   markings as a whole.
// - agreement: the lane's own. Where its bounds are lines (dashed, solid or a kerb), the share of
//   those lines' evidence across each bound (kAgreementWindowM either side, every way-point)
//   that lies within kAgreementCoreM of it: observations that agree where the line is (those of
//   one drive, and of every traversal after alignment) pile up on it; traversals that disagree
//   about this lane (misaligned here, or one that saw it wrongly) spread its lines. A lane whose
//   bounds are both virtual has none (std::nullopt) and its value is the mean of the other four.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/lanes/explorer.h"
#include "core/map/lane_map.h"

#include <optional>
#include <vector>

namespace lanemap::mapping {

struct LaneConfidence {
  double observed = 0.0, bounds = 0.0, support = 0.0, repeat = 0.0;
  std::optional<double> agreement;
  double value() const {
    return agreement ? (observed + bounds + support + repeat + *agreement) / 5.0 : (observed + bounds + support + repeat) / 4.0;
  }
};

inline constexpr double kAgreementWindowM = 0.6;  // line evidence looked for this far either side of a bound
inline constexpr double kAgreementCoreM = 0.15;   // a line (0.15 m of paint) lies within this of its bound

// One per lane of `result` (same order).
std::vector<LaneConfidence> laneConfidences(const bev::BevGrid& grid, const lanes::ExplorationResult& result,
                                            const lanes::ExplorerOptions& options);

// Sets every road lanelet's confidence in `lanes` (toLaneMap(result)) to its lane's: the lane
// whose centre is nearest the lanelet's middle point.
void setConfidence(map::LaneMap& lanes, const lanes::ExplorationResult& result, const std::vector<LaneConfidence>& confidence);

}  // namespace lanemap::mapping
