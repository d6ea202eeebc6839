#include "core/eval/area.h"

#include <set>
#include <utility>

namespace lanemap::eval {

map::LaneMap restrictToMappedRoads(const map::LaneMap& truth, const map::LaneMap& built) {
  std::set<std::pair<int64_t, int64_t>> mapped;  // (from_node, to_node) of the built road lanelets
  for (const auto& l : built.lanelets) {
    if (l.kind == map::LaneletKind::kRoad && l.from_node >= 0) mapped.insert({l.from_node, l.to_node});
  }
  std::set<int64_t> keep;
  for (const auto& l : truth.lanelets) {
    if (l.kind == map::LaneletKind::kRoad && mapped.count({l.from_node, l.to_node})) keep.insert(l.id);
  }
  std::set<int64_t> connectors;
  for (const auto& l : truth.lanelets) {
    if (!keep.count(l.id)) continue;
    for (int64_t s : l.successors) {
      const auto* c = truth.lanelet(s);
      if (!c || c->kind != map::LaneletKind::kIntersection) continue;
      for (int64_t t : c->successors) {
        if (keep.count(t)) connectors.insert(c->id);
      }
    }
  }
  keep.insert(connectors.begin(), connectors.end());

  map::LaneMap out;
  out.origin_lat = truth.origin_lat;
  out.origin_lon = truth.origin_lon;
  out.origin_alt = truth.origin_alt;
  std::set<int64_t> lines;
  for (const auto& l : truth.lanelets) {
    if (!keep.count(l.id)) continue;
    out.lanelets.push_back(l);
    auto& kept = out.lanelets.back();
    kept.successors.clear();
    for (int64_t s : l.successors) {
      if (keep.count(s)) kept.successors.push_back(s);
    }
    lines.insert(l.left_id);
    lines.insert(l.right_id);
    if (l.stop_line_id) lines.insert(*l.stop_line_id);
  }
  for (const auto& ls : truth.lines) {
    if (lines.count(ls.id)) out.lines.push_back(ls);
  }
  return out;
}

}  // namespace lanemap::eval
