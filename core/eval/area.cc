#include "core/eval/area.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
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
  return restrictToRoads(truth, roads, {});
}

map::LaneMap restrictToRoads(const map::LaneMap& truth, const std::set<RoadKey>& roads,
                             const std::set<int64_t>& driven_road_ids) {
  // The truth's atomic roads per kept (from, to): two or more are parallel roads between the same
  // two junctions, of which driven_road_ids names the driven ones (when it names any).
  std::map<RoadKey, std::set<int64_t>> ids;
  for (const auto& l : truth.lanelets) {
    if (l.kind == map::LaneletKind::kRoad && roads.count({l.from_node, l.to_node})) ids[{l.from_node, l.to_node}].insert(l.road_id);
  }
  const auto driven = [&](const map::Lanelet& l) {
    const std::set<int64_t>& same_ends = ids[{l.from_node, l.to_node}];
    if (same_ends.size() < 2 || driven_road_ids.count(l.road_id)) return true;
    return std::none_of(same_ends.begin(), same_ends.end(), [&](int64_t id) { return driven_road_ids.count(id) > 0; });
  };
  std::set<int64_t> keep;
  for (const auto& l : truth.lanelets) {
    if (l.kind == map::LaneletKind::kRoad && roads.count({l.from_node, l.to_node}) && driven(l)) keep.insert(l.id);
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

namespace {

// The line across the road through `end`, direction `t`: a point is past it when ahead of it and
// within `side_m` of `end` sideways.
struct Cut {
  Eigen::Vector2d end, t;
  double side_m = 15.0;
  double ahead(const Eigen::Vector3d& p) const { return (p.head<2>() - end).dot(t); }
  bool past(const Eigen::Vector3d& p) const {
    const Eigen::Vector2d v = p.head<2>() - end;
    return v.dot(t) > 0.0 && std::abs(t.x() * v.y() - t.y() * v.x()) < side_m;
  }
  // The part of `pts` before the cut in the road's direction (a polyline stored against it is cut
  // from its other end); *cut_off: whether anything was cut off.
  std::vector<Eigen::Vector3d> before(std::vector<Eigen::Vector3d> pts, bool* cut_off) const {
    *cut_off = false;
    if (pts.size() < 2) return pts;
    const bool reversed = (pts.back() - pts.front()).head<2>().dot(t) < 0.0;
    if (reversed) std::reverse(pts.begin(), pts.end());
    std::vector<Eigen::Vector3d> out;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (past(pts[i])) {
        *cut_off = true;
        if (i > 0) {
          const double a0 = ahead(pts[i - 1]), a1 = ahead(pts[i]);
          const double f = a0 < a1 ? std::clamp(-a0 / (a1 - a0), 0.0, 1.0) : 0.0;
          const Eigen::Vector3d q = pts[i - 1] + f * (pts[i] - pts[i - 1]);
          if (out.empty() || (q - out.back()).norm() > 1e-6) out.push_back(q);
        }
        break;
      }
      out.push_back(pts[i]);
    }
    if (reversed) std::reverse(out.begin(), out.end());
    return out;
  }
};

}  // namespace

map::LaneMap cutRoadAt(const map::LaneMap& truth, const RoadKey& road, const Eigen::Vector2d& end, CutKeep keep) {
  map::LaneMap out = truth;
  auto onRoad = [&](const map::Lanelet& l) {
    return l.kind == map::LaneletKind::kRoad && l.from_node == road.first && l.to_node == road.second;
  };
  // The road's direction at `end`: the nearest segment of its centre lines.
  double best = std::numeric_limits<double>::infinity();
  Cut cut{end, Eigen::Vector2d::Zero()};
  for (const auto& l : truth.lanelets) {
    if (!onRoad(l)) continue;
    for (size_t i = 0; i + 1 < l.centre.size(); ++i) {
      const Eigen::Vector2d a = l.centre[i].head<2>(), b = l.centre[i + 1].head<2>();
      const Eigen::Vector2d ab = b - a;
      if (ab.norm() < 1e-9) continue;
      const double f = std::clamp((end - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      const double d = (a + f * ab - end).norm();
      if (d < best) {
        best = d;
        cut.t = ab.normalized();
      }
    }
  }
  if (!std::isfinite(best)) return out;  // the truth has no lanes on the road
  const bool keep_after = keep == CutKeep::kKeepAfter;
  if (keep_after) cut.t = -cut.t;  // "before" the cut against the road's direction: after it
  int64_t next_id = 1;
  for (const auto& l : truth.lines) next_id = std::max(next_id, l.id + 1);
  for (const auto& l : truth.lanelets) next_id = std::max(next_id, l.id + 1);
  for (const auto& r : truth.regulatory_elements) next_id = std::max(next_id, r.id + 1);
  for (const auto& c : truth.crosswalks) next_id = std::max(next_id, c.id + 1);
  std::map<int64_t, int64_t> cut_line;  // original bound -> its cut copy (one per bound)
  std::set<int64_t> dropped, road_lanelets;
  std::vector<map::Lanelet> kept;
  for (auto l : out.lanelets) {
    if (!onRoad(l)) {
      kept.push_back(std::move(l));
      continue;
    }
    road_lanelets.insert(l.id);
    bool centre_cut = false;
    l.centre = cut.before(l.centre, &centre_cut);
    const map::LineString* left = truth.line(l.left_id);
    const map::LineString* right = truth.line(l.right_id);
    bool ok = l.centre.size() >= 2 && left && right;
    for (const map::LineString* b : {left, right}) {
      if (!ok) break;
      bool b_cut = false;
      auto pts = cut.before(b->points, &b_cut);
      if (pts.size() < 2) ok = false;
      if (!ok || !b_cut) continue;
      auto [it, fresh] = cut_line.try_emplace(b->id, next_id);
      if (fresh) {
        map::LineString copy = *b;
        copy.id = next_id++;
        copy.points = std::move(pts);
        out.lines.push_back(std::move(copy));
      }
      (b == left ? l.left_id : l.right_id) = it->second;
    }
    if (!ok) {
      dropped.insert(l.id);
      continue;
    }
    if (centre_cut && !keep_after) {  // it ends where the car stopped now: no successor, no stop line there
      l.successors.clear();
      l.stop_line_id.reset();
    }
    kept.push_back(std::move(l));
  }
  out.lanelets = std::move(kept);
  // Crosswalks past the cut no longer cross the road's lanes.
  for (auto& c : out.crosswalks) {
    Eigen::Vector3d mid = Eigen::Vector3d::Zero();
    for (const auto& p : c.left) mid += p;
    for (const auto& p : c.right) mid += p;
    const size_t n = c.left.size() + c.right.size();
    const bool past = n > 0 && cut.past(mid / static_cast<double>(n));
    c.crossing.erase(std::remove_if(c.crossing.begin(), c.crossing.end(),
                                    [&](int64_t id) { return dropped.count(id) || (past && road_lanelets.count(id)); }),
                     c.crossing.end());
  }
  return out;
}

map::LaneMap restrictToDriven(const map::LaneMap& truth, const DrivenArea& area) {
  map::LaneMap cut = truth;
  std::set<RoadKey> roads = area.roads;
  for (const auto& p : area.partial) {
    if (area.roads.count(p.road)) continue;  // driven to its end another time
    cut = cutRoadAt(cut, p.road, p.end);
    roads.insert(p.road);
  }
  for (const auto& e : area.entered) {
    cut = cutRoadAt(cut, e.road, e.start, CutKeep::kKeepAfter);
    roads.insert(e.road);
  }
  return restrictToRoads(cut, roads, area.road_ids);
}

DrivenArea drivenAreaFromScenario(const std::string& path, const geo::LocalFrame& frame) {
  DrivenArea area;
  area.roads = drivenRoadsFromScenario(path);
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& route = j["route"];
  for (const auto& r : route) {
    if (r.contains("road_id") && r["road_id"].is_number_integer()) area.road_ids.insert(r["road_id"].get<int64_t>());
  }
  if (route.empty() || !j.contains("origin")) return area;
  // The car's first and last positions: trajectory.csv's first and last rows
  // (t_s,utime,east_m,north_m,up_m,...), moved into `frame`.
  std::ifstream csv(std::filesystem::path(path).parent_path() / "trajectory.csv");
  std::string line, first, last;
  while (std::getline(csv, line)) {
    if (line.empty() || line[0] == 't') continue;
    if (first.empty()) first = line;
    last = line;
  }
  if (last.empty()) return area;
  const auto& o = j["origin"];
  const geo::LocalFrame scenario_frame({o.at("lat").get<double>(), o.at("lon").get<double>(), o.value("alt", 0.0)});
  const auto position = [&](const std::string& row, const char* which) {
    std::vector<double> v;
    std::stringstream ss(row);
    std::string item;
    while (std::getline(ss, item, ',')) {
      try {
        v.push_back(std::stod(item));
      } catch (const std::exception&) {
        v.push_back(std::nan(""));
      }
    }
    if (v.size() < 5 || !std::isfinite(v[2]) || !std::isfinite(v[3])) {
      throw std::runtime_error(path + ": trajectory.csv's " + which + " row is not t_s,utime,east_m,north_m,up_m,...");
    }
    return Eigen::Vector2d(frame.toEnu(scenario_frame.toWgs84(Eigen::Vector3d(v[2], v[3], v[4]))).head<2>());
  };
  const auto key = [](const nlohmann::json& r) { return RoadKey{r["from"].get<int64_t>(), r["to"].get<int64_t>()}; };
  if (route.back().contains("left_utime") && route.back()["left_utime"].is_null()) {
    area.partial.push_back({key(route.back()), position(last, "last")});
  }
  // The road the drive began on, unless the route enters it again from its start.
  const RoadKey began = key(route.front());
  size_t times = 0;
  for (const auto& r : route) times += key(r) == began;
  if (times == 1) area.entered.push_back({began, position(first, "first")});
  return area;
}

}  // namespace lanemap::eval
