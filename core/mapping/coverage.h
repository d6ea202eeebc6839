// Coverage of a city by a map store (issue 14, `lanemap-coverage`): for every directed atomic road
// of the skeleton whether the store maps it (its lanes in lanes/road_<id>.osm: complete, or partial
// as far as a drive got), whether it was only driven (a BEV grid and no lanes yet), how many
// traversals its evidence holds (the grid's header: bev/road_<id>.bev, and a partial grid), and its
// lanes' mean confidence; and the share of the city's directed road length mapped.
#pragma once

#include "core/skeleton/skeleton.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::mapping {

enum class RoadState { kNeverDriven, kDriven, kPartial, kMapped };
const char* toString(RoadState s);  // "never_driven", "driven", "partial", "mapped"

struct RoadCoverage {
  int64_t road_id = -1, from = -1, to = -1;
  double length_m = 0.0;  // the directed road, junction to junction (AtomicRoad::length)
  RoadState state = RoadState::kNeverDriven;
  double mapped_m = 0.0;  // length_m when mapped, the station reached when partial, else 0
  int traversals = 0;     // drives whose evidence the road's grids hold (complete + partial)
  int frames = 0;
  int lanes = 0;          // lanes of the road in its lanes file (distinct index_from_left)
  std::optional<double> confidence;  // mean of its road lanelets' confidence, when they say
  std::vector<std::string> problems;  // files that could not be read (the road counts unmapped)
};

struct CityCoverage {
  std::vector<RoadCoverage> roads;  // every directed atomic road, by id
  double total_m = 0.0, mapped_m = 0.0;
  std::vector<std::string> problems;  // a whole-map file that could not be read
  double share() const { return total_m > 0.0 ? mapped_m / total_m : 0.0; }
  int count(RoadState s) const;
};

// The next drive (`lanemap-coverage --plan`): a route from an intersection that covers as much
// directed road length not yet mapped (never driven, driven without lanes, a partial road's rest)
// as it can in `seconds` of driving at `speed_mps`. Greedy with a look-ahead: at each
// intersection the first road of the path of up to `lookahead` roads that covers the most new
// length (the quicker path on a tie); where no such path starts, the quickest way to the nearest
// road left to cover. No U-turns (a driver avoids them; the simulator makes one only at a dead end
// an auto route cannot go on from, never on a given route): not back onto the road's reverse, nor
// a heading change over 150 degrees onto another road; OSM turn restrictions are not known here
// (nor does the simulator's world honour them; its junctions leave out U-turns by the same 150
// degrees). A dead end ends the route. When the time left is shorter than every road that would
// cover more, the route ends on the road leaving its last intersection with the most left to
// cover, as far as the time goes (its seconds and new_m count that part).
struct CoveragePlan {
  std::vector<int64_t> roads;          // directed atomic roads in driving order
  std::vector<int64_t> intersections;  // the first road's start, then each road's end (lanemap-sim --route)
  double seconds = 0.0;                // driving time of the route (at most the time given)
  double new_m = 0.0;                  // unmapped directed length it covers
};
CoveragePlan planCoverage(const skeleton::Skeleton& skeleton, const CityCoverage& coverage, int64_t start_intersection,
                          double seconds, double speed_mps = 8.0, int lookahead = 4);

// Where a campaign's next drive starts when no intersection is given (lanemap-sim --cover): the
// start of a road still to cover that only a drive's first road can cover, one leaving a dead end
// (no U-turns: a drive that enters a dead end ends there, so nothing else brings the car out of
// one) into the network (not a piece between two dead ends, where the drive would end at once);
// else the start of any road still to cover; else of any road. `seed` picks among them.
// Throws std::invalid_argument when the skeleton has no road.
int64_t coverageStart(const skeleton::Skeleton& skeleton, const CityCoverage& coverage, uint64_t seed);

// A coverage file (lanemap-coverage --json) read back against `skeleton`: the roads' states and
// mapped lengths (lanemap-sim --cover plans on it). Throws std::runtime_error naming the file when
// it cannot be read, or when a road id's ends are not the skeleton's (made from another OSM file
// or map config); roads the file does not list count as never driven.
CityCoverage readCoverageJson(const std::string& path, const skeleton::Skeleton& skeleton);

// Reads what `store` holds for every road of `skeleton` (the skeleton the store was built with:
// the same OSM and map config, or the road ids do not match). A missing store is empty. A folder
// without lanes/road_<id>.osm files (lanemap-offline's --out) is read from its whole map,
// lane_map.osm or map.osm, by the lanelets' road ids.
CityCoverage cityCoverage(const skeleton::Skeleton& skeleton, const std::string& store);

}  // namespace lanemap::mapping
