#include "core/lanes/stop_lines.h"

#include <algorithm>
#include <cmath>
#include <optional>

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

}  // namespace lanemap::lanes
