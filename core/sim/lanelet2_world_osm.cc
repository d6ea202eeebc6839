// The Lanelet2 world, step 7: the road-level OSM derived from the lanelets, and its skeleton
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

void Builder::addOsmNode(int64_t id, const Vector2d& p) {
  const geo::LatLonAlt g = frame_.toWgs84(Vector3d(p.x(), p.y(), 0.0));
  osm::Node n;
  n.id = id;
  // OSM's precision (what roads.osm stores), so a skeleton built from the file is this one.
  n.lat = std::round(g.lat * 1e7) / 1e7;
  n.lon = std::round(g.lon * 1e7) / 1e7;
  roads_.nodes[id] = n;
}

// The longest chain of successors inside a road (its spine), in its driving direction.
std::vector<size_t> Builder::spine(const std::vector<size_t>& members) const {
  std::set<size_t> in(members.begin(), members.end());
  std::vector<size_t> best;
  double best_len = -1.0;
  for (size_t start : members) {
    bool has_pred = false;
    for (size_t p : vls_[start].pred) has_pred |= in.count(p) > 0;
    if (has_pred) continue;
    std::vector<size_t> chain{start};
    std::set<size_t> seen{start};
    double len = length(vls_[start].centre);
    for (;;) {
      const VL& cur = vls_[chain.back()];
      size_t next = SIZE_MAX;
      double best_turn = 1e9;
      for (size_t s : cur.succ) {
        if (!in.count(s) || seen.count(s)) continue;
        const double turn = std::abs(headingChange({cur.centre[cur.centre.size() - 2], cur.centre.back(),
                                                    vls_[s].centre[1]}));
        if (turn < best_turn) {
          best_turn = turn;
          next = s;
        }
      }
      if (next == SIZE_MAX) break;
      chain.push_back(next);
      seen.insert(next);
      len += length(vls_[next].centre);
    }
    if (len > best_len) {
      best_len = len;
      best = chain;
    }
  }
  if (best.empty()) best.push_back(members.front());  // a ring: any lanelet
  return best;
}

// 7. The road-level OSM: one way per road, junction node to junction node; then the skeleton.
void Builder::deriveOsm() {
  int64_t way_id = 1;
  for (auto& comp : comps_) {
    const auto chain = spine(comp.lanelets);
    std::vector<Vector2d> centre;
    for (size_t i : chain) {
      for (const auto& p : vls_[i].centre) {
        if (centre.empty() || (p - centre.back()).norm() > 1e-3) centre.push_back(p);
      }
    }
    if (centre.size() < 2 || length(centre) < 0.5) continue;
    // The middle of the whole cross-section at every 2 m of the spine.
    const auto samples = resampleSpacing(centre, 2.0);
    std::vector<size_t> cands = comp.lanelets;
    std::vector<Vector2d> mid, normals;
    std::vector<double> offsets;
    int fwd_max = 0, bwd_max = 0;
    for (size_t k = 0; k < samples.size(); ++k) {
      const Vector2d p = samples[k];
      const Vector2d t = (samples[std::min(k + 1, samples.size() - 1)] - samples[k > 0 ? k - 1 : 0]).normalized();
      const Vector2d n(-t.y(), t.x());
      double dl = 0.0, dr = 0.0;
      const auto ml = cast(vls_, cands, p, n, &dl);
      const auto mr = cast(vls_, cands, p, -n, &dr);
      offsets.push_back(0.5 * (dl - dr));
      normals.push_back(n);
      std::set<size_t> met(ml.begin(), ml.end());
      met.insert(mr.begin(), mr.end());
      int f = 0, b = 0;
      for (size_t m : met) (project(vls_[m].centre, p).tangent.dot(t) > 0 ? f : b)++;
      fwd_max = std::max({fwd_max, f, 1});
      bwd_max = std::max(bwd_max, b);
    }
    // The offset of the middle from the spine, robustly smoothed (a cast that runs into a
    // branching lane jumps): median of 7, then mean of 5.
    std::vector<double> med(offsets.size());
    for (size_t k = 0; k < offsets.size(); ++k) {
      std::vector<double> win;
      for (size_t q = k >= 3 ? k - 3 : 0; q < std::min(offsets.size(), k + 4); ++q) win.push_back(offsets[q]);
      std::nth_element(win.begin(), win.begin() + win.size() / 2, win.end());
      med[k] = win[win.size() / 2];
    }
    for (size_t k = 0; k < offsets.size(); ++k) {
      double sum = 0.0;
      int cnt = 0;
      for (size_t q = k >= 2 ? k - 2 : 0; q < std::min(offsets.size(), k + 3); ++q, ++cnt) sum += med[q];
      mid.push_back(samples[k] + normals[k] * (sum / cnt));
    }
    for (size_t m : comp.lanelets) {
      const Vector2d pm = resample(vls_[m].centre, 3)[1];
      if (project(centre, pm).tangent.dot(project(vls_[m].centre, pm).tangent) < 0) bwd_max = std::max(bwd_max, 1);
    }
    // Junction areas along the road: where its lanelets lead into or come from junction
    // lanelets. Those near an end end the way there (the closest at each end); those further in
    // (a junction the road's other lanes pass by, e.g. an entry into a roundabout's ring) are
    // junction nodes on the way, moved onto its middle line.
    const double L = length(centre);
    const double end_zone = std::min(12.0, 0.3 * L);
    std::map<int, Projection> attached;  // area -> its attachment nearest the spine
    for (size_t m : comp.lanelets) {
      auto attach = [&](size_t other, const Vector2d& where) {
        const int a = vls_[other].area;
        if (a < 0) return;
        const auto pr = project(centre, where);
        if (!attached.count(a) || pr.distance < attached[a].distance) attached[a] = pr;
      };
      for (size_t s : vls_[m].succ) attach(s, vls_[m].centre.back());
      for (size_t p : vls_[m].pred) attach(p, vls_[m].centre.front());
    }
    int a0 = -1, a1 = -1;
    double d0 = 1e300, d1 = 1e300;
    std::vector<std::pair<double, int>> inner;  // (s, area)
    for (const auto& [a, pr] : attached) {
      if (pr.s < end_zone) {
        if (pr.s + pr.distance < d0) {
          d0 = pr.s + pr.distance;
          a0 = a;
        }
      } else if (pr.s > L - end_zone) {
        if (L - pr.s + pr.distance < d1) {
          d1 = L - pr.s + pr.distance;
          a1 = a;
        }
      } else {
        inner.emplace_back(pr.s, a);
      }
    }
    std::sort(inner.begin(), inner.end());
    // A stub shorter than kMinRoadLength beside one junction (a short lane piece drawn at its
    // edge) is part of that junction, not a road of its own; a short link between two
    // junctions stays a road.
    std::set<int> areas_met;
    for (const auto& [a, pr] : attached) areas_met.insert(a);
    if (L < kMinRoadLength && areas_met.size() == 1) {
      int best = -1;
      double bd = 1e300;
      for (const auto& [a, pr] : attached) {
        if (pr.distance < bd) {
          bd = pr.distance;
          best = a;
        }
      }
      for (size_t m : comp.lanelets) {
        vls_[m].junction = true;
        vls_[m].area = best;
      }
      ++stats_.stubs_in_junctions;
      continue;
    }
    // Interior junctions move onto this road's middle line (the first road to pass one wins).
    for (const auto& [s_in, a] : inner) {
      if (a == a0 || a == a1) continue;
      auto& area = areas_[a];
      if (!area.pinned) {
        area.pinned = true;
        const double step = samples.size() > 1 ? L / static_cast<double>(samples.size() - 1) : L;
        area.centre = mid[std::min(mid.size() - 1, static_cast<size_t>(std::lround(s_in / step)))];
        addOsmNode(area.node, area.centre);
      }
    }
    comp.way_line = centre;  // for the direction of each lanelet
    comp.mid = std::move(mid);
    comp.length = L;
    comp.a0 = a0;
    comp.a1 = a1;
    comp.inner = std::move(inner);
    comp.forward = fwd_max;
    comp.backward = bwd_max;
    comp.has_way = true;
  }
  // A junction that a one-way carriageway runs through (it ends one road and begins the next
  // going on in nearly the same direction, e.g. a roundabout's ring past an entry): its node
  // goes onto the carriageway, between the two roads, as OSM draws it (and as OSM's, a small
  // roundabout's nodes are then close enough for the skeleton to make it one intersection).
  for (size_t a = 0; a < areas_.size(); ++a) {
    auto& area = areas_[a];
    if (area.pinned) continue;
    int pairs = 0;
    Vector2d at = Vector2d::Zero();
    for (const auto& x : comps_) {
      if (!x.has_way || x.a1 != static_cast<int>(a) || x.backward > 0 || x.way_line.size() < 2) continue;
      for (const auto& y : comps_) {
        if (&x == &y || !y.has_way || y.a0 != static_cast<int>(a) || y.backward > 0 || y.way_line.size() < 2) continue;
        const Vector2d tx = (x.way_line.back() - x.way_line[x.way_line.size() - 2]).normalized();
        const Vector2d ty = (y.way_line[1] - y.way_line.front()).normalized();
        const Vector2d gap = y.mid.front() - x.mid.back();
        if (tx.dot(ty) < std::cos(100.0 * kPi / 180.0) || gap.norm() > 40.0) continue;
        ++pairs;
        at = 0.5 * (x.mid.back() + y.mid.front());
      }
    }
    if (pairs != 1) continue;
    area.pinned = true;
    area.centre = at;
    addOsmNode(area.node, at);
    ++stats_.through_junctions;
  }
  // The ways, once every junction node has its place.
  for (auto& comp : comps_) {
    if (!comp.has_way) continue;
    struct WayPoint {
      int64_t node;  // -1: a new node
      Vector2d p;
    };
    std::vector<WayPoint> pts;
    const auto& mid = comp.mid;
    const double step = mid.size() > 1 ? comp.length / static_cast<double>(mid.size() - 1) : comp.length;
    size_t k = 0;
    auto run_until = [&](double s_stop) {  // the middle line's points before s_stop, simplified
      std::vector<Vector2d> run;
      for (; k < mid.size() && static_cast<double>(k) * step < s_stop; ++k) run.push_back(mid[k]);
      for (const auto& p : simplify(run, 0.2)) pts.push_back({-1, p});
    };
    if (comp.a0 >= 0) pts.push_back({areas_[comp.a0].node, areas_[comp.a0].centre});
    for (const auto& [s_in, a] : comp.inner) {
      if (a == comp.a0 || a == comp.a1) continue;
      run_until(s_in - 2.5);
      while (k < mid.size() && static_cast<double>(k) * step < s_in + 2.5) ++k;
      if (pts.empty() || pts.back().node != areas_[a].node) pts.push_back({areas_[a].node, areas_[a].centre});
    }
    run_until(1e300);
    if (comp.a1 >= 0 && (comp.a1 != comp.a0 || pts.size() > 2)) pts.push_back({areas_[comp.a1].node, areas_[comp.a1].centre});
    // No fold-backs: drop middle-line points where the way would turn by more than 100 degrees
    // (a junction node beside or behind the road's first lane points), and points closer than
    // 0.5 m to the one before.
    for (bool changed = true; changed;) {
      changed = false;
      for (size_t i = 1; i + 1 < pts.size() && !changed; ++i) {
        const Vector2d u = pts[i].p - pts[i - 1].p, v = pts[i + 1].p - pts[i].p;
        const bool close = u.norm() < 0.5;
        const bool fold = !close && v.norm() > 1e-6 && u.normalized().dot(v.normalized()) < std::cos(100.0 * kPi / 180.0);
        if (!close && !fold) continue;
        size_t drop = SIZE_MAX;
        if (pts[i].node < 0) drop = i;
        else if (close && pts[i - 1].node < 0 && i - 1 > 0) drop = i - 1;
        else if (fold && pts[i - 1].node < 0 && i - 1 > 0) drop = i - 1;
        else if (fold && pts[i + 1].node < 0 && i + 1 < pts.size() - 1) drop = i + 1;
        if (drop != SIZE_MAX) {
          pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(drop));
          changed = true;
        }
      }
    }
    osm::Way w;
    w.id = way_id++;
    for (const auto& q : pts) {
      int64_t id = q.node;
      if (id < 0) {
        id = next_osm_node_++;
        addOsmNode(id, q.p);
      }
      if (w.nodes.empty() || w.nodes.back() != id) w.nodes.push_back(id);
    }
    if (w.nodes.size() < 2) continue;
    const int fwd_max = comp.forward, bwd_max = comp.backward;
    const int lanes = fwd_max + bwd_max;
    w.tags["highway"] = std::max(fwd_max, bwd_max) >= 2 ? "secondary" : "residential";
    w.tags["lanes"] = std::to_string(std::max(1, lanes));
    if (bwd_max == 0) {
      w.tags["oneway"] = "yes";
    } else {
      w.tags["lanes:forward"] = std::to_string(fwd_max);
      w.tags["lanes:backward"] = std::to_string(bwd_max);
    }
    w.tags["lanemap:source"] = "lanelet2";
    comp.way_id = w.id;
    roads_.ways.push_back(std::move(w));
    ++stats_.roads;
  }
  if (roads_.ways.empty()) throw std::runtime_error(path_ + ": no road could be derived from the lanelets");
  // Drop the junction nodes no way uses; bounds from the nodes.
  std::set<int64_t> used;
  for (const auto& w : roads_.ways) used.insert(w.nodes.begin(), w.nodes.end());
  for (auto it = roads_.nodes.begin(); it != roads_.nodes.end();) {
    it = used.count(it->first) ? std::next(it) : roads_.nodes.erase(it);
  }
  osm::Bounds b{1e9, 1e9, -1e9, -1e9};
  for (const auto& [id, n] : roads_.nodes) {
    b.min_lat = std::min(b.min_lat, n.lat);
    b.max_lat = std::max(b.max_lat, n.lat);
    b.min_lon = std::min(b.min_lon, n.lon);
    b.max_lon = std::max(b.max_lon, n.lon);
  }
  roads_.bounds = b;
  skeleton::SkeletonOptions so;
  so.origin = origin_;
  skeleton_ = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(roads_, so));
}

}  // namespace lanemap::sim::l2w
