// Internals of the map evaluation (core/eval/evaluate.h), shared by its parts: lane chaining
// (chaining.cc), matching of lanes, intersection pairs and lane graph edges (matching.cc), MapTR's
// Chamfer AP (chamfer_ap.cc) and the report (report.cc). Not part of the public interface.
#pragma once

#include "core/eval/evaluate.h"
#include "core/eval/geometry.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

namespace lanemap::eval::internal {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Box {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = Eigen::Vector2d::Constant(-std::numeric_limits<double>::infinity());
  void add(const Polyline& pts) {
    for (const auto& p : pts) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  // Distance between two boxes (0 when they overlap): a lower bound of any point distance.
  double gap(const Box& o) const {
    const Eigen::Vector2d d = (lo - o.hi).cwiseMax(o.lo - hi).cwiseMax(Eigen::Vector2d::Zero());
    return d.norm();
  }
};

struct Instance {
  Polyline pts;  // chamfer_points resampled
  Box box;
  double score = 0.0;
};

struct Lane {
  LaneInfo info;
  Polyline centre, left, right;
  LanePolygon polygon;
  Box box;
};

// One map, prepared: lanes, intersection pairs, graph edges, Chamfer instances.
struct Prepared {
  std::vector<Lane> lanes;
  std::unordered_map<int64_t, int> lane_of;       // road lanelet id -> lane
  std::map<std::pair<int, int>, Polyline> pairs;  // (in lane, out lane) -> connection centre
  std::set<std::pair<int, int>> edges;            // lane graph
  std::vector<Instance> centres, bounds;
  size_t intersection_lanelets = 0;
  size_t repaired = 0;
};

// chaining.cc: a map's lanes (chains of road lanelets), intersection pairs, lane graph edges and
// Chamfer instances.
Prepared prepareMap(const map::LaneMap& m, const EvalOptions& o);

// matching.cc: the greedy one-to-one lane matching (fills r.matches and the lane scores); returns
// the truth lane matched to each built lane (-1: none).
std::vector<int> matchLanes(const Prepared& truth, const Prepared& built, const EvalOptions& o, EvalReport& r);
// matching.cc: intersection pairs and lane graph edges through the lane matching, and the per-road
// detail.
void scorePairs(const Prepared& truth, const Prepared& built, const std::vector<int>& match_of_built,
                const EvalOptions& o, EvalReport& r);
void scoreGraph(const Prepared& truth, const Prepared& built, const std::vector<int>& match_of_built, EvalReport& r);
void scoreRoads(const Prepared& truth, const Prepared& built, EvalReport& r);

// chamfer_ap.cc: the Chamfer instances of a prepared map: centre lines of its lanes, then of its
// intersection lanelets (`intersection_centres`, map order); each lane's left and right bound,
// duplicates within the map (Chamfer distance below duplicate_chamfer_m) counted once.
void makeChamferInstances(Prepared& p, const std::vector<Polyline>& intersection_centres, const EvalOptions& o);
// chamfer_ap.cc: MapTR's AP for one class.
ApResult averagePrecision(const std::vector<Instance>& truth, const std::vector<Instance>& pred,
                          const std::vector<double>& thresholds);
// chamfer_ap.cc: r.ap_centre, r.ap_boundary and their mean r.chamfer_ap.
void scoreChamferAp(const Prepared& truth, const Prepared& built, const EvalOptions& o, EvalReport& r);

double meanOf(const std::vector<double>& v);

}  // namespace lanemap::eval::internal
