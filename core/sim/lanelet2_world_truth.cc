// The Lanelet2 world, step 8: the truth lanelets labelled with their atomic roads and junctions
// (lanelet2_world_build.h).
#include "core/sim/lanelet2_world_build.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace lanemap::sim::l2w {

// 8. Truth labels in terms of the skeleton.
void Builder::labelTruth() {
  const auto& sk = *skeleton_;
  std::unordered_map<int64_t, int64_t> inter_of_node;
  for (const auto& in : sk.intersections()) {
    for (int64_t n : in.osm_nodes) inter_of_node[n] = in.id;
  }
  std::map<std::pair<int64_t, bool>, std::vector<int64_t>> road_of;  // (way, along) -> road ids
  for (const auto& r : sk.roads()) road_of[{r.way_id, r.along_way}].push_back(r.id);
  for (auto& v : vls_) {
    if (v.junction) continue;
    const auto& comp = comps_[v.comp];
    const Vector2d mid = resample(v.centre, 3)[1];
    const bool along = comp.way_id >= 0 && project(comp.way_line, mid).tangent.dot(project(v.centre, mid).tangent) > 0;
    auto it = road_of.find({comp.way_id, along});
    if (it != road_of.end()) {
      // The way's atomic road (a way with junction nodes along it has several) nearest the
      // lanelet's middle.
      int64_t best_road = it->second.front();
      double best_d = 1e300;
      for (int64_t rid : it->second) {
        const double d = sk.project(rid, mid).distance;
        if (d < best_d) {
          best_d = d;
          best_road = rid;
        }
      }
      const auto* r = sk.road(best_road);
      v.ll.road_id = r->id;
      v.ll.from_node = r->from;
      v.ll.to_node = r->to;
      v.ll.index_from_left = impl_->right_hand ? v.left_same : v.right_same;
      continue;
    }
    // The skeleton has no road there (a piece inside a merged intersection): a junction lanelet
    // of the nearest intersection.
    ++stats_.unassigned_lanelets;
    v.junction = true;
    const skeleton::Intersection* best = nullptr;
    double bd = 1e300;
    for (const auto& in : sk.intersections()) {
      const double d = (in.centre - mid).norm();
      if (d < bd) {
        bd = d;
        best = &in;
      }
    }
    v.ll.intersection_id = best ? best->id : -1;
  }
  for (auto& v : vls_) {
    if (!v.junction) continue;
    v.ll.kind = LaneletKind::kIntersection;
    if (v.area >= 0) {
      auto it = inter_of_node.find(areas_[v.area].node);
      v.ll.intersection_id = it != inter_of_node.end() ? it->second : areas_[v.area].node;
    }
    const double h = headingChange(v.centre);
    v.ll.turn = h > 0.5 ? map::TurnDirection::kLeft : h < -0.5 ? map::TurnDirection::kRight
                                                       : map::TurnDirection::kStraight;
  }
  // The truth: the vehicle lanelets, their bounds and stop lines.
  auto& truth = impl_->truth;
  truth.origin_lat = origin_.lat;
  truth.origin_lon = origin_.lon;
  truth.origin_alt = origin_.alt;
  // Junction lanelets drawn in pieces (road -> J1 -> J2 -> road) are joined into one
  // intersection lanelet per path, as lanemap's truth has one lanelet per junction connection.
  std::vector<std::vector<size_t>> paths;
  std::map<size_t, std::vector<size_t>> paths_from;  // entry piece -> path indices
  for (size_t j = 0; j < vls_.size(); ++j) {
    const VL& v = vls_[j];
    if (!v.junction) continue;
    bool entry = v.pred.empty();
    for (size_t p : v.pred) entry |= !vls_[p].junction;
    if (!entry) continue;
    std::vector<size_t> path{j};
    std::function<void()> walk = [&]() {
      const VL& cur = vls_[path.back()];
      bool road_next = cur.succ.empty();
      for (size_t s : cur.succ) road_next |= !vls_[s].junction;
      if (road_next || path.size() >= 8) {
        paths_from[path.front()].push_back(paths.size());
        paths.push_back(path);
      }
      if (path.size() >= 8 || paths.size() > 20000) return;
      for (size_t s : cur.succ) {
        if (!vls_[s].junction || std::find(path.begin(), path.end(), s) != path.end()) continue;
        path.push_back(s);
        walk();
        path.pop_back();
      }
    };
    walk();
  }
  std::vector<map::Lanelet> junction_out;
  std::set<size_t> in_paths;
  std::vector<int64_t> path_id(paths.size());
  for (size_t k = 0; k < paths.size(); ++k) {
    const auto& path = paths[k];
    in_paths.insert(path.begin(), path.end());
    if (path.size() == 1) {
      path_id[k] = vls_[path[0]].ll.id;
      continue;
    }
    path_id[k] = next_id_++;
    ++stats_.joined_junction_paths;
    for (size_t j : path) joined_[path_id[k]].push_back(vls_[j].ll.id);
  }
  for (size_t k = 0; k < paths.size(); ++k) {
    const auto& path = paths[k];
    map::Lanelet ll = vls_[path.front()].ll;
    if (path.size() > 1) {
      std::vector<Vector2d> left, right, centre;
      auto append = [](std::vector<Vector2d>& to, const std::vector<Vector2d>& from) {
        for (const auto& p : from) {
          if (to.empty() || (p - to.back()).norm() > 1e-3) to.push_back(p);
        }
      };
      for (size_t j : path) {
        append(left, vls_[j].left);
        append(right, vls_[j].right);
        append(centre, vls_[j].centre);
      }
      ll.id = path_id[k];
      ll.left_id = addLine(anyLine(vls_[path.front()].ll.left_id)->type, left, next_id_);
      ll.right_id = addLine(anyLine(vls_[path.front()].ll.right_id)->type, right, next_id_);
      ll.centre.clear();
      for (const auto& p : centre) ll.centre.emplace_back(p.x(), p.y(), 0.0);
      ll.stop_line_id = vls_[path.back()].ll.stop_line_id;
      const double h = headingChange(centre);
      ll.turn = h > 0.5 ? map::TurnDirection::kLeft : h < -0.5 ? map::TurnDirection::kRight
                                                     : map::TurnDirection::kStraight;
    }
    ll.successors.clear();
    for (size_t s : vls_[path.back()].succ) {
      if (!vls_[s].junction) ll.successors.push_back(vls_[s].ll.id);
    }
    junction_out.push_back(std::move(ll));
  }
  auto successorIds = [&](const VL& v) {
    std::vector<int64_t> out;
    for (size_t s : v.succ) {
      if (!vls_[s].junction) {
        out.push_back(vls_[s].ll.id);
      } else if (auto it = paths_from.find(s); it != paths_from.end()) {
        for (size_t k : it->second) out.push_back(path_id[k]);
      }
    }
    return out;
  };
  std::set<int64_t> lines;
  auto keep = [&](const map::Lanelet& ll) {
    lines.insert(ll.left_id);
    lines.insert(ll.right_id);
    if (ll.stop_line_id) lines.insert(*ll.stop_line_id);
    truth.lanelets.push_back(ll);
    (ll.kind == LaneletKind::kIntersection ? stats_.junction_lanelets : stats_.road_lanelets)++;
  };
  for (auto& v : vls_) {
    if (v.junction) {
      if (in_paths.count(&v - vls_.data())) continue;
      map::Lanelet ll = v.ll;  // on a cycle of junction pieces: as drawn
      ll.successors = successorIds(v);
      keep(ll);
      continue;
    }
    v.ll.successors = successorIds(v);
    keep(v.ll);
  }
  for (const auto& ll : junction_out) keep(ll);
  for (const auto& l : file_.map.lines) {
    if (lines.count(l.id)) truth.lines.push_back(l);
  }
  for (const auto& l : new_lines_) {
    if (lines.count(l.id)) truth.lines.push_back(l);
  }
  // Lateral slots for laneOffset: the road is the cross-section.
  for (auto& v : vls_) {
    if (v.junction) continue;
    detail::LaneSlot slot;
    slot.cross_section = v.comp;
    const auto& comp = comps_[v.comp];
    const Vector2d mid = resample(v.centre, 3)[1];
    slot.dir = project(comp.way_line, mid).tangent.dot(project(v.centre, mid).tangent) > 0 ? 1 : -1;
    slot.rank_curb = impl_->right_hand ? v.right_same : v.left_same;
    slot.rank_centre = impl_->right_hand ? v.left_same : v.right_same;
    impl_->slots[v.ll.id] = slot;
  }
}

}  // namespace lanemap::sim::l2w
