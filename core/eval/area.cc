#include "core/eval/area.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <stdexcept>

namespace lanemap::eval {

std::set<RoadKey> mappedRoads(const map::LaneMap& built) {
  std::set<RoadKey> mapped;
  for (const auto& l : built.lanelets) {
    if (l.kind == map::LaneletKind::kRoad && l.from_node >= 0) mapped.insert({l.from_node, l.to_node});
  }
  return mapped;
}

map::LaneMap restrictToMappedRoads(const map::LaneMap& truth, const map::LaneMap& built) {
  return restrictToRoads(truth, mappedRoads(built));
}

map::LaneMap restrictToRoads(const map::LaneMap& truth, const std::set<RoadKey>& roads) {
  std::set<int64_t> keep;
  for (const auto& l : truth.lanelets) {
    if (l.kind == map::LaneletKind::kRoad && roads.count({l.from_node, l.to_node})) keep.insert(l.id);
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
  return restrictToLanelets(truth, keep);
}

map::LaneMap restrictToLanelets(const map::LaneMap& truth, const std::set<int64_t>& keep) {
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
  // The rules at kept stop lines and the crosswalks over kept lanelets, restricted likewise.
  for (const auto& r : truth.regulatory_elements) {
    if (!lines.count(r.stop_line_id)) continue;
    map::RegulatoryElement k = r;
    k.lanelets.clear();
    k.priority.clear();
    for (int64_t id : r.lanelets) if (keep.count(id)) k.lanelets.push_back(id);
    for (int64_t id : r.priority) if (keep.count(id)) k.priority.push_back(id);
    if (!k.lanelets.empty()) out.regulatory_elements.push_back(std::move(k));
  }
  for (const auto& c : truth.crosswalks) {
    map::Crosswalk k = c;
    k.crossing.clear();
    for (int64_t id : c.crossing) if (keep.count(id)) k.crossing.push_back(id);
    if (!k.crossing.empty()) out.crosswalks.push_back(std::move(k));
  }
  return out;
}

std::set<RoadKey> drivenRoadsFromScenario(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": not JSON (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("route") || !j["route"].is_array()) {
    throw std::runtime_error(path + ": no \"route\" array (expected lanemap-sim's scenario.json)");
  }
  std::set<RoadKey> out;
  for (const auto& r : j["route"]) {
    if (!r.contains("from") || !r.contains("to")) throw std::runtime_error(path + ": a route entry without from/to");
    if (r.contains("left_utime") && r["left_utime"].is_null()) continue;  // the drive ended on it
    out.insert({r["from"].get<int64_t>(), r["to"].get<int64_t>()});
  }
  return out;
}

}  // namespace lanemap::eval
