#include "core/lanes/stop_lines.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>

namespace lanemap::lanes {

namespace {

struct Found {
  map::Lanelet* lanelet = nullptr;
  Eigen::Vector3d left, right;  // the stop line's ends on this lane's bounds
  Eigen::Vector2d dir;          // driving direction at the stop line
};

// The lanelet's cross-section at arc length s of its centre line (bounds sampled like the centre,
// as toLaneMap writes them): left and right bound points; nullopt when the shapes differ.
std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> crossSection(const map::Lanelet& ll,
                                                                         const map::LineString& l,
                                                                         const map::LineString& r,
                                                                         const std::vector<double>& arc, double s) {
  const auto& c = ll.centre;
  if (l.points.size() != c.size() || r.points.size() != c.size()) return std::nullopt;
  const size_t i = std::clamp<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin(), 1, arc.size() - 1) - 1;
  const double len = arc[i + 1] - arc[i];
  const double t = len > 0.0 ? std::clamp((s - arc[i]) / len, 0.0, 1.0) : 0.0;
  return std::make_pair(l.points[i] + t * (l.points[i + 1] - l.points[i]), r.points[i] + t * (r.points[i + 1] - r.points[i]));
}

std::optional<Found> findOnLane(const bev::BevGrid& grid, map::Lanelet& ll, const map::LineString& l,
                                const map::LineString& r, const StopLineOptions& o) {
  if (ll.centre.size() < 2) return std::nullopt;
  std::vector<double> arc{0.0};
  for (size_t i = 1; i < ll.centre.size(); ++i) arc.push_back(arc.back() + (ll.centre[i] - ll.centre[i - 1]).head<2>().norm());
  const double total = arc.back();
  if (total <= 0.0) return std::nullopt;
  const auto isPaint = [&](const Eigen::Vector2d& p) {
    const auto cell = grid.cellOf(p);
    return grid.count(cell, bev::Layer::kObserved) >= o.min_observed && grid.fraction(cell, bev::Layer::kStopLine) >= o.min_fraction;
  };
  // Stations from the end backwards; the first run of paint stations wins.
  std::optional<double> run_end, run_start;
  for (double back = 0.0; back <= std::min(o.search_m, total) + 1e-9; back += o.step_m) {
    const double s = total - back;
    const auto xs = crossSection(ll, l, r, arc, s);
    if (!xs) return std::nullopt;
    int paint = 0;
    for (int k = 0; k < o.samples; ++k) {
      const double f = 0.1 + 0.8 * (o.samples == 1 ? 0.5 : static_cast<double>(k) / (o.samples - 1));
      paint += isPaint((xs->first + f * (xs->second - xs->first)).head<2>());
    }
    const bool hit = paint >= o.min_cover * o.samples;
    if (hit) {
      if (!run_end) run_end = s;
      run_start = s;
    } else if (run_end) {
      break;
    }
  }
  if (!run_end) return std::nullopt;
  const double s = 0.5 * (*run_start + *run_end);
  const auto xs = crossSection(ll, l, r, arc, s);
  Found f;
  f.lanelet = &ll;
  f.left = xs->first;
  f.right = xs->second;
  const size_t i = std::clamp<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin(), 1, arc.size() - 1) - 1;
  f.dir = (ll.centre[i + 1] - ll.centre[i]).head<2>().normalized();
  return f;
}

}  // namespace

size_t addStopLines(const bev::BevGrid& grid, map::LaneMap& m, const StopLineOptions& o) {
  int64_t next_id = 1;
  for (const auto& l : m.lines) next_id = std::max(next_id, l.id + 1);
  for (const auto& l : m.lanelets) next_id = std::max(next_id, l.id + 1);
  std::vector<Found> found;
  for (auto& ll : m.lanelets) {
    if (!ll.successors.empty() || ll.stop_line_id || ll.kind != map::LaneletKind::kRoad) continue;
    const map::LineString* l = m.line(ll.left_id);
    const map::LineString* r = m.line(ll.right_id);
    if (!l || !r) continue;
    if (auto f = findOnLane(grid, ll, *l, *r, o)) found.push_back(*f);
  }
  // Left to right, then one stop line per group of lanes whose stop lines line up.
  std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
    return a.lanelet->index_from_left < b.lanelet->index_from_left;
  });
  std::vector<bool> used(found.size(), false);
  std::vector<map::LineString> lines;
  for (size_t a = 0; a < found.size(); ++a) {
    if (used[a]) continue;
    std::vector<size_t> group{a};
    used[a] = true;
    const Eigen::Vector2d mid_a = 0.5 * (found[a].left + found[a].right).head<2>();
    for (size_t b = a + 1; b < found.size(); ++b) {
      const Eigen::Vector2d mid_b = 0.5 * (found[b].left + found[b].right).head<2>();
      if (!used[b] && std::abs((mid_b - mid_a).dot(found[a].dir)) < o.merge_m) {
        group.push_back(b);
        used[b] = true;
      }
    }
    // Across the group from its leftmost lane's left end to its rightmost lane's right end, by
    // where the lanes are (index_from_left is counted at each lane's middle: two lanes of a road
    // that end side by side can share it).
    const Eigen::Vector2d to_left(-found[a].dir.y(), found[a].dir.x());
    const auto lateral = [&](size_t g) { return (0.5 * (found[g].left + found[g].right)).head<2>().dot(to_left); };
    std::stable_sort(group.begin(), group.end(), [&](size_t x, size_t y) { return lateral(x) > lateral(y); });
    map::LineString line;
    line.id = next_id++;
    line.type = map::LineType::kStopLine;
    line.points = {found[group.front()].left, found[group.back()].right};
    for (size_t g : group) found[g].lanelet->stop_line_id = line.id;
    lines.push_back(std::move(line));
  }
  for (auto& l : lines) m.lines.push_back(std::move(l));
  return lines.size();
}

namespace {

// A lanelet's centre and bound points at distance `back` from its end (from_end) or its start.
std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> sectionAt(const map::LaneMap& m, const map::Lanelet& ll,
                                                                     double back, bool from_end, Eigen::Vector2d* dir) {
  const map::LineString* l = m.line(ll.left_id);
  const map::LineString* r = m.line(ll.right_id);
  if (!l || !r || ll.centre.size() < 2) return std::nullopt;
  std::vector<double> arc{0.0};
  for (size_t i = 1; i < ll.centre.size(); ++i) arc.push_back(arc.back() + (ll.centre[i] - ll.centre[i - 1]).head<2>().norm());
  if (back > arc.back()) return std::nullopt;
  const double s = from_end ? arc.back() - back : back;
  if (dir) {
    const size_t i = std::clamp<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin(), 1, arc.size() - 1) - 1;
    *dir = (ll.centre[i + 1] - ll.centre[i]).head<2>().normalized();
  }
  return crossSection(ll, *l, *r, arc, s);
}

}  // namespace

std::vector<map::Crosswalk> findCrosswalks(const bev::BevGrid& grid, const map::LaneMap& m, int64_t first_id,
                                           const CrosswalkOptions& o) {
  std::vector<map::Crosswalk> out;
  const auto isPaint = [&](const Eigen::Vector2d& p) {
    const auto cell = grid.cellOf(p);
    return grid.count(cell, bev::Layer::kObserved) >= o.min_observed && grid.fraction(cell, bev::Layer::kCrosswalk) >= o.min_fraction;
  };
  // The lanes at each end: lanelets with no successor (the road's end) / no predecessor (its start).
  std::set<int64_t> has_pred;
  for (const auto& ll : m.lanelets) has_pred.insert(ll.successors.begin(), ll.successors.end());
  for (const bool at_end : {true, false}) {
    std::vector<const map::Lanelet*> lanes;
    for (const auto& ll : m.lanelets) {
      if (ll.kind != map::LaneletKind::kRoad) continue;
      if (at_end ? ll.successors.empty() : !has_pred.count(ll.id)) lanes.push_back(&ll);
    }
    if (lanes.empty()) continue;
    std::sort(lanes.begin(), lanes.end(), [](const auto* a, const auto* b) { return a->index_from_left < b->index_from_left; });
    struct Station {
      double back;
      Eigen::Vector3d left, right;  // the crossing's extent at this station
      Eigen::Vector2d dir;
    };
    std::vector<Station> hits;
    for (double back = 0.0; back <= o.search_m + 1e-9; back += o.step_m) {
      Eigen::Vector2d dir;
      const auto a = sectionAt(m, *lanes.front(), back, at_end, &dir);
      const auto b = sectionAt(m, *lanes.back(), back, at_end, nullptr);
      if (!a || !b) break;
      const Eigen::Vector3d pl = a->first, pr = b->second;
      const double width = (pr - pl).head<2>().norm();
      if (width <= 0.0) continue;
      const Eigen::Vector3d across = (pr - pl) / width;  // left to right
      int paint = 0, n = 0;
      for (double u = 0.0; u <= width + 1e-9; u += o.step_m, ++n) paint += isPaint((pl + u * across).head<2>());
      if (n == 0 || paint < o.min_cover * n) continue;
      // On beyond the lanes while the paint goes on.
      const auto reach = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& step) {
        double last = 0.0;
        for (double u = o.step_m; u <= o.beyond_m + 1e-9 && u - last <= o.max_gap_m; u += o.step_m) {
          if (isPaint((from + u * step).head<2>())) last = u;
        }
        return last;
      };
      const double out_left = reach(pl, -across), out_right = reach(pr, across);
      hits.push_back({back, pl - out_left * across, pr + out_right * across, dir});
    }
    // Runs of stations, each without its end stations whose edge would be under min_edge_m.
    const auto edgeOk = [&](const Station& h) { return (h.right - h.left).head<2>().norm() >= o.min_edge_m; };
    size_t i = 0;
    while (i < hits.size()) {
      size_t j = i;
      while (j + 1 < hits.size() && hits[j + 1].back - hits[j].back <= o.max_gap_m + 1e-9) ++j;
      const size_t run_end = j;
      while (i < j && !edgeOk(hits[i])) ++i;
      while (j > i && !edgeOk(hits[j])) --j;
      if (edgeOk(hits[i]) && hits[j].back - hits[i].back >= o.min_depth_m) {
        // Walking from the right curb to the left one, the edge further along the road is on the right.
        const Station& near = at_end ? hits[j] : hits[i];  // smaller arc length along the road
        const Station& far = at_end ? hits[i] : hits[j];
        map::Crosswalk c;
        c.id = first_id++;
        c.road_id = lanes.front()->road_id;
        c.left = {near.right, near.left};
        c.right = {far.right, far.left};
        for (const auto* ll : lanes) c.crossing.push_back(ll->id);
        out.push_back(std::move(c));
      }
      i = run_end + 1;
    }
  }
  return out;
}

void mergeCrosswalks(std::vector<map::Crosswalk>& cws, double merge_m) {
  const auto centre = [](const map::Crosswalk& c) {
    return (0.25 * (c.left.front() + c.left.back() + c.right.front() + c.right.back())).head<2>().eval();
  };
  const auto width = [](const map::Crosswalk& c) { return (c.left.back() - c.left.front()).head<2>().norm(); };
  std::vector<map::Crosswalk> out;
  for (auto& c : cws) {
    auto it = std::find_if(out.begin(), out.end(), [&](const map::Crosswalk& k) { return (centre(k) - centre(c)).norm() < merge_m; });
    if (it == out.end()) {
      out.push_back(std::move(c));
      continue;
    }
    std::vector<int64_t> crossing = it->crossing;
    crossing.insert(crossing.end(), c.crossing.begin(), c.crossing.end());
    if (width(c) > width(*it)) {
      const int64_t id = it->id;
      *it = std::move(c);
      it->id = id;
    }
    std::sort(crossing.begin(), crossing.end());
    crossing.erase(std::unique(crossing.begin(), crossing.end()), crossing.end());
    it->crossing = std::move(crossing);
  }
  cws = std::move(out);
}

size_t addCrosswalks(map::LaneMap& m, std::vector<map::Crosswalk> found, double merge_m) {
  std::set<int64_t> lanelets;
  int64_t next_id = 1;
  for (const auto& l : m.lines) next_id = std::max(next_id, l.id + 1);
  for (const auto& l : m.lanelets) {
    next_id = std::max(next_id, l.id + 1);
    lanelets.insert(l.id);
  }
  for (const auto& r : m.regulatory_elements) next_id = std::max(next_id, r.id + 1);
  for (const auto& c : m.crosswalks) next_id = std::max(next_id, c.id + 1);
  for (auto& c : found) {
    c.id = next_id++;
    c.crossing.erase(std::remove_if(c.crossing.begin(), c.crossing.end(), [&](int64_t id) { return !lanelets.count(id); }),
                     c.crossing.end());
  }
  mergeCrosswalks(found, merge_m);
  const size_t n = found.size();
  for (auto& c : found) m.crosswalks.push_back(std::move(c));
  return n;
}

}  // namespace lanemap::lanes
