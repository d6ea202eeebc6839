#include "core/mapping/road_lanes.h"

#include "core/io/lanelet2_orientation.h"
#include "core/lanes/stop_lines.h"
#include "core/mapping/lane_confidence.h"
#include "core/mapping/partial_road.h"

#include <algorithm>
#include <set>

namespace lanemap::mapping {

std::vector<std::string> dropMisreadLanelets(map::LaneMap& lanes) {
  std::vector<std::string> problems;
  std::set<int64_t> dropped, their_lines;
  for (const auto& ll : lanes.lanelets) {
    const auto* left = lanes.line(ll.left_id);
    const auto* right = lanes.line(ll.right_id);
    if (!left || !right) continue;
    std::string p = io::orientationProblem(ll, *left, *right);
    if (p.empty()) continue;
    problems.push_back(std::move(p));
    dropped.insert(ll.id);
    their_lines.insert({ll.left_id, ll.right_id});
    if (ll.stop_line_id) their_lines.insert(*ll.stop_line_id);
  }
  if (dropped.empty()) return problems;
  const auto gone = [&](int64_t id) { return dropped.count(id) > 0; };
  auto& ls = lanes.lanelets;
  ls.erase(std::remove_if(ls.begin(), ls.end(), [&](const map::Lanelet& l) { return gone(l.id); }), ls.end());
  std::set<int64_t> used;  // lines the remaining lanelets still need
  for (auto& l : ls) {
    l.successors.erase(std::remove_if(l.successors.begin(), l.successors.end(), gone), l.successors.end());
    used.insert(l.left_id);
    used.insert(l.right_id);
    if (l.stop_line_id) used.insert(*l.stop_line_id);
  }
  for (auto& r : lanes.regulatory_elements) {
    r.lanelets.erase(std::remove_if(r.lanelets.begin(), r.lanelets.end(), gone), r.lanelets.end());
    r.priority.erase(std::remove_if(r.priority.begin(), r.priority.end(), gone), r.priority.end());
  }
  auto& regs = lanes.regulatory_elements;
  regs.erase(std::remove_if(regs.begin(), regs.end(), [](const map::RegulatoryElement& r) { return r.lanelets.empty(); }), regs.end());
  for (const auto& r : regs) used.insert(r.stop_line_id);
  for (auto& c : lanes.crosswalks) c.crossing.erase(std::remove_if(c.crossing.begin(), c.crossing.end(), gone), c.crossing.end());
  auto& lines = lanes.lines;
  lines.erase(std::remove_if(lines.begin(), lines.end(), [&](const map::LineString& l) {
                return their_lines.count(l.id) > 0 && used.count(l.id) == 0;
              }), lines.end());
  return problems;
}

RoadLanes exploreRoadLanes(const bev::BevGrid& grid, const lanes::RoadGeometry& geometry,
                           const std::optional<map::PartialRoad>& partial, const lanes::ExplorerOptions& options,
                           const geo::LatLonAlt& origin, const std::vector<lanes::CarriedLane>& carried) {
  RoadLanes out;
  const bool may_carry = !partial && !carried.empty() && geometry.s_end - geometry.s_begin < options.carry_lanes_max_m;
  bool explored = true;
  try {
    out.result = lanes::exploreRoad(grid, geometry, options);
  } catch (const lanes::LanesError&) {
    if (!may_carry) throw;
    explored = false;  // nothing to explore: the lanes run on from the road before
  }
  if (may_carry && (!explored || lanes::takesCarriedLanes(geometry, out.result, carried.size(), options))) {
    out.result = lanes::carryLanesThrough(geometry, carried, options);
    out.lanes_carried = true;
  } else if (may_carry) {
    out.lanes_apart_dropped = lanes::dropLanesApartFromCarried(geometry, carried, options, &out.result);
    out.lanes_carried_added = lanes::addCarriedLanesNotFound(geometry, carried, options, &out.result);
  }
  out.lanes = lanes::toLaneMap(out.result, origin.lat, origin.lon, origin.alt);
  setConfidence(out.lanes, out.result, laneConfidences(grid, out.result, options));  // per lane, 0..1
  if (partial) {
    markPartial(out.lanes, *partial);  // its lanes end where the car stopped: no stop line there
  } else {
    lanes::addStopLines(grid, out.lanes);  // stop lines the BEV saw at the lanes' ends
  }
  out.lanes_dropped = dropMisreadLanelets(out.lanes);
  return out;
}

}  // namespace lanemap::mapping
