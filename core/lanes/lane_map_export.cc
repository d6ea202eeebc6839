// toLaneMap (explorer.h): the explored lanes of one road as Lanelet2 lanelets.
#include "core/lanes/explorer.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

namespace lanemap::lanes {

namespace {

double interp(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
  if (xs.size() == 1) return ys[0];
  auto it = std::upper_bound(xs.begin(), xs.end(), x);
  size_t i = std::clamp<size_t>(it - xs.begin(), 1, xs.size() - 1) - 1;
  const double t = std::clamp((x - xs[i]) / std::max(1e-9, xs[i + 1] - xs[i]), 0.0, 1.0);
  return ys[i] + t * (ys[i + 1] - ys[i]);
}


// The stations of a lanelet piece [a, b] of lane l: its ends and the lane's way-points between them.
std::vector<double> pieceStations(const Lane& l, double a, double b) {
  std::vector<double> ss{a};
  for (double s : l.waypoint_s) if (s > a + 0.2 && s < b - 0.2) ss.push_back(s);
  ss.push_back(b);
  return ss;
}

// The type of a border two lanes share, from what each lane's probes found there: paint wins over
// no paint, solid over dashed (crossing it is not allowed when either side saw a solid line).
map::LineType sharedType(map::LineType a, map::LineType b) {
  using map::LineType;
  if (a == b) return a;
  for (LineType t : {LineType::kSolidSolid, LineType::kSolid, LineType::kDashed, LineType::kCurb}) {
    if (a == t || b == t) return t;
  }
  return a;
}

}  // namespace

double boundaryD(const Lane& l, const Boundary& b, double s) { return interp(l.waypoint_s, b.d, s); }

std::vector<LaneNeighbours> laneNeighbours(const ExplorationResult& r, const LaneNeighbourOptions& o) {
  std::vector<LaneNeighbours> out;
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    for (size_t j = 0; j < r.lanes.size(); ++j) {
      if (i == j) continue;
      const Lane& left = r.lanes[i];
      const Lane& right = r.lanes[j];
      const double a = std::max(left.s_begin, right.s_begin), b = std::min(left.s_end, right.s_end);
      if (!(b - a >= o.min_overlap_m)) continue;
      const int n = std::max(2, static_cast<int>(std::ceil((b - a) / o.sample_m)) + 1);
      int on = 0;
      double first = INFINITY, last = -INFINITY;  // the first and last sample where the bounds agree
      for (int k = 0; k < n; ++k) {
        const double s = a + (b - a) * k / (n - 1);
        if (left.dAt(s) <= right.dAt(s)) {  // `right` must lie right of `left` all along
          on = -1;
          break;
        }
        if (std::abs(boundaryD(left, left.right, s) - boundaryD(right, right.left, s)) <= o.tolerance_m) {
          ++on;
          first = std::min(first, s);
          last = std::max(last, s);
        }
      }
      // Shared from the first to the last place they agree: where one lane tapers off beside the
      // other their probes part, and a border halfway between them would jump at its end.
      if (on >= o.min_fraction * n && last - first >= o.min_overlap_m) {
        out.push_back({static_cast<int>(i), static_cast<int>(j), first, last});
      }
    }
  }
  return out;
}

map::LaneMap toLaneMap(const ExplorationResult& r, double lat, double lon, double alt) {
  map::LaneMap out;
  out.origin_lat = lat;
  out.origin_lon = lon;
  out.origin_alt = alt;
  const int64_t base = (r.road_id + 1) * 100000;
  int64_t next = base + 1;
  // Cut points of every lane: where a lane splits off it or merges into it.
  std::vector<std::vector<double>> cuts(r.lanes.size());
  for (size_t i = 0; i < r.lanes.size(); ++i) cuts[i] = {r.lanes[i].s_begin, r.lanes[i].s_end};
  // A cut within 1 m of a lane's end is none (the end is a cut already).
  const auto inside = [&](int lane, double s) { return s > r.lanes[lane].s_begin + 1.0 && s < r.lanes[lane].s_end - 1.0; };
  auto addCut = [&](int lane, double s) {
    if (inside(lane, s)) cuts[lane].push_back(s);
  };
  for (const Lane& l : r.lanes) {
    if (l.split_from >= 0) addCut(l.split_from, l.s_begin);
    if (l.merges_into >= 0) addCut(l.merges_into, l.s_end);
  }
  // Two neighbouring lanes share one border line string (Lanelet2 and Autoware: a lane change is
  // possible only between lanelets with a common bound), so their pieces must begin and end at
  // the same s over the stretch they run side by side: each takes the other's cuts there.
  // Where a stretch ends within 1 m of one lane's end, that end is where the other is cut (a
  // cut one of them took at the stretch's end and the other not, being too near its end, would
  // leave one lane in two pieces beside the other's one, and their border drawn twice).
  const std::vector<LaneNeighbours> neighbours = laneNeighbours(r);
  const auto nearestEnd = [&](int lane, double s) {
    const Lane& l = r.lanes[lane];
    return std::abs(s - l.s_begin) < std::abs(s - l.s_end) ? l.s_begin : l.s_end;
  };
  for (const auto& nb : neighbours) {
    for (const double s : {nb.s_begin, nb.s_end}) {
      addCut(nb.left, inside(nb.right, s) ? s : nearestEnd(nb.right, s));
      addCut(nb.right, inside(nb.left, s) ? s : nearestEnd(nb.left, s));
    }
  }
  for (size_t pass = 0; pass <= r.lanes.size(); ++pass) {  // until no cut is new (chains of lanes)
    bool added = false;
    for (const auto& nb : neighbours) {
      for (const auto& [from, to] : {std::pair{nb.left, nb.right}, std::pair{nb.right, nb.left}}) {
        const std::vector<double> theirs = cuts[from];
        for (double s : theirs) {
          if (s <= nb.s_begin + 1.0 || s >= nb.s_end - 1.0) continue;
          const bool known = std::any_of(cuts[to].begin(), cuts[to].end(), [&](double c) { return std::abs(c - s) < 1.0; });
          if (!known) {
            addCut(to, s);
            added = true;
          }
        }
      }
    }
    if (!added) break;
  }
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    auto& c = cuts[i];
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end(), [](double a, double b) { return std::abs(a - b) < 1.0; }), c.end());
    if (c.size() < 2) c = {r.lanes[i].s_begin, r.lanes[i].s_end};
  }
  // Where two neighbours' cuts are within 1 m of each other, both take the same one (the left
  // lane's), so that their shared border ends exactly where each piece's other bound ends (Lanelet2
  // joins a lanelet to its successor by their bounds' common end points).
  for (size_t pass = 0; pass <= r.lanes.size(); ++pass) {
    bool moved = false;
    for (const auto& nb : neighbours) {
      for (double& c : cuts[nb.right]) {
        if (c < nb.s_begin - 1.0 || c > nb.s_end + 1.0) continue;
        for (double l : cuts[nb.left]) {
          if (std::abs(l - c) < 1.0 && l != c) {
            c = l;
            moved = true;
          }
        }
      }
    }
    if (!moved) break;
  }
  // A lane's bound offset at s: halfway between its probes and its neighbour's where the two share
  // the border, its own probes elsewhere. Every piece and every shared line takes its points from
  // here, so a bound runs on without a break where it becomes or stops being shared; within
  // kBlendM of the shared stretch the lane's own probes blend into it linearly, so the bound does
  // not step sideways where its sharing begins or ends.
  constexpr double kBlendM = 4.0;
  const auto boundAt = [&](int lane, bool right_side, double s) -> double {
    const Lane& l = r.lanes[lane];
    const double own = boundaryD(l, right_side ? l.right : l.left, s);
    for (const auto& nb : neighbours) {
      if ((right_side ? nb.left : nb.right) != lane) continue;
      const double outside = std::max(nb.s_begin - 1.0 - s, s - nb.s_end - 1.0);  // <= 0: shared here
      if (outside >= kBlendM) continue;
      const Lane& ll = r.lanes[nb.left];
      const Lane& rl = r.lanes[nb.right];
      const double shared = 0.5 * (boundaryD(ll, ll.right, s) + boundaryD(rl, rl.left, s));
      const double w = outside <= 0.0 ? 1.0 : 1.0 - outside / kBlendM;
      return own + w * (shared - own);
    }
    return own;
  };
  // The piece k of `lane` that spans [a, b] (its ends within 1 m), if there is one.
  const auto pieceOf = [&](int lane, double a, double b) -> int {
    const auto& c = cuts[lane];
    for (size_t k = 0; k + 1 < c.size(); ++k) {
      if (std::abs(c[k] - a) < 1.0 && std::abs(c[k + 1] - b) < 1.0) return static_cast<int>(k);
    }
    return -1;
  };
  // The border that piece [a, b] of `lane` shares with its neighbour on one side: made once, by
  // whichever of the two lanes comes first, at the left lane's way-points, halfway between the two
  // lanes' probes of it. -1: no neighbour there with a piece over the same stretch.
  std::map<std::tuple<int, int, int>, int64_t> shared_line;  // (left lane, right lane, its piece) -> line
  const auto sharedBorder = [&](int lane, bool on_right, double a, double b) -> int64_t {
    for (const auto& nb : neighbours) {
      if ((on_right ? nb.left : nb.right) != lane) continue;
      // (up to 2 m beyond it: a stretch that ends within 1 m of a lane's end is not cut there)
      if (a < nb.s_begin - 2.0 || b > nb.s_end + 2.0) continue;
      const int k = pieceOf(nb.left, a, b);
      if (k < 0 || pieceOf(nb.right, a, b) < 0) continue;
      const auto key = std::tuple{nb.left, nb.right, k};
      if (const auto it = shared_line.find(key); it != shared_line.end()) return it->second;
      const Lane& ll = r.lanes[nb.left];
      const Lane& rl = r.lanes[nb.right];
      const double from = cuts[nb.left][k], to = cuts[nb.left][k + 1];
      map::LineString line;
      line.id = next++;
      line.type = sharedType(ll.right.type, rl.left.type);
      for (double s : pieceStations(ll, from, to)) {
        const Eigen::Vector2d p = r.frame->toEnu(s, boundAt(nb.left, true, s));
        line.points.emplace_back(p.x(), p.y(), 0.0);
      }
      shared_line[key] = line.id;
      out.lines.push_back(std::move(line));
      return out.lines.back().id;
    }
    return -1;
  };
  // piece ids per lane: (start s, lanelet id)
  std::vector<std::vector<std::pair<double, int64_t>>> pieces(r.lanes.size());
  std::map<int64_t, size_t> pos;
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    const Lane& l = r.lanes[i];
    const auto& c = cuts[i];
    for (size_t k = 0; k + 1 < c.size(); ++k) {
      const double a = c[k], b = c[k + 1];
      const std::vector<double> ss = pieceStations(l, a, b);
      const int64_t shared_left = sharedBorder(static_cast<int>(i), false, a, b);
      const int64_t shared_right = sharedBorder(static_cast<int>(i), true, a, b);
      map::LineString left, right;
      if (shared_left < 0) left.id = next++;
      if (shared_right < 0) right.id = next++;
      left.type = l.left.type;
      right.type = l.right.type;
      map::Lanelet ll;
      ll.id = next++;
      ll.kind = map::LaneletKind::kRoad;
      ll.road_id = r.road_id;
      ll.from_node = r.from_node;
      ll.to_node = r.to_node;
      ll.index_from_left = l.index_from_left;
      ll.left_id = shared_left >= 0 ? shared_left : left.id;
      ll.right_id = shared_right >= 0 ? shared_right : right.id;
      for (double s : ss) {
        const double dl = boundAt(static_cast<int>(i), false, s), dr = boundAt(static_cast<int>(i), true, s);
        // The centre line comes from the particles, the bounds from the probes: where a bound was
        // drawn in past the centre (at most recentre_max_m recentres it), the centre is kept on the
        // lanelet's edge (within kCentreSlackM) so that it never leaves its lanelet.
        constexpr double kCentreSlackM = 0.05;
        const double dc = std::clamp(l.centre.d(s), std::min(dl, dr) - kCentreSlackM, std::max(dl, dr) + kCentreSlackM);
        const Eigen::Vector2d pl = r.frame->toEnu(s, dl), pr = r.frame->toEnu(s, dr), pc = r.frame->toEnu(s, dc);
        left.points.emplace_back(pl.x(), pl.y(), 0.0);
        right.points.emplace_back(pr.x(), pr.y(), 0.0);
        ll.centre.emplace_back(pc.x(), pc.y(), 0.0);
      }
      pieces[i].push_back({a, ll.id});
      if (shared_left < 0) out.lines.push_back(std::move(left));
      if (shared_right < 0) out.lines.push_back(std::move(right));
      pos[ll.id] = out.lanelets.size();
      out.lanelets.push_back(std::move(ll));
    }
  }
  auto lanelet = [&](int64_t id) -> map::Lanelet& { return out.lanelets[pos.at(id)]; };
  // The piece of lane i that ends at s (or starts at s).
  auto pieceEnding = [&](int i, double s) -> int64_t {
    const auto& p = pieces[i];
    for (size_t k = 0; k < p.size(); ++k) {
      const double end = k + 1 < p.size() ? p[k + 1].first : r.lanes[i].s_end;
      if (std::abs(end - s) < 1.0) return p[k].second;
    }
    return -1;
  };
  auto pieceStarting = [&](int i, double s) -> int64_t {
    for (const auto& [a, id] : pieces[i]) if (std::abs(a - s) < 1.0) return id;
    return -1;
  };
  for (size_t i = 0; i < r.lanes.size(); ++i) {
    for (size_t k = 0; k + 1 < pieces[i].size(); ++k) lanelet(pieces[i][k].second).successors.push_back(pieces[i][k + 1].second);
    const Lane& l = r.lanes[i];
    if (l.split_from >= 0) {
      const int64_t from = pieceEnding(l.split_from, l.s_begin);
      if (from >= 0) lanelet(from).successors.push_back(pieces[i].front().second);
    }
    if (l.merges_into >= 0) {
      const int64_t to = pieceStarting(l.merges_into, l.s_end);
      if (to >= 0) lanelet(pieces[i].back().second).successors.push_back(to);
    }
  }
  return out;
}

}  // namespace lanemap::lanes
