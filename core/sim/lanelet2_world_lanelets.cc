// The Lanelet2 world, steps 1-6: the map's vehicle lanelets, who follows and who stands beside whom,
// which are junction lanelets, the junction areas and the roads (lanelet2_world_build.h).
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

// 1. Vehicle lanelets, bounds in the driving direction; two-way lanelets split in two.
void Builder::makeVehicleLanelets() {
  for (const auto& l : file_.map.lanelets) {
    const auto st = file_.lanelet_subtype.find(l.id);
    const std::string subtype = st == file_.lanelet_subtype.end() ? "" : st->second;
    if (!isVehicleSubtype(subtype)) continue;
    ++stats_.map_vehicle_lanelets;
    VL v;
    v.ll = l;
    v.ll.kind = LaneletKind::kRoad;
    v.ll.successors.clear();
    v.ll.road_id = v.ll.from_node = v.ll.to_node = v.ll.intersection_id = -1;
    v.ll.index_from_left = -1;
    v.ll.turn = map::TurnDirection::kNone;
    v.left = xy(fileLine(l.left_id).points);
    v.right = xy(fileLine(l.right_id).points);
    v.centre = xy(l.centre);
    if (v.left.size() < 2 || v.right.size() < 2 || v.centre.size() < 2) continue;
    const Vector2d dir = direction(v.centre);
    bool left_rev = false, right_rev = false;
    if (direction(v.left).dot(dir) < 0) {
      std::reverse(v.left.begin(), v.left.end());
      left_rev = true;
    }
    if (direction(v.right).dot(dir) < 0) {
      std::reverse(v.right.begin(), v.right.end());
      right_rev = true;
    }
    v.left_key = key(l.left_id);
    v.right_key = key(l.right_id);
    if (left_rev) v.ll.left_id = addLine(fileLine(l.left_id).type, v.left, v.left_key);
    if (right_rev) v.ll.right_id = addLine(fileLine(l.right_id).type, v.right, v.right_key);
    const auto ow = extra_.one_way.find(l.id);
    if (!isTwoWay(subtype, ow == extra_.one_way.end() ? "" : ow->second)) {
      finishGeometry(v);
      vls_.push_back(std::move(v));
      continue;
    }
    // Two ways: the drawn direction drives on the right half (left-hand traffic: the left half).
    ++stats_.two_way_split;
    const size_t n = std::max({v.left.size(), v.right.size(),
                               static_cast<size_t>(std::ceil(std::max(length(v.left), length(v.right)))) + 1});
    const auto L = resample(v.left, n), R = resample(v.right, n);
    std::vector<Vector2d> M(n), cf(n), cb(n);
    for (size_t i = 0; i < n; ++i) M[i] = 0.5 * (L[i] + R[i]);
    const int64_t mid_key = next_id_;  // the new middle line's own id
    const int64_t mid_id = addLine(LineType::kVirtual, M, mid_key);
    std::vector<Vector2d> Mr(M.rbegin(), M.rend());
    const int64_t mid_rev_id = addLine(LineType::kVirtual, Mr, mid_key);
    const bool rh = impl_->right_hand;
    // Forward half: between M and R (right-hand) or between L and M (left-hand).
    VL f = v, b = v;
    const std::vector<Vector2d>& f_left = rh ? M : L;
    const std::vector<Vector2d>& f_right = rh ? R : M;
    f.left = f_left;
    f.right = f_right;
    f.left_key = rh ? mid_key : v.left_key;
    f.right_key = rh ? v.right_key : mid_key;
    if (rh) f.ll.left_id = mid_id;
    else f.ll.right_id = mid_id;
    for (size_t i = 0; i < n; ++i) cf[i] = 0.5 * (f_left[i] + f_right[i]);
    f.centre = cf;
    // Backward half: the other half, driven the other way; its bounds are reversed copies.
    std::vector<Vector2d> b_left_fwd = rh ? L : M, b_right_fwd = rh ? M : R;  // in the drawn direction
    // Driving backwards, the drawn right side is on the left.
    b.left.assign(b_right_fwd.rbegin(), b_right_fwd.rend());
    b.right.assign(b_left_fwd.rbegin(), b_left_fwd.rend());
    b.left_key = rh ? mid_key : v.right_key;
    b.right_key = rh ? v.left_key : mid_key;
    b.ll.left_id = rh ? mid_rev_id : addLine(fileLine(l.right_id).type, b.left, v.right_key);
    b.ll.right_id = rh ? addLine(fileLine(l.left_id).type, b.right, v.left_key) : mid_rev_id;
    for (size_t i = 0; i < n; ++i) cb[i] = 0.5 * (b.left[i] + b.right[i]);
    b.centre = cb;
    b.ll.id = next_id_++;
    b.ll.stop_line_id.reset();
    split_twin_[f.ll.id] = b.ll.id;
    finishGeometry(f);
    finishGeometry(b);
    vls_.push_back(std::move(f));
    vls_.push_back(std::move(b));
  }
  for (auto& v : vls_) {
    v.ll.centre.clear();
    for (const auto& p : v.centre) v.ll.centre.emplace_back(p.x(), p.y(), 0.0);
  }
}

// 2. B follows A when A's bounds end where B's begin.
void Builder::findSuccessors() {
  for (size_t a = 0; a < vls_.size(); ++a) {
    for (size_t b = 0; b < vls_.size(); ++b) {
      if (a == b) continue;
      const VL &A = vls_[a], &B = vls_[b];
      const bool l = (A.left.back() - B.left.front()).norm() < kSuccessorGap;
      const bool r = (A.right.back() - B.right.front()).norm() < kSuccessorGap;
      // Or the lane goes on where it widens or narrows, or where a two-way lanelet (split in
      // halves) meets one-way ones: headings agree and the centre ends are close (one shared
      // bound end: within half the wider lane; none: within 0.3 m).
      const Vector2d ta = A.centre.back() - A.centre[A.centre.size() - 2];
      const Vector2d tb = B.centre[1] - B.centre.front();
      const bool ahead = ta.normalized().dot(tb.normalized()) > std::cos(35.0 * kPi / 180.0);
      const double dc = (A.centre.back() - B.centre.front()).norm();
      const double wide = std::max((A.left.back() - A.right.back()).norm(), (B.left.front() - B.right.front()).norm());
      const bool goes_on = ahead && (((l || r) && dc < 0.5 * wide + 0.1) || dc < 0.3);
      if ((l && r) || goes_on) {
        vls_[a].succ.push_back(b);
        vls_[b].pred.push_back(a);
      }
    }
  }
}

// 3. Side by side: a shared bound, or most of one's bound runs along one of the other's bounds.
void Builder::findLateral() {
  auto along = [](const std::vector<Vector2d>& a, const std::vector<Vector2d>& b) {
    const auto s = resampleSpacing(a, 1.0);
    size_t hits = 0;
    for (const auto& p : s) hits += project(b, p).distance < 0.15;
    return static_cast<double>(hits) / static_cast<double>(s.size());
  };
  for (size_t a = 0; a < vls_.size(); ++a) {
    for (size_t b : near(vls_, vls_[a].box, 0.5)) {
      if (b <= a) continue;
      const VL &A = vls_[a], &B = vls_[b];
      bool side = false;
      for (int64_t ka : {A.left_key, A.right_key}) {
        if (ka == B.left_key || ka == B.right_key) side = true;
      }
      for (int sa = 0; sa < 2 && !side; ++sa) {
        for (int sb = 0; sb < 2 && !side; ++sb) {
          const auto& la = sa ? A.right : A.left;
          const auto& lb = sb ? B.right : B.left;
          if (std::max(along(la, lb), along(lb, la)) >= 0.5) side = true;
        }
      }
      if (side) {
        vls_[a].lateral.insert(b);
        vls_[b].lateral.insert(a);
      }
    }
  }
}

// 4. Junction lanelets: the centre line runs inside another vehicle lanelet that is neither
//    side by side nor a successor/predecessor (crossing, branching, merging movements).
void Builder::findJunctions() {
  conflicts_.assign(vls_.size(), {});
  for (size_t a = 0; a < vls_.size(); ++a) {
    const VL& A = vls_[a];
    const double L = length(A.centre);
    if (L < 1.6) continue;
    const auto pts = resampleSpacing(A.centre, 0.5);
    std::vector<size_t> cands;
    for (size_t b : near(vls_, A.box, 0.0)) {
      if (b == a || A.lateral.count(b)) continue;
      if (std::find(A.succ.begin(), A.succ.end(), b) != A.succ.end()) continue;
      if (std::find(A.pred.begin(), A.pred.end(), b) != A.pred.end()) continue;
      cands.push_back(b);
    }
    for (size_t b : cands) {
      int hits = 0;
      double s = 0.0;
      for (size_t i = 0; i < pts.size(); ++i) {
        if (i > 0) s += (pts[i] - pts[i - 1]).norm();
        if (s < 0.75 || s > L - 0.75) continue;
        if (inside(vls_[b], pts[i])) ++hits;
      }
      if (hits >= 2) {
        conflicts_[a].insert(b);
        conflicts_[b].insert(a);
      }
    }
  }
  for (size_t a = 0; a < vls_.size(); ++a) {
    if (!conflicts_[a].empty()) vls_[a].junction = true;
  }
  // Branches and merges that are not side by side (the lanes go different ways).
  for (const auto& v : vls_) {
    for (const auto* set : {&v.succ, &v.pred}) {
      bool apart = false;
      for (size_t x : *set) {
        for (size_t y : *set) {
          if (x < y && !vls_[x].lateral.count(y)) apart = true;
        }
      }
      if (!apart) continue;
      for (size_t x : *set) vls_[x].junction = true;
    }
  }
}

// 5. Junction areas and their OSM nodes.
void Builder::groupAreas() {
  UnionFind uf(vls_.size());
  for (size_t a = 0; a < vls_.size(); ++a) {
    if (!vls_[a].junction) continue;
    auto link = [&](size_t b) {
      if (vls_[b].junction) uf.join(a, b);
    };
    for (size_t b : conflicts_[a]) link(b);
    for (size_t b : vls_[a].succ) link(b);
    for (size_t b : vls_[a].pred) link(b);
    for (size_t b : vls_[a].lateral) link(b);
  }
  for (const auto& v : vls_) {  // pieces that branch from or merge into one lanelet
    for (const auto* set : {&v.succ, &v.pred}) {
      for (size_t x : *set) {
        for (size_t y : *set) {
          if (vls_[x].junction && vls_[y].junction) uf.join(x, y);
        }
      }
    }
  }
  std::map<size_t, int> area_of_root;
  for (size_t a = 0; a < vls_.size(); ++a) {
    if (!vls_[a].junction) continue;
    const size_t r = uf.find(a);
    auto [it, inserted] = area_of_root.emplace(r, static_cast<int>(areas_.size()));
    if (inserted) areas_.push_back({});
    vls_[a].area = it->second;
    areas_[it->second].lanelets.push_back(a);
  }
  for (auto& area : areas_) {
    Vector2d sum = Vector2d::Zero();
    size_t n = 0;
    for (size_t a : area.lanelets) {
      for (const auto& p : resampleSpacing(vls_[a].centre, 1.0)) {
        sum += p;
        ++n;
      }
    }
    area.centre = sum / static_cast<double>(std::max<size_t>(1, n));
    area.node = next_osm_node_++;
    addOsmNode(area.node, area.centre);
  }
  stats_.junction_areas = areas_.size();
}

// 6. Roads: road lanelets joined by succession or side by side.
void Builder::groupRoads() {
  UnionFind uf(vls_.size());
  for (size_t a = 0; a < vls_.size(); ++a) {
    if (vls_[a].junction) continue;
    for (size_t b : vls_[a].succ) {
      if (!vls_[b].junction) uf.join(a, b);
    }
    for (size_t b : vls_[a].lateral) {
      if (!vls_[b].junction) uf.join(a, b);
    }
  }
  std::map<size_t, int> comp_of_root;
  for (size_t a = 0; a < vls_.size(); ++a) {
    if (vls_[a].junction) continue;
    auto [it, inserted] = comp_of_root.emplace(uf.find(a), static_cast<int>(comps_.size()));
    if (inserted) comps_.push_back({});
    vls_[a].comp = it->second;
    comps_[it->second].lanelets.push_back(a);
  }
  // Same-direction lanes to each road lanelet's left and right, at its middle.
  for (auto& v : vls_) {
    if (v.junction) continue;
    std::vector<size_t> cands;
    for (size_t i : comps_[v.comp].lanelets) cands.push_back(i);
    const auto pr = project(v.centre, resample(v.centre, 3)[1]);
    const Vector2d p = pr.point, t = pr.tangent, n(-t.y(), t.x());
    for (int side = 0; side < 2; ++side) {
      const auto met = cast(vls_, cands, p, side == 0 ? n : Vector2d(-n), nullptr);
      int same = 0;
      for (size_t m : met) {
        if (&vls_[m] == &v) continue;
        const auto pm = project(vls_[m].centre, p);
        if (pm.tangent.dot(t) <= 0.0) break;  // the other direction begins
        ++same;
      }
      (side == 0 ? v.left_same : v.right_same) = same;
    }
  }
}

}  // namespace lanemap::sim::l2w
