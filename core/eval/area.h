// What part of the truth a drive could have mapped. A drive covers a few atomic roads of a city;
// scoring it against every lane of the city's truth measures the route, not the mapper. The paper
// scores the blocks it drove.
// - restrictToRoads keeps the truth's road lanelets of the given directed atomic roads (by their
//   lanemap:from_node/to_node) and the truth's intersection lanelets that lead from one kept road
//   lanelet to another.
// - restrictToDrivenRoads (lanemap-eval --driven): the roads the car drove to their end
//   intersection, from the drive's route (drivenRoads*). A driven road the map has no lanes on
//   still counts: its true lanes are missed (recall), which restrictToMappedRoads cannot see.
// - The road the drive ended on (issue 14) was driven from its start to where the car stopped:
//   restrictToDriven keeps its truth lanelets cut there (the line across the road through the
//   car's last position), so a map that has it as far as driven (lanemap's partial lanes) is
//   scored on what the car could see, and one without it misses those lanes. Dropping the road
//   (as restrictToRoads alone does) would count a partial road's lanes against precision.
// - Likewise the road the drive began on (where the car stood when the recording started, often
//   far into it) was driven from there to its end: its truth is cut at the car's first position,
//   the part behind the car dropped (nothing of it was seen), unless the drive drove the road
//   whole another time.
// - restrictToMappedRoads (lanemap-eval --mapped-roads-only): the roads the built map has lanes
//   on; optimistic, a road the mapper dropped does not count against it.
#pragma once

#include "core/geo/local_frame.h"
#include "core/map/lane_map.h"

#include <Eigen/Core>

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace lanemap::eval {

// A directed atomic road by its end intersections (OSM node ids): (from_node, to_node).
using RoadKey = std::pair<int64_t, int64_t>;

map::LaneMap restrictToRoads(const map::LaneMap& truth, const std::set<RoadKey>& roads);
// The same, where the truth joins two junctions by more than one atomic road (a street and the
// tunnel under it, both from node A to node B): of those, only the ones in `driven_road_ids` (the
// truth's road_id numbering) are kept, unless none of them is there (the ids are of another
// numbering: then all are kept, as above).
map::LaneMap restrictToRoads(const map::LaneMap& truth, const std::set<RoadKey>& roads,
                             const std::set<int64_t>& driven_road_ids);
map::LaneMap restrictToMappedRoads(const map::LaneMap& truth, const map::LaneMap& built);
// The lanelets `keep` with their successors among them, their bound and stop lines, and the rules
// and crosswalks over them (restricted to them; one over none of them is dropped).
map::LaneMap restrictToLanelets(const map::LaneMap& truth, const std::set<int64_t>& keep);

// The directed roads the map has road lanelets on.
std::set<RoadKey> mappedRoads(const map::LaneMap& built);

// The roads a simulated drive drove to their end intersection, from lanemap-sim's scenario.json
// ("route": [{from, to, left_utime}, ...]; a road with left_utime null, where the drive ended,
// was not closed and is not counted). Throws std::runtime_error naming the file on a missing file
// or a file without a route.
std::set<RoadKey> drivenRoadsFromScenario(const std::string& scenario_json_path);

// A road driven from its start to `end` (ENU of the frame the truth is read in), where the drive
// ended.
struct PartialDrive {
  RoadKey road{-1, -1};
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
};
// A road driven from `start` (ENU) to its end, where the drive began.
struct EnteredDrive {
  RoadKey road{-1, -1};
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
};
struct DrivenArea {
  std::set<RoadKey> roads;              // driven to their end intersection
  std::vector<PartialDrive> partial;    // the road the drive ended on (none when it ended in a junction)
  // The road the drive began on, when it was not also driven whole (none when the drive began in a
  // junction or drove that road again from its start).
  std::vector<EnteredDrive> entered;
  // The route's atomic road ids (lanemap-sim numbers them as the truth's road_id): which of two
  // roads between the same two junctions was driven. Empty: not known.
  std::set<int64_t> road_ids;
};

// drivenRoadsFromScenario, and the road the drive ended on (the route's entry with left_utime
// null) with the car's last position: the last row of trajectory.csv beside scenario.json (ENU of
// the scenario's "origin"), moved into `frame`; the road it began on (the route's first entry,
// when it is not in the route again) with the first row's position. Without trajectory.csv there
// is no partial road and no entered one. road_ids: every route entry's road_id.
DrivenArea drivenAreaFromScenario(const std::string& scenario_json_path, const geo::LocalFrame& frame);

// The truth's lanelets of `road` cut at the line across the road through `at`: with kKeepBefore
// the part before it kept (a lanelet wholly past it dropped, a stop line past it dropped, the cut
// lanelets' successors too: they end where the car stopped); with kKeepAfter the part after it (a
// lanelet wholly behind it dropped). The road's direction at `at` is that of the nearest of its
// truth centre lines; a point on the dropped side of the line and within 15 m of `at` sideways is
// cut off (a road bending back further away is not cut). The cut bounds are copies under fresh ids
// (a bound shared with another road stays whole for it).
enum class CutKeep { kKeepBefore, kKeepAfter };
map::LaneMap cutRoadAt(const map::LaneMap& truth, const RoadKey& road, const Eigen::Vector2d& at,
                       CutKeep keep = CutKeep::kKeepBefore);

// restrictToRoads of the roads driven to their end and the partial ones (of parallel roads between
// the same junctions, those of area.road_ids), the partial ones cut at where the car stopped and
// the entered one where the car started (cutRoadAt); crosswalks on the dropped side of a cut are
// dropped with the lanes there.
map::LaneMap restrictToDriven(const map::LaneMap& truth, const DrivenArea& area);

}  // namespace lanemap::eval
