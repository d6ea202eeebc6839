// Parameters of lane exploration (METHOD.md section 4, Algorithm 1), with the paper's values as
// defaults. config/lane_mapper.yaml `explorer:` holds the same keys; fromYaml reads the ones present.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <stdexcept>

namespace lanemap::config { class YamlReader; }

namespace lanemap::lanes {

class LanesError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ExplorerOptions {
  // --- particle filter (the paper's values) ---
  int num_particles = 500;
  double footprint_length_m = 3.0;
  double footprint_width_m = 1.5;
  double v_min = 0.9, v_max = 1.1;       // m/s, drawn per particle per step
  double w_min = -0.2, w_max = 0.2;      // rad, drawn per particle per step (yaw noise)
  double dt_s = 1.0;                     // step; ~1 m of travel per step at the defaults
  double max_heading_rad = 1.0;          // |yaw - road heading| above this: the particle dies
  uint64_t seed = 1;                     // std::mt19937_64; a run is deterministic for a seed

  // --- which BEV cells kill a particle (fractions of the cell's observations) ---
  // A cell is a boundary when it shows a solid, dashed, curb line or a lane separation at least
  // this often; it is blocked when observed but drivable (lane classes + crosswalk + stop line,
  // which cross lanes and must not stop particles) less often than drivable_fraction. Unobserved
  // cells (fewer than min_observations) are passable but never give a lane a start (see births).
  double marking_fraction = 0.3;
  double separation_fraction = 0.3;
  int kill_min_count = 2;                // a line or a blocked cell needs at least this many
                                         //   observations saying so: one hit among a far cell's
                                         //   three or four is noise (fewer: the cell is what its
                                         //   other observations say, drivable or unobserved)
  double drivable_fraction = 0.5;
  int drivable_min_count = 1;            // ... unless seen drivable this often (0: off): a junction's
                                         //   frames label the roads around it background
  int min_observations = 1;

  // --- the road's corridor in its Frenet frame (d > 0 left of the driving direction) ---
  double corridor_half_width_m = 15.0;
  // Frenet frame samples along the skeleton polyline and their moving-average radius: the map
  // block's road_frame (config::RoadFrameConfig), set by LaneMapperSettings::explorerOptions.
  double frame_spacing_m = 0.5;
  double frame_smoothing_m = 6.0;
  bool right_hand_traffic = true;        // two-way road: our lanes are right of the divider
  double divider_search_m = 3.0;         // look for the direction divider within this of d = 0
  double divider_bin_m = 10.0;           // along s (also the bins of the carriageway search)
  double divider_reach_m = 20.0;         // a bin with no divider seen takes a seen one's at most this far along s, else d = 0 (0: any distance)
  double carriageway_wall_m = 1.0;       // blocked/curb this wide (most of a bin) ends our carriageway
  double kerb_wall_fraction = 0.7;       // ... so does a kerb seen along this share of a bin's rows
                                         //   (within line_tolerance_m of one column; 0: only walls)

  // --- births: particles seeded where a footprint fits on observed drivable ground no particle
  // covers (turn pockets, bus bays, a lane behind a parked car); the paper's strip at the start is
  // the first birth ---
  double birth_every_m = 2.0;
  double birth_min_free_m = 0.5;         // free footprint-centre interval at least this wide
  double birth_min_evidence = 0.6;       // fraction of the footprint cells observed drivable
  int birth_particles = 40;

  bool unnamed_lanes = true;             // lanes beyond the segmentation's +-2 lane classes: a
                                         //   blocked strip between painted lines (one dashed) is a lane
  double lane_width_min_m = 2.4;         // ... when the lines are this far apart ...
  double lane_width_max_m = 4.6;         // ... at most
  double line_tolerance_m = 0.3;         // ... a solid line or curb within this of a column in a row
                                         //   counts for that column (lines at a slant to the frame)
  bool blocked_lane_beyond_dashed_edge = true;  // the carriageway walk stopped at a dashed line with
                                         //   ground seen blocked beyond it: a lane as wide as the one
                                         //   on its near side lies beyond it (explorer.cc
                                         //   markBlockedLanesBeyondDashedEdges)

  // --- clustering and lanes ---
  double dbscan_eps_m = 1.0;             // the paper's value
  int dbscan_min_points = 4;
  double track_tolerance_m = 0.6;        // a cluster continues a lane whose d is within its range +- this
  double lane_gap_max_m = 20.0;          // a lane with no particles longer than this has ended
  bool flat_beyond_samples = true;       // before its first and after its last particle sample a lane
                                         //   runs parallel to the road (false: on at its fitted slope)
  double same_lane_m = 1.2;              // two lanes closer than this are one
  double min_lane_length_m = 10.0;       // shorter lanes are dropped (on a road shorter than this
                                         //   between its ROIs: shorter than 0.8 of that stretch)
  double short_road_min_m = 6.0;         // a road whose stretch between its two ROIs is shorter (a
                                         //   link between close junctions) is explored over this
                                         //   much around the stretch's middle, into the ROIs ...
  double short_road_line_run_m = 1.0;    // ... or, where its painted lines run along it in runs of
                                         //   at least this much, over their extent (at most
                                         //   short_road_min_m; shortLinkStretch) (0: never)
  double partial_min_driven_m = 2.0;     // the road a drive ended on is mapped when the car got this
                                         //   far past its start ROI (core/mapping/partial_road.h);
                                         //   under short_road_min_m driven, the stretch explored
                                         //   reaches back into the ROI, not past the car (but
                                         //   within short_road_min_m of the road's start node,
                                         //   see partial_road.h)
  double carry_lanes_max_m = 15.0;       // a road whose stretch between its ROIs is shorter takes the
                                         //   lanes of the road leading straight into it (carried_lanes.h)
                                         //   when exploring found no lane on it (0: never)
  double carry_max_turn_rad = 0.35;      // ... "straight": its heading turns by at most this at the junction
  bool lanes_from_osm_way = true;        // ... and when no mapped road runs straight into or out of it,
                                         //   the lanes its own OSM way gives (carried_lanes.h lanesFromOsmWay)
  bool drop_lanes_apart_from_carried = true;  // a short road's explored lanes more than a lane's width
                                         //   beyond those the road before runs on into are dropped
                                         //   (carried_lanes.h dropLanesApartFromCarried)
  bool add_carried_lanes_not_found = true;  // ... and where it found fewer, each of those lanes it
                                         //   missed is added (carried_lanes.h addCarriedLanesNotFound)
  double split_neighbour_m = 4.5;        // a lane born/ending this close to another splits/merges
  double pocket_taper_max_m = 40.0;      // a lane split off another (a turn pocket) starts where its
                                         //   taper does, looked for this far back (0: where it was found)
  double pocket_min_width_m = 0.6;       // ... where its two lines close in to under this
  bool pocket_to_junction = true;        // ... and one whose lines stay a lane apart (lane_width_min_m)
                                         //   back to the junction's ROI ran from the junction: it
                                         //   starts there, split from nothing (likewise at the end)
  double bulge_density_fraction = 0.15;  // a lane that splits off or merges into a lane with fewer
                                         //   particles per metre than this fraction of that lane's
                                         //   is noise beside it, not a lane
  double min_drivable_share = 0.1;       // a lane whose centre line crosses observed drivable ground
                                         //   at under this share of its length lies on nothing: dropped
                                         //   (0: never)
  double weak_density_fraction = 0.05;   // any lane with fewer particles per metre than this
                                         //   fraction of a lane over most of its stretch is
                                         //   dropped (0: never)
  double join_gap_max_m = 200.0;         // a lane the particles lost and found again at its offset
                                         //   this far on, over drivable ground no other lane holds,
                                         //   is one lane (0: never join)
  double join_min_drivable_share = 0.8;  // ... drivable: the straight line between the pieces, in
                                         //   at least this share of its metres
  double floating_lane_max_m = 100.0;    // a lane shorter than this beside a lane seen lane_gap_max_m
                                         //   before and after it (not a bay: out of a lane and back
                                         //   into it on the kerb side) is a glimpse of a far lane,
                                         //   not a lane: dropped (0: never)
  int lanes_beyond_dashed = 3;           // the outermost lane's bound is a dashed line: a lane of
                                         //   our direction lies beyond it (the far lanes of a wide
                                         //   road, past the segmentation's lane classes) where the BEV
                                         //   shows a strip without a kerb; at most this many added
                                         //   (explorer.cc addLanesBeyondDashedLines; 0: none)

  // --- centre line regression (Eq. 6) and way-points ---
  double bin_m = 1.0;                    // particle positions are binned along s (exact for Eq. 6)
  double break_spacing_m = 5.0;          // candidate break points
  double break_penalty_m2 = 0.3;         // a break must reduce the binned squared error by this
  double waypoint_spacing_m = 2.0;

  // --- boundaries ---
  double probe_max_m = 3.5;              // lateral probing range from the centre line
  double default_half_width_m = 1.75;    // bound where probing finds nothing
  // A probe whose lane half-width differs by more than this from the median of its
  // boundary_median_window neighbours along the lane (itself included) is an outlier (a gap in a
  // dashed line, a speck of noise): it takes that median, so a bound does not zigzag. 0: off.
  double boundary_outlier_m = 0.5;
  int boundary_median_window = 5;        // odd
  // A lane's centre line moves to midway between its probed bounds (by their median offset over
  // the way-points where both were found, if at most this; 0: off).
  double recentre_max_m = 0.4;

  static ExplorerOptions fromYaml(const YAML::Node& node);  // throws LanesError
  // From the `explorer:` section of a config (strict: the caller's finish() refuses other keys);
  // throws config::ConfigError naming the file and key.
  static ExplorerOptions fromYaml(const config::YamlReader& r);
  void validate() const;                                    // throws LanesError
};

}  // namespace lanemap::lanes
