// Lane exploration on one closed atomic road (METHOD.md section 4, Algorithm 1). exploreRoad runs
// the steps below, each a function of explorer.cc named after it: buildRaster (1); ParticleFilter's
// seedStartStrip, then per step predict, kill, clusterAndTrack, resample and births (2-3);
// fitLanes (4); probeBoundaries and extendPocketsToTheirTaper (5); addLanesBeyondDashedLines (6), indexLanesFromLeft.
//
// 1. The road's BEV evidence is resampled into a straightened raster in the road's Frenet frame
//    (s along the skeleton, d to the left), each cell classified once: unobserved, drivable,
//    blocked (observed, not drivable), lane separation, dashed, solid, curb, or outside our
//    direction (beyond the divider of a two-way road). A line or a blocked cell needs
//    kill_min_count observations saying so (a far cell is seen 2-4 times, and one stray label
//    among them is noise, not a boundary): with fewer, the cell is what its other observations
//    say (drivable, else unobserved). A cell seen drivable drivable_min_count times is drivable
//    (frames taken in a junction label the roads around it background); a blocked strip a lane
//    wide between painted lines (one dashed, or drivable somewhere along the bin, or holding a one-way road's line, or beside a two-way road's divider; a kerb at a slant
//    to the frame counts within line_tolerance_m) is a lane the segmentation does not name (beyond its +-2 lane classes, or seen from the junction
//    before the road: the lane classes are the ego lane's cross-section's only). Only the
//    explored stretch kills a particle (past the ROI edges lie the junctions). Our carriageway ends
//    at the first wall (blocked ground a metre wide) or kerb either side: beyond it is outside; but
//    where the walk stopped at a dashed line with ground seen blocked beyond it (a road seen from
//    the junction before it, whose far lanes have no line the camera caught), a lane as wide as
//    the one on its near side is put back beyond it (markBlockedLanesBeyondDashedEdges,
//    blocked_lane_beyond_dashed_edge). A road whose stretch between its ROIs is shorter than
//    short_road_min_m is explored over that much around its middle (explorationStretch).
// 2. Particle filter: N car footprints (3 m x 1.5 m) start as a strip across the road start and
//    move by the paper's motion model (Eq. 5) with v ~ U(0.9, 1.1), w ~ U(-0.2, 0.2) per particle
//    per step, in Frenet coordinates so they follow a curved road. A footprint that touches a
//    boundary cell dies; dead particles are replaced by copies of surviving particles *near them
//    in d* (local resampling: the paper's survival weights, without letting one lane's particles
//    take over another's by drift). Births: where a footprint fits on observed drivable ground that
//    no particle covers (a turn pocket opening, a bus bay, the lane after a parked car), particles
//    are seeded; the paper's start strip is the first birth, across the first observed drivable
//    ground within 30 m of the road's start (its lanes are carried back to the start); a road first
//    seen farther in (a drive that began on it) has its lanes start where it was seen, not made up
//    over ground nobody saw. Runs to s_end (the end ROI).
// 3. DBSCAN (eps 1 m) over the surviving particles of each step gives the lanes at that step;
//    clusters are linked along s into lanes, so a lane can start (split) or end (merge) mid-road; a
//    lane that loses its particles for less than lane_gap_max_m (parked car) continues; lanes
//    inside one wide cluster (a stretch with no markings) coast with their last offsets.
//    A piece beside a lane (splitting off it, merging into it) with a fraction of its particles is
//    dropped, and so is any lane holding under weak_density_fraction of the particles per metre
//    of a lane over half its stretch (a few particles that found room beyond a kerb).
// 4. Each lane's particle history is regressed (Eq. 6: piecewise linear with optimised break
//    points, then a natural cubic spline) as d(s); before its first and after its last sample
//    (a lane seen late, a track coasting beside another to the junction) it is held at its end
//    offsets, parallel to the road (flat_beyond_samples); way-points every waypoint_spacing_m. A lane
//    whose centre line crosses observed drivable ground at under min_drivable_share of its length
//    lies on nothing the camera saw as road (particles living on in unobserved ground) and is
//    dropped (dropLanesOnNothing).
// 5. Boundaries: from each way-point, probe left and right along the normal until a marking, curb,
//    blocked or outside cell; the marking type is kept (asymmetric, follows the drivable area).
//    The centre line then moves to midway between its bounds, by the median offset over the
//    way-points where both were found, at most recentre_max_m (recentreOnBounds): the particles'
//    mean lies midway between the lines' near edges, off by up to a fifth of a metre beside a
//    double line or a kerb. A lane split off another (a turn pocket) then starts where its taper
//    does, not where a footprint first fitted beside its parent, and a lane merging into another
//    ends where its taper closes (extendPocketsToTheirTaper); one whose lines stay a lane apart
//    back to the junction's ROI (a lane seen late after a turn, or lost in its last metres) runs
//    to the junction and splits from (merges into) nothing (pocket_to_junction).
// 6. A dashed line only separates lanes of one direction: where the outermost lane's bound is
//    dashed and the strip beyond is road the particles did not hold (the far lanes of a wide road,
//    beyond the segmentation's lane classes), a lane is added there (addLanesBeyondDashedLines,
//    lanes_beyond_dashed).
#pragma once

#include "core/bev/bev_grid.h"
#include "core/lanes/centre_line.h"
#include "core/lanes/frenet.h"
#include "core/lanes/options.h"
#include "core/map/lane_map.h"
#include "core/skeleton/skeleton.h"

#include <Eigen/Core>

#include <array>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace lanemap::lanes {

// One atomic road to explore (from skeleton::AtomicRoad).
struct RoadGeometry {
  int64_t road_id = -1;
  int64_t from_node = -1, to_node = -1;  // intersection ids I_i, I_j
  std::vector<Eigen::Vector2d> polyline;  // ENU, driving direction
  double s_begin = 0.0, s_end = 0.0;      // leaves I_i's ROI / enters I_j's ROI
  bool two_way = false;                   // the opposite direction shares the carriageway
  static RoadGeometry fromSkeleton(const skeleton::AtomicRoad& road);
};

// Ego pose when the car entered the road (ENU x, y, yaw): the strip starts across it.
struct EgoPose {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double yaw = 0.0;
};

struct Boundary {
  std::vector<Eigen::Vector2d> points;  // ENU, at the way-points of the lane
  std::vector<double> d;                // lateral offsets in the road frame
  map::LineType type = map::LineType::kVirtual;
};

struct Lane {
  int id = 0;                 // index in ExplorationResult::lanes
  int index_from_left = 0;    // at the middle of the lane, among the lanes present there
  double s_begin = 0.0, s_end = 0.0;
  CentreLine centre;          // d(s) in the road's Frenet frame
  std::vector<double> waypoint_s;
  std::vector<Eigen::Vector2d> waypoints;  // ENU
  Boundary left, right;
  int split_from = -1;        // lane this one branches off at s_begin (turn pocket, bay)
  int merges_into = -1;       // lane this one runs into at s_end
  int64_t particle_samples = 0;  // particle positions behind the regression
  double dAt(double s) const { return centre.d(s); }
};

struct ExplorationStats {
  int steps = 0;
  int births = 0;              // birth events (the start strip included)
  int64_t particle_steps = 0;  // particles moved and tested
  int64_t deaths = 0;
  int tracks = 0;              // lane tracks before dropping short ones
  int pieces_joined = 0;       // tracks joined to an earlier one as one lane (joinLanePieces)
  // Cells of the straightened raster per class: unobserved, drivable, blocked, separation, dashed,
  // solid, curb, outside (our direction's carriageway ends there).
  std::array<int64_t, 8> raster_cells{};
  double raster_s = 0.0, filter_s = 0.0, fit_s = 0.0;  // seconds
};

struct ExplorationResult {
  int64_t road_id = -1, from_node = -1, to_node = -1;
  std::shared_ptr<const FrenetFrame> frame;
  std::vector<Lane> lanes;  // left to right where they overlap
  ExplorationStats stats;
  // Lanes present at arc length s.
  int laneCountAt(double s) const;
  // Optional debug data (history_stride > 0): surviving particles (s, d) of every
  // `history_stride`-th step, and the straightened raster the particles ran on.
  std::vector<Eigen::Vector2d> history;
  struct DebugRaster {
    double s0 = 0.0, d0 = 0.0, resolution = 0.0;  // cell (i, j) covers s0 + i res.., d0 + j res..
    int rows = 0, cols = 0;                       // rows along s, columns along d (right to left)
    std::vector<uint8_t> code;                    // rows x cols, RasterClass values
  } raster;
};

// Classes of the straightened raster's cells (ExplorationResult::raster); >= kBlocked kills a
// particle's footprint.
enum RasterClass : uint8_t { kUnobserved = 0, kDrivable, kBlocked, kSeparation, kDashed, kSolid, kCurb, kOutside };
const char* toString(RasterClass c);

// The stretch [s_begin, s_end] of a road that exploreRoad explores (the road's own, between its
// two ROIs, clamped to the polyline's length; on a road shorter there than
// options.short_road_min_m, that much around the stretch's middle, which exploreRoad then moves
// to where the link's painted lines run, when they do: short_road_line_run_m).
RoadGeometry explorationStretch(const RoadGeometry& road, double length, const ExplorerOptions& options);

// Runs Algorithm 1 on a road's BEV grid. Deterministic for options.seed. Throws LanesError on a
// degenerate road (a polyline under 1 m long).
// What every way of finding a road's lanes starts with (exploreRoad, carryLanesThrough): options
// validated (throws LanesError), the road's ids and Frenet frame in an empty result, and in
// *stretch the stretch the lanes run over (explorationStretch). Throws LanesError for a road
// without a polyline.
ExplorationResult startExploration(const RoadGeometry& road, const ExplorerOptions& options, RoadGeometry* stretch);

ExplorationResult exploreRoad(const bev::BevGrid& grid, const RoadGeometry& road, const ExplorerOptions& options,
                              const std::optional<EgoPose>& ego = std::nullopt, int history_stride = 0);

// A lane boundary's offset at s: its probes (one per way-point), linearly interpolated; the end
// values beyond them. `b` is l.left or l.right, probed (as many offsets as way-points).
double boundaryD(const Lane& l, const Boundary& b, double s);

// Removes the lanes whose drop[id] is set (ids are indices into *lanes), renumbers the rest, their
// split and merge links with them (a link to a removed lane is none), and indexes them from the
// left again.
void removeLanes(const std::vector<bool>& drop, std::vector<Lane>* lanes);

// Two lanes of one road that run side by side over [s_begin, s_end] with the right bound of lane
// `left` on the left bound of lane `right` (their probes found the same line).
struct LaneNeighbours {
  int left = -1, right = -1;  // indices in ExplorationResult::lanes
  double s_begin = 0.0, s_end = 0.0;
};
struct LaneNeighbourOptions {
  double tolerance_m = 0.3;    // the two bounds' offsets differ by at most this ...
  double min_fraction = 0.8;   // ... at this share of the samples of their common stretch
  double min_overlap_m = 2.0;  // a common stretch shorter than this is not a neighbourhood
  double sample_m = 1.0;
};
std::vector<LaneNeighbours> laneNeighbours(const ExplorationResult& result, const LaneNeighbourOptions& options = {});

// The road's lanes as Lanelet2 lanelets (map::LaneMap): one lanelet per lane piece between split
// and merge points, left/right LineStrings typed by the probed marking, successors at splits and
// merges. Neighbouring lanes (laneNeighbours) are pieced at the same s over their common stretch
// and share one border line string there (halfway between their probes; typed by the stronger
// marking either saw), so Lanelet2's routing graph sees them as neighbours. Ids: (road_id + 1) * 100000 + k, so the roads of one map never collide.
map::LaneMap toLaneMap(const ExplorationResult& result, double origin_lat = 0.0, double origin_lon = 0.0,
                       double origin_alt = 0.0);

}  // namespace lanemap::lanes
