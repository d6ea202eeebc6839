#include "core/mapping/shared_dividers.h"

#include "core/geo/polyline.h"
#include "core/io/lanelet2_orientation.h"

#include <algorithm>
#include <map>
#include <set>
#include <unordered_map>
#include <vector>

namespace lanemap::mapping {
namespace {

using Points = std::vector<Eigen::Vector3d>;

// The share of `a`'s points (every metre, as lanemap-check samples) within tolerance_m of `b`.
double shareOn(const Points& a, const Points& b, double tolerance_m) {
  const auto s = geo::pointsEveryXy(a, 1.0);
  if (s.empty()) return 0.0;
  size_t on = 0;
  for (const auto& p : s) on += geo::distanceToPolylineXy(b, p) <= tolerance_m;
  return static_cast<double>(on) / static_cast<double>(s.size());
}

// Whether a and b are one line drawn twice (see the header): running against each other (`along`
// false: a divider, once for each direction), one's start within end_gap_max_m of the other's end
// and back; or running the same way (`along`: the border of two neighbouring connections, whose
// road lanes' probes of one painted line differ by its width), start within that of start and end
// of end; and each lying on the other.
bool onTop(const Points& a, const Points& b, bool along, const SharedDividerOptions& o) {
  if (a.size() < 2 || b.size() < 2) return false;
  const Eigen::Vector2d da = (a.back() - a.front()).head<2>(), db = (b.back() - b.front()).head<2>();
  if (along ? da.dot(db) <= 0.0 : da.dot(db) >= 0.0) return false;
  const Eigen::Vector3d& b_first = along ? b.front() : b.back();
  const Eigen::Vector3d& b_last = along ? b.back() : b.front();
  if ((a.front() - b_first).head<2>().norm() > o.end_gap_max_m || (a.back() - b_last).head<2>().norm() > o.end_gap_max_m) {
    return false;
  }
  return shareOn(a, b, o.tolerance_m) >= o.share && shareOn(b, a, o.tolerance_m) >= o.share;
}

// Moves a line's end by `by`, and its points near that end by less the farther they are along it
// (nothing from taper_m on, or at its other end), so the line does not kink where it was joined.
void moveEnd(Points& pl, bool at_front, const Eigen::Vector3d& by, double taper_m) {
  if (!at_front) std::reverse(pl.begin(), pl.end());
  const double reach = std::min(taper_m, geo::polylineLength(pl));
  std::vector<double> s(pl.size(), 0.0);  // along the line as it was
  for (size_t i = 1; i < pl.size(); ++i) s[i] = s[i - 1] + (pl[i] - pl[i - 1]).norm();
  for (size_t i = 0; i < pl.size() && (i == 0 || s[i] < reach); ++i) pl[i] += by * (i == 0 ? 1.0 : 1.0 - s[i] / reach);
  if (!at_front) std::reverse(pl.begin(), pl.end());
}

}  // namespace

size_t shareDividers(map::LaneMap& m, const skeleton::Skeleton& skeleton, const SharedDividerOptions& o) {
  std::unordered_map<int64_t, size_t> line_at;
  for (size_t i = 0; i < m.lines.size(); ++i) line_at[m.lines[i].id] = i;
  std::map<int64_t, std::set<int64_t>> bounds_of_road;          // road id -> its road lanelets' bound lines
  std::map<int64_t, std::set<int64_t>> bounds_of_intersection;  // OSM node id -> its lanelets' bound lines
  for (const auto& ll : m.lanelets) {
    auto* bounds = ll.kind == map::LaneletKind::kRoad ? (ll.road_id >= 0 ? &bounds_of_road[ll.road_id] : nullptr)
                                                      : &bounds_of_intersection[ll.intersection_id];
    if (!bounds) continue;
    for (int64_t id : {ll.left_id, ll.right_id}) {
      if (line_at.count(id)) bounds->insert(id);
    }
  }
  std::unordered_map<int64_t, std::vector<size_t>> lanelets_of_line;  // line id -> lanelets bounded by it
  for (size_t i = 0; i < m.lanelets.size(); ++i) {
    lanelets_of_line[m.lanelets[i].left_id].push_back(i);
    if (m.lanelets[i].right_id != m.lanelets[i].left_id) lanelets_of_line[m.lanelets[i].right_id].push_back(i);
  }
  // Whether Lanelet2 reads lanelet i as meant, with `drop` read as `keep`.
  const auto readAsMeant = [&](size_t i, int64_t drop, int64_t keep) {
    map::Lanelet ll = m.lanelets[i];
    if (ll.left_id == drop) ll.left_id = keep;
    if (ll.right_id == drop) ll.right_id = keep;
    const auto left = line_at.find(ll.left_id), right = line_at.find(ll.right_id);
    return left != line_at.end() && right != line_at.end() &&
           io::orientationProblem(ll, m.lines[left->second], m.lines[right->second]).empty();
  };
  std::set<int64_t> dropped;
  // Makes a and b one line when they are one divider drawn twice (or, `along`: one border of two
  // neighbouring connections).
  const auto share = [&](int64_t a, int64_t b, bool along) {
    if (a == b || dropped.count(a) || dropped.count(b)) return;
    const map::LineString& la = m.lines[line_at.at(a)];
    const map::LineString& lb = m.lines[line_at.at(b)];
    if (!onTop(la.points, lb.points, along, o)) return;
    const bool keep_b = la.type == map::LineType::kVirtual && lb.type != map::LineType::kVirtual;
    const int64_t keep_id = keep_b ? b : a, drop_id = keep_b ? a : b;
    const map::LineString& keep = m.lines[line_at.at(keep_id)];
    const map::LineString& drop = m.lines[line_at.at(drop_id)];
    // Lines that ended at the dropped line's ends end at the kept line's (the same end along,
    // the other against).
    const Eigen::Vector3d drop_front = drop.points.front(), drop_back = drop.points.back();
    const Eigen::Vector3d keep_front = keep.points.front(), keep_back = keep.points.back();
    std::vector<std::pair<size_t, Points>> moved;  // line index, its points before
    for (size_t k = 0; k < m.lines.size(); ++k) {
      auto& l = m.lines[k];
      if (l.id == drop_id || l.id == keep_id || l.points.empty()) continue;
      for (bool at_front : {true, false}) {
        const Eigen::Vector3d end = at_front ? l.points.front() : l.points.back();
        const bool at_drop_front = (end - drop_front).norm() < 1e-6, at_drop_back = (end - drop_back).norm() < 1e-6;
        if (!at_drop_front && !at_drop_back) continue;
        if (moved.empty() || moved.back().first != k) moved.emplace_back(k, l.points);
        moveEnd(l.points, at_front, (at_drop_front != along ? keep_back : keep_front) - end, o.taper_m);
      }
    }
    // Every lanelet of the dropped line, and of a line moved, as Lanelet2 will read it; else undone.
    std::vector<size_t> to_check = lanelets_of_line[drop_id];
    for (const auto& [k, before] : moved) {
      const auto& of = lanelets_of_line[m.lines[k].id];
      to_check.insert(to_check.end(), of.begin(), of.end());
    }
    if (!std::all_of(to_check.begin(), to_check.end(), [&](size_t i) { return readAsMeant(i, drop_id, keep_id); })) {
      for (auto& [k, before] : moved) m.lines[k].points = std::move(before);
      return;
    }
    for (size_t i : lanelets_of_line[drop_id]) {
      auto& ll = m.lanelets[i];
      if (ll.left_id == drop_id) ll.left_id = keep_id;
      if (ll.right_id == drop_id) ll.right_id = keep_id;
      lanelets_of_line[keep_id].push_back(i);
    }
    lanelets_of_line.erase(drop_id);
    dropped.insert(drop_id);
  };
  for (const auto& [road_id, lines] : bounds_of_road) {
    const auto* road = skeleton.road(road_id);
    if (!road || road->reverse_id <= road_id) continue;  // each pair once, from its lower id
    const auto rev = bounds_of_road.find(road->reverse_id);
    if (rev == bounds_of_road.end()) continue;
    for (int64_t a : lines) {
      for (int64_t b : rev->second) share(a, b, false);
    }
  }
  for (const auto& [node, lines] : bounds_of_intersection) {
    for (auto a = lines.begin(); a != lines.end(); ++a) {
      for (auto b = std::next(a); b != lines.end(); ++b) {
        share(*a, *b, false);
        share(*a, *b, true);
      }
    }
  }
  if (!dropped.empty()) {
    m.lines.erase(std::remove_if(m.lines.begin(), m.lines.end(), [&](const map::LineString& l) { return dropped.count(l.id) > 0; }),
                  m.lines.end());
  }
  return dropped.size();
}

}  // namespace lanemap::mapping
