// The world's intersections: which lane goes to which (the truth's own rules, richer than the
// mapper's: turn:lanes read by core/osm/turn_lanes.h, not the mapper's pairing) and the connecting
// lanelets. Part of buildWorld (core/sim/world_build.h).
#include "core/sim/world_build.h"

namespace lanemap::sim::world_build {

void Builder::buildIntersection(const skeleton::Intersection& in) {
  auto& ins = incoming_[in.id];
  auto& outs = outgoing_[in.id];
  std::vector<Vector2d> patch_pts = end_points_[in.id];
  double radius = 0.0;
  for (const auto& p : patch_pts) radius = std::max(radius, (p - in.centre).norm());
  for (const Approach& a : ins) {
    std::vector<int> connections(a.lanes.size(), 0);
    const Approach* straightest = nullptr;
    double best_dot = -2.0;
    for (const Approach& d : outs) {
      if (a.lanes.empty() || d.lanes.empty() || isUturn(a, d)) continue;
      if (turnRestricted(a, d)) {
        ++impl_->stats.turns_restricted;
        continue;
      }
      const Vector2d tin = a.lanes.front().tangent, tout = d.lanes.front().tangent;
      if (tin.dot(tout) > best_dot) {
        best_dot = tin.dot(tout);
        straightest = &d;
      }
      const TurnDirection turn = classify(tin, tout);
      for (const auto& [i, o] : pairLanes(a, d, turn)) {
        if (connect(in, a.lanes[i], d.lanes[o], turn, &radius)) ++connections[i];
      }
    }
    // No lane may end at an intersection that has a way out: link it straight on.
    if (straightest) {
      for (size_t i = 0; i < a.lanes.size(); ++i) {
        if (connections[i]) continue;
        const size_t o = std::min(i, straightest->lanes.size() - 1);
        connect(in, a.lanes[i], straightest->lanes[o], classify(a.lanes[i].tangent, straightest->lanes[o].tangent), &radius);
      }
    }
  }
  if (!in.dead_end && patch_pts.size() >= 3) {
    auto hull = convexHull(patch_pts);
    if (hull.size() >= 3) {
      impl_->flat_polygons.push_back(hull);
      addFill(Surface::kIntersection, detail::kLayerIntersection, hull);
    }
  }
  zones_circles_.push_back({in.centre, radius});
}

// An OSM turn restriction at the junction node where road a ends and road d starts (the via node):
// no_* forbids a -> d when a lies on its from way and d on its to way; only_* forbids every road
// out of that node but the one on its to way. A restriction whose via node is not where a ends, or
// whose turn passes other junction nodes of a merged intersection (d starts elsewhere), is not
// applied: the truth then keeps the turn. Only the OSM data is read here, not the mapper's rules.
bool Builder::turnRestricted(const Approach& a, const Approach& d) const {
  if (restrictions_.empty()) return false;
  const skeleton::AtomicRoad* ra = sk_.road(a.road_id);
  const skeleton::AtomicRoad* rd = sk_.road(d.road_id);
  if (!ra || !rd || ra->osm_nodes.empty() || rd->osm_nodes.empty()) return false;
  const int64_t via = ra->osm_nodes.back();
  if (rd->osm_nodes.front() != via) return false;
  for (const auto& r : restrictions_) {
    if (r.via_node != via || r.from_way != ra->way_id) continue;
    if (r.prohibitive() && r.to_way == rd->way_id) return true;
    if (r.mandatory() && r.to_way != rd->way_id) return true;
  }
  return false;
}

std::vector<std::pair<int, int>> Builder::pairLanes(const Approach& a, const Approach& d, TurnDirection turn) const {
  std::vector<std::pair<int, int>> out;
  const int nin = static_cast<int>(a.lanes.size()), nout = static_cast<int>(d.lanes.size());
  bool any_specified = false;
  for (const auto& l : a.lanes) any_specified |= l.moves.specified;
  std::vector<int> cand;
  if (turn == TurnDirection::kStraight) {
    for (int i = 0; i < nin; ++i) {
      const auto& m = a.lanes[i].moves;
      if (!m.specified || m.straight) cand.push_back(i);
    }
    for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) out.emplace_back(cand[j], j);
    return out;
  }
  const bool left = turn == TurnDirection::kLeft;
  for (int i = 0; i < nin; ++i) {
    const auto& m = a.lanes[i].moves;
    if (m.specified && (left ? m.left : m.right)) cand.push_back(i);
  }
  if (cand.empty()) {
    if (any_specified) {
      // Tagged lanes with no such movement: only an untagged edge lane may turn.
      const int edge = left ? 0 : nin - 1;
      if (a.lanes[edge].moves.specified) return out;
    }
    cand.push_back(left ? 0 : nin - 1);
  }
  if (left) {
    for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) out.emplace_back(cand[j], j);
  } else {
    for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) {
      out.emplace_back(cand[cand.size() - 1 - j], nout - 1 - j);
    }
  }
  return out;
}

bool Builder::connect(const skeleton::Intersection& in, const LaneEnd& a, const LaneEnd& b, TurnDirection turn,
    double* radius) {
  intersections::CurveOptions curve_options;
  curve_options.step_m = 0.5;
  const auto curve = intersections::bezierConnection(a.centre, a.tangent, b.centre, b.tangent, curve_options)
                         .sample(curve_options.step_m);
  const auto bounds = intersections::connectorBounds(a.left, a.right, a.tangent, b.left, b.right, b.tangent,
                                                     curve_options, &curve);
  const auto& left = bounds.left;
  const auto& right = bounds.right;
  auto lift = [&](const std::vector<Vector2d>& pts) {
    std::vector<Vector3d> out;
    for (const auto& p : pts) out.emplace_back(p.x(), p.y(), terrainAt(p));
    return out;
  };
  LineString lb, rb;
  lb.type = LineType::kVirtual;
  lb.points = lift(left);
  rb.type = LineType::kVirtual;
  rb.points = lift(right);
  // Keep the joints' heights equal to the road lanes' (crown faded to 0 there anyway).
  Lanelet l;
  l.kind = LaneletKind::kIntersection;
  l.centre = lift(curve);
  l.centre.front() = laneletRef(a.lanelet).centre.back();
  l.centre.back() = laneletRef(b.lanelet).centre.front();
  if (!connectionIsSound(l, lb, rb)) {
    ++impl_->stats.connections_not_built;
    return false;
  }
  lb.id = nextId();
  rb.id = nextId();
  l.id = nextId();
  l.left_id = lb.id;
  l.right_id = rb.id;
  l.successors = {b.lanelet};
  l.turn = turn;
  l.intersection_id = in.id;
  for (const auto& p : curve) *radius = std::max(*radius, (p - in.centre).norm() + std::max(a.width, b.width) / 2);
  std::vector<Vector2d> poly = left;
  poly.insert(poly.end(), right.rbegin(), right.rend());
  addFill(Surface::kIntersection, detail::kLayerIntersection, std::move(poly));
  pushLine(std::move(lb));
  pushLine(std::move(rb));
  laneletRef(a.lanelet).successors.push_back(l.id);
  pushLanelet(std::move(l));
  ++impl_->stats.intersection_lanelets;
  return true;
}

void Builder::shareOpposedIntersectionBounds() {
  auto& t = truth();
  std::map<int64_t, std::vector<size_t>> by_intersection;
  for (size_t i = 0; i < t.lanelets.size(); ++i) {
    if (t.lanelets[i].kind == LaneletKind::kIntersection) by_intersection[t.lanelets[i].intersection_id].push_back(i);
  }
  const auto near = [](const Vector3d& a, const Vector3d& b) { return (a - b).head<2>().norm() < 0.02; };
  const auto onTop = [&](const LineString& a, const LineString& b, bool reversed) {
    if (a.points.size() < 2 || b.points.size() < 2) return false;
    const Vector3d& b0 = reversed ? b.points.back() : b.points.front();
    const Vector3d& b1 = reversed ? b.points.front() : b.points.back();
    if (!near(a.points.front(), b0) || !near(a.points.back(), b1)) return false;
    const auto inside = [](const LineString& p, const LineString& q) {  // every point of p on q
      for (const auto& x : p.points) {
        double best = 1e9;
        for (size_t k = 0; k + 1 < q.points.size(); ++k) {
          const Vector2d u = q.points[k].head<2>(), v = q.points[k + 1].head<2>();
          const double len2 = (v - u).squaredNorm();
          const double f = len2 > 0.0 ? std::clamp((x.head<2>() - u).dot(v - u) / len2, 0.0, 1.0) : 0.0;
          best = std::min(best, (u + f * (v - u) - x.head<2>()).norm());
        }
        if (best > 0.02) return false;
      }
      return true;
    };
    return inside(a, b) && inside(b, a);
  };
  std::unordered_map<int64_t, int> uses;  // a line another lanelet also uses stays
  for (const auto& l : t.lanelets) {
    ++uses[l.left_id];
    ++uses[l.right_id];
    if (l.stop_line_id) ++uses[*l.stop_line_id];
  }
  std::set<int64_t> dropped;
  for (const auto& [id, idx] : by_intersection) {
    for (size_t a = 0; a < idx.size(); ++a) {
      for (size_t b = a + 1; b < idx.size(); ++b) {
        Lanelet& la = t.lanelets[idx[a]];
        Lanelet& lb = t.lanelets[idx[b]];
        // lb's bound `mine` becomes la's bound `theirs` when they lie on top of each other.
        const auto share = [&](int64_t& mine, int64_t theirs, bool reversed) {
          if (mine == theirs || dropped.count(mine) || dropped.count(theirs) || uses[mine] != 1) return;
          if (!onTop(lineRef(theirs), lineRef(mine), reversed)) return;
          dropped.insert(mine);
          mine = theirs;
        };
        share(lb.left_id, la.left_id, true);    // opposite directions, the centre line
        share(lb.left_id, la.right_id, false);  // side by side in one direction: lb right of la
        share(lb.right_id, la.left_id, false);  // lb left of la
      }
    }
  }
  if (dropped.empty()) return;
  t.lines.erase(std::remove_if(t.lines.begin(), t.lines.end(), [&](const LineString& l) { return dropped.count(l.id) > 0; }),
                t.lines.end());
  line_pos_.clear();
  for (size_t i = 0; i < t.lines.size(); ++i) line_pos_[t.lines[i].id] = i;
}

}  // namespace lanemap::sim::world_build
