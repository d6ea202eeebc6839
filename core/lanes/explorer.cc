#include "core/lanes/explorer.h"

#include "core/lanes/dbscan.h"

#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <unordered_map>
#include <utility>

namespace lanemap::lanes {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int floorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// The upper median of a non-empty sample: its element at size / 2 in order.
template <class T>
T upperMedian(std::vector<T> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Direct tile access to a BevGrid (one hash lookup per tile change, not per layer and cell).
class BevSampler {
 public:
  explicit BevSampler(const bev::BevGrid& g) : t_(g.options().tile_cells), res_(g.resolution()) {
    g.forEachTile([&](const bev::BevGrid::Cell& origin, const uint16_t* data) {
      tiles_[key(floorDiv(origin.x(), t_), floorDiv(origin.y(), t_))] = data;
    });
  }
  // Counts of every layer at an ENU point; nullptr-free: zeros where nothing was written.
  const uint16_t* at(const Eigen::Vector2d& p, size_t* idx) {
    const int cx = static_cast<int>(std::floor(p.x() / res_)), cy = static_cast<int>(std::floor(p.y() / res_));
    const int tx = floorDiv(cx, t_), ty = floorDiv(cy, t_);
    const int64_t k = key(tx, ty);
    if (k != last_key_) {
      last_key_ = k;
      auto it = tiles_.find(k);
      last_ = it == tiles_.end() ? nullptr : it->second;
    }
    *idx = static_cast<size_t>(cy - ty * t_) * t_ + (cx - tx * t_);
    return last_;
  }
  size_t layerStride() const { return static_cast<size_t>(t_) * t_; }

 private:
  static int64_t key(int tx, int ty) { return (static_cast<int64_t>(tx) << 32) ^ static_cast<uint32_t>(ty); }
  int t_;
  double res_;
  std::unordered_map<int64_t, const uint16_t*> tiles_;
  int64_t last_key_ = INT64_MIN;
  const uint16_t* last_ = nullptr;
};

// The road's evidence in its Frenet frame: rows along s, columns along d.
struct Raster {
  double sa = 0, res = 0.1, d0 = 0;  // row i at s = sa + (i + 0.5) res; column j at d = d0 + (j + 0.5) res
  int ns = 0, nd = 0;
  int live_i0 = 0, live_i1 = -1;  // rows of the explored stretch [s_begin, s_end]
  std::vector<uint8_t> code;
  std::vector<int32_t> dead_sat, good_sat;  // summed-area tables, (ns + 1) x (nd + 1)

  uint8_t at(int i, int j) const { return code[static_cast<size_t>(i) * nd + j]; }
  int row(double s) const { return static_cast<int>(std::floor((s - sa) / res)); }
  int col(double d) const { return static_cast<int>(std::floor((d - d0) / res)); }
  double sOf(int i) const { return sa + (i + 0.5) * res; }
  double dOf(int j) const { return d0 + (j + 0.5) * res; }

  static int32_t box(const std::vector<int32_t>& sat, int nd1, int i0, int i1, int j0, int j1) {
    // inclusive cell ranges, already clamped
    return sat[static_cast<size_t>(i1 + 1) * nd1 + j1 + 1] - sat[static_cast<size_t>(i0) * nd1 + j1 + 1] -
           sat[static_cast<size_t>(i1 + 1) * nd1 + j0] + sat[static_cast<size_t>(i0) * nd1 + j0];
  }
  // Deadly cells in [s0, s1] x [d0, d1]; a box leaving the corridor sideways counts as deadly,
  // rows beyond the explored stretch (live_i0..live_i1: the ROIs of I_i and I_j, where this road's
  // lanes are not) as free.
  int deadly(double s0, double s1, double dlo, double dhi) const {
    int j0 = col(dlo), j1 = col(dhi);
    if (j0 < 0 || j1 >= nd) return 1;
    int i0 = std::max(live_i0, row(s0)), i1 = std::min(live_i1, row(s1));
    if (i1 < i0) return 0;
    return box(dead_sat, nd + 1, i0, i1, j0, j1);
  }
  // Fraction of cells observed drivable in the box (0 outside).
  double goodFraction(double s0, double s1, double dlo, double dhi) const {
    const int j0 = std::max(0, col(dlo)), j1 = std::min(nd - 1, col(dhi));
    const int i0 = std::max(0, row(s0)), i1 = std::min(ns - 1, row(s1));
    if (i1 < i0 || j1 < j0) return 0.0;
    return static_cast<double>(box(good_sat, nd + 1, i0, i1, j0, j1)) / ((i1 - i0 + 1) * (j1 - j0 + 1));
  }
};

// Lanes between painted lines. The segmentation labels the ego lane and two lanes either side, and
// only in the ego lane's cross-section: a lane beyond them (the fourth and fifth lanes of an
// avenue, seen from the first), and the asphalt of a road seen from the junction before it (on a
// short road between close junctions, or after a turn, most of what the camera saw of it), is
// observed ground of no lane class, i.e. blocked, and would end the exploration there. The lines
// are labelled whatever lane the car is in. Per bin of divider_bin_m along s: the painted lines
// of the bin (columns with dashes in at least 10 % of its rows, or a solid line, a curb or the
// divider of a two-way road (beyond it: outside, painted or not) in 30 %);
// between two neighbouring lines lane_width_min_m to lane_width_max_m apart, the strip is a lane
// (its blocked cells become drivable) when one of the lines is dashed (a dashed line only ever
// separates two lanes of one direction) or the strip is drivable in 20 % of its cells somewhere
// in the bin (a lane the segmentation named, between a curb and a solid line), or the strip holds
// the one-way road's own line, or it is the strip beside a two-way road's divider (the lane next to
// the centre of a street is a traffic lane, never parking). A parking strip or a cycle track
// between a solid line and a curb is never labelled a lane. A solid line or curb at a slant to the
// road's frame (the OSM line of a ring or a bend is not parallel to the kerbs) spreads over
// several columns, none of which holds it in 30 % of the rows: a row's edge cell counts for every
// column within line_tolerance_m of it, and the widths are measured between the lines as found.
void markUnnamedLanes(Raster& r, const ExplorerOptions& o, bool two_way) {
  const int bin_rows = std::max(1, static_cast<int>(std::round(o.divider_bin_m / r.res)));
  const int min_cols = static_cast<int>(std::round(o.lane_width_min_m / r.res));
  const int max_cols = static_cast<int>(std::round(o.lane_width_max_m / r.res));
  const int tol = std::max(0, static_cast<int>(std::round(o.line_tolerance_m / r.res)));
  std::vector<float> dashed(r.nd), edge(r.nd), good(r.nd), outside(r.nd);
  std::vector<int> ed_row(r.nd + 1);  // one row's edge cells, prefix sums
  for (int i0 = 0; i0 < r.ns; i0 += bin_rows) {
    const int i1 = std::min(r.ns, i0 + bin_rows);
    const float n = static_cast<float>(i1 - i0);
    std::fill(dashed.begin(), dashed.end(), 0.0f);
    std::fill(edge.begin(), edge.end(), 0.0f);
    std::fill(good.begin(), good.end(), 0.0f);
    std::fill(outside.begin(), outside.end(), 0.0f);
    for (int i = i0; i < i1; ++i) {
      for (int j = 0; j < r.nd; ++j) {
        const uint8_t c = r.at(i, j);
        dashed[j] += c == kDashed;
        good[j] += c == kDrivable;
        outside[j] += c == kOutside;
        ed_row[j + 1] = ed_row[j] + (c == kSolid || c == kCurb || c == kOutside);  // the divider of a two-way road too
      }
      for (int j = 0; j < r.nd; ++j) {
        edge[j] += ed_row[std::min(r.nd, j + tol + 1)] - ed_row[std::max(0, j - tol)] > 0;
      }
    }
    for (int j = 0; j < r.nd; ++j) {
      dashed[j] /= n;
      edge[j] /= n;
      good[j] /= n;
      outside[j] /= n;
    }
    // Painted lines of the bin, left to right in d: runs of marked columns; `divider`: the run is
    // the edge of our direction's carriageway at a two-way road's divider (outside beyond it).
    struct Paint { int j0, j1; bool dashed, divider; };
    std::vector<Paint> lines;
    for (int j = 0; j < r.nd; ++j) {
      const bool d = dashed[j] >= 0.1f, e = edge[j] >= 0.3f;
      if (!d && !e) continue;
      if (!lines.empty() && lines.back().j1 >= j - 1) {
        lines.back().j1 = j;
        lines.back().dashed = lines.back().dashed || d;
      } else {
        lines.push_back({j, j, d, false});
      }
    }
    if (two_way && !lines.empty()) {
      // Beyond the divider everything is outside up to the corridor's edge: on the left of our
      // lanes in right-hand traffic (the last run), on the right in left-hand traffic (the first).
      Paint& ln = o.right_hand_traffic ? lines.back() : lines.front();
      const int edge_col = o.right_hand_traffic ? r.nd - 1 : 0;
      ln.divider = (o.right_hand_traffic ? ln.j1 : ln.j0) == edge_col && outside[edge_col] >= 0.9f;
    }
    for (size_t k = 0; k + 1 < lines.size(); ++k) {
      const Paint& a = lines[k];
      const Paint& b = lines[k + 1];
      // Between the lines as found: a run widened by the slant tolerance is that much narrower.
      const int gap = b.j0 - a.j1 + 2 * tol;
      if (gap < min_cols || gap > max_cols) continue;
      float good_sum = 0.0f;
      for (int j = a.j1 + 1; j < b.j0; ++j) good_sum += good[j];
      // The one-way road's own line runs between them: a single lane (a slip road, a link between
      // islands), whatever the segmentation named.
      const bool on_road = !two_way && a.j1 < r.col(0.0) && b.j0 > r.col(0.0);
      // Beside a two-way road's divider, on our side: the street's lane our way.
      const bool beside_divider = two_way && (o.right_hand_traffic ? b.divider : a.divider);
      if (!a.dashed && !b.dashed && !on_road && !beside_divider && good_sum < 0.2f * (b.j0 - a.j1 - 1)) continue;
      const int ja = std::max(a.j0, a.j1 - tol) + 1, jb = std::min(b.j1, b.j0 + tol);
      for (int i = i0; i < i1; ++i) {
        for (int j = ja; j < jb; ++j) {
          uint8_t& c = r.code[static_cast<size_t>(i) * r.nd + j];
          if (c == kBlocked) c = kDrivable;
        }
      }
    }
  }
}

// A lane beyond the outermost dashed line. A dashed line only ever separates two lanes of one
// direction, yet the carriageway walk can end our carriageway right at one: the lanes of a road
// seen only from the junction before it are background (the lane classes are relative to the
// ego lane, and the car was not in this road's cross-section yet), i.e. blocked, and so is a lane
// beyond the segmentation's +-2 classes; with no line seen on the far side of such a lane,
// markUnnamedLanes has no strip between two lines, and the walk puts it outside. Per bin of
// divider_bin_m along s: a dashed line (dashes in 10 % of the bin's rows) with a lane on its near
// side (the next painted line lane_width_min_m to lane_width_max_m away) and, within
// carriageway_wall_m beyond it, ground the walk put outside that was seen blocked (in half the
// bin's rows), and nothing painted within two lane widths beyond it (a line or kerb there bounds
// either a strip between two lines, markUnnamedLanes' to decide, or a hard shoulder wider than a
// lane), has a lane as wide as the near one beyond it: that strip's blocked cells become
// drivable and its other cells what they were before the walk, up to a curb or a solid line.
// Beyond the strip all stays outside, so the lane inferred is bounded and its particles cannot
// wander. `before_walk`: the raster's codes before the carriageway walk (a two-way road's divider
// is already outside there, so no lane is put beyond it).
void markBlockedLanesBeyondDashedEdges(Raster& r, const std::vector<uint8_t>& before_walk, const ExplorerOptions& o) {
  const int bin_rows = std::max(1, static_cast<int>(std::round(o.divider_bin_m / r.res)));
  const int min_cols = static_cast<int>(std::round(o.lane_width_min_m / r.res));
  const int max_cols = static_cast<int>(std::round(o.lane_width_max_m / r.res));
  const int tol = std::max(0, static_cast<int>(std::round(o.line_tolerance_m / r.res)));
  const int reach = std::max(tol, static_cast<int>(std::round(o.carriageway_wall_m / r.res)));
  auto walled_off = [&](int i, int j) {
    const size_t k = static_cast<size_t>(i) * r.nd + j;
    return r.code[k] == kOutside && before_walk[k] == kBlocked;
  };
  std::vector<float> dashed(r.nd), edge(r.nd), beyond(r.nd), line_before(r.nd);
  for (int i0 = 0; i0 < r.ns; i0 += bin_rows) {
    const int i1 = std::min(r.ns, i0 + bin_rows);
    const float n = static_cast<float>(i1 - i0);
    std::fill(dashed.begin(), dashed.end(), 0.0f);
    std::fill(edge.begin(), edge.end(), 0.0f);
    std::fill(beyond.begin(), beyond.end(), 0.0f);
    std::fill(line_before.begin(), line_before.end(), 0.0f);
    for (int i = i0; i < i1; ++i) {
      for (int j = 0; j < r.nd; ++j) {
        const uint8_t c = r.at(i, j);
        dashed[j] += c == kDashed;
        edge[j] += c == kSolid || c == kCurb;
        beyond[j] += walled_off(i, j);
        const uint8_t b = before_walk[static_cast<size_t>(i) * r.nd + j];
        line_before[j] += b == kSolid || b == kCurb ? 1.0f : b == kDashed ? 3.0f : 0.0f;  // (dashes: 10 % is a line)
      }
    }
    // Dashed runs of the bin (columns with dashes in 10 % of its rows, neighbours joined).
    struct Run { int j0, j1; };
    std::vector<Run> runs;
    for (int j = 0; j < r.nd; ++j) {
      if (dashed[j] < 0.1f * n) continue;
      if (!runs.empty() && runs.back().j1 >= j - 1) runs.back().j1 = j;
      else runs.push_back({j, j});
    }
    auto is_line = [&](int j) { return dashed[j] >= 0.1f * n || edge[j] >= 0.3f * n; };
    for (const Run& run : runs) {
      for (int dir : {-1, 1}) {
        const int first = dir > 0 ? run.j1 + 1 : run.j0 - 1;  // the first column beyond the line
        if (first < 0 || first >= r.nd) continue;
        // Beyond: walled off (seen blocked, put outside by the walk) in half the rows, within
        // carriageway_wall_m of the line.
        bool walled = false;
        for (int m = 0; m <= reach && !walled; ++m) {
          const int j = first + dir * m;
          walled = j >= 0 && j < r.nd && beyond[j] >= 0.5f * n;
        }
        if (!walled) continue;
        // Nothing painted beyond within two lanes: a line or kerb there bounds a strip that is
        // either a lane between two lines (markUnnamedLanes' to decide) or wider than a lane (a
        // hard shoulder), not a lane as wide as the near one.
        // (From past the columns of the dashed line itself, which the walk may have put outside.)
        int m0 = 0;
        while (m0 <= reach && first + dir * m0 >= 0 && first + dir * m0 < r.nd && line_before[first + dir * m0] >= 0.3f * n) ++m0;
        bool far_line = false;
        for (int m = m0; m <= m0 + 2 * max_cols && !far_line; ++m) {
          const int j = first + dir * m;
          far_line = j >= 0 && j < r.nd && line_before[j] >= 0.3f * n;
        }
        if (far_line) continue;
        // Near side: a lane, from this line to the next painted line.
        const int near0 = dir > 0 ? run.j0 - 1 : run.j1 + 1;
        int width = -1;
        for (int j = near0; j >= 0 && j < r.nd; j -= dir) {
          if (std::abs(j - near0) > max_cols) break;
          if (is_line(j)) {
            width = std::abs(j - near0) + 1;
            break;
          }
        }
        if (width < min_cols || width > max_cols) continue;
        for (int i = i0; i < i1; ++i) {
          for (int j = first, k = 0; j >= 0 && j < r.nd && k < width; j += dir, ++k) {
            const size_t idx = static_cast<size_t>(i) * r.nd + j;
            const uint8_t was = before_walk[idx];
            if (was == kCurb || was == kSolid) break;
            if (r.code[idx] == kBlocked) r.code[idx] = kDrivable;
            if (r.code[idx] != kOutside) continue;
            if (was == kBlocked) r.code[idx] = kDrivable;
            else if (was == kUnobserved || was == kDrivable || was == kDashed || was == kSeparation) r.code[idx] = was;
          }
        }
      }
    }
  }
}

Raster buildRaster(const bev::BevGrid& grid, const FrenetFrame& frame, const RoadGeometry& road, const ExplorerOptions& o) {
  Raster r;
  r.res = grid.resolution();
  r.sa = std::max(0.0, road.s_begin - 3.0);
  const double sb = std::min(frame.length(), road.s_end + 3.0);
  r.ns = std::max(1, static_cast<int>(std::ceil((sb - r.sa) / r.res)));
  r.d0 = -o.corridor_half_width_m;
  r.nd = static_cast<int>(std::ceil(2 * o.corridor_half_width_m / r.res));
  r.code.assign(static_cast<size_t>(r.ns) * r.nd, kUnobserved);
  r.live_i0 = std::clamp(r.row(road.s_begin), 0, r.ns - 1);
  r.live_i1 = std::clamp(r.row(road.s_end), 0, r.ns - 1);
  BevSampler sampler(grid);
  const size_t L = sampler.layerStride();
  auto layer = [&](const uint16_t* t, size_t idx, bev::Layer l) { return t[static_cast<size_t>(l) * L + idx]; };
  for (int i = 0; i < r.ns; ++i) {
    const double s = r.sOf(i);
    const Eigen::Vector2d p = frame.point(s), n = frame.normal(s);
    for (int j = 0; j < r.nd; ++j) {
      size_t idx;
      const uint16_t* t = sampler.at(p + r.dOf(j) * n, &idx);
      if (!t) continue;
      const double obs = layer(t, idx, bev::Layer::kObserved);
      if (obs < o.min_observations) continue;
      // A line: seen so in marking_fraction of the cell's observations, and at least
      // kill_min_count times.
      auto line = [&](bev::Layer l, double fraction) {
        const double n = layer(t, idx, l);
        return n >= o.kill_min_count && n / obs >= fraction;
      };
      const double passable = layer(t, idx, bev::Layer::kDrivable) + layer(t, idx, bev::Layer::kCrosswalk) +
                              layer(t, idx, bev::Layer::kStopLine);
      uint8_t c;
      if (line(bev::Layer::kCurb, o.marking_fraction)) c = kCurb;
      else if (line(bev::Layer::kSolidLine, o.marking_fraction)) c = kSolid;
      else if (line(bev::Layer::kDashedLine, o.marking_fraction)) c = kDashed;
      else if (line(bev::Layer::kLaneSeparation, o.separation_fraction)) c = kSeparation;
      else if (passable / obs >= o.drivable_fraction) c = kDrivable;
      // Seen drivable often enough, whatever else it was labelled: the lane classes are relative to
      // the ego lane, and frames taken inside a junction (no ego lane) label the roads around it
      // background; on a short road after a turn most views are such frames.
      else if (o.drivable_min_count > 0 && layer(t, idx, bev::Layer::kDrivable) >= o.drivable_min_count) c = kDrivable;
      // Blocked on at least kill_min_count observations of something else; fewer say nothing.
      else if (obs - passable >= o.kill_min_count) c = kBlocked;
      else continue;
      r.code[static_cast<size_t>(i) * r.nd + j] = c;
    }
  }
  // Direction divider of a two-way road: per divider_bin_m of s, the solid line nearest d = 0
  // within divider_search_m; bins without one are interpolated (up to divider_reach_m from one), a road without any uses d = 0.
  if (road.two_way) {
    const int bin_rows = std::max(1, static_cast<int>(std::round(o.divider_bin_m / r.res)));
    const int nb = (r.ns + bin_rows - 1) / bin_rows;
    std::vector<double> div(nb, NAN);
    const int jlo = std::max(0, r.col(-o.divider_search_m)), jhi = std::min(r.nd - 1, r.col(o.divider_search_m));
    for (int b = 0; b < nb; ++b) {
      const int i0 = b * bin_rows, i1 = std::min(r.ns, i0 + bin_rows);
      double best = INFINITY;
      for (int j = jlo; j <= jhi; ++j) {
        int solid = 0;
        for (int i = i0; i < i1; ++i) solid += r.at(i, j) == kSolid;
        if (solid >= 0.3 * (i1 - i0) && std::abs(r.dOf(j)) < std::abs(best)) best = r.dOf(j);
      }
      if (std::isfinite(best)) {
        // Centre of the solid run around `best` (a double line is two runs 0.2 m apart: both).
        div[b] = best;
      }
    }
    std::vector<int> known;
    for (int b = 0; b < nb; ++b) if (std::isfinite(div[b])) known.push_back(b);
    // A bin farther than divider_reach_m from every bin with a divider seen uses d = 0: a solid
    // line painted only near a junction (a centre line turning solid before it, a far edge line)
    // says little about the middle of a long road.
    const int reach = o.divider_reach_m > 0 ? static_cast<int>(std::round(o.divider_reach_m / o.divider_bin_m)) : nb;
    for (int b = 0; b < nb; ++b) {
      if (std::isfinite(div[b])) continue;
      if (known.empty()) { div[b] = 0.0; continue; }
      auto it = std::lower_bound(known.begin(), known.end(), b);
      const int before = it == known.begin() ? -1 : *(it - 1), after = it == known.end() ? -1 : *it;
      const bool near_before = before >= 0 && b - before <= reach, near_after = after >= 0 && after - b <= reach;
      if (near_before && near_after) div[b] = div[before] + (div[after] - div[before]) * (b - before) / double(after - before);
      else if (near_before) div[b] = div[before];
      else if (near_after) div[b] = div[after];
      else div[b] = 0.0;
    }
    for (int i = 0; i < r.ns; ++i) {
      const double dv = div[i / bin_rows];
      for (int j = 0; j < r.nd; ++j) {
        const double d = r.dOf(j);
        const bool out = o.right_hand_traffic ? d > dv + 0.15 : d < dv - 0.15;
        if (out) r.code[static_cast<size_t>(i) * r.nd + j] = kOutside;
      }
    }
  }
  if (o.unnamed_lanes) markUnnamedLanes(r, o, road.two_way);
  // Our carriageway: per bin along s, walk out from the road's centre line (or the nearest drivable
  // column to it) to the first wall (blocked or curb in most rows of the bin, at least
  // carriageway_wall_m wide): a median, a sidewalk, a parking strip; or to the first kerb seen
  // along kerb_wall_fraction of the bin's rows (within line_tolerance_m of one column: a kerb at
  // a slant to the frame): a kerb with ground seen drivable beyond it (a side road's mouth, a
  // parallel roadway, a forecourt) bounds this road as well. Not one within half a lane
  // (lane_width_min_m / 2) of where the walk starts: the road's line runs along it (the gore of
  // an exit ramp the line follows), so which side is this road's cannot be told. Beyond the wall
  // or kerb lie other roads (the other carriageway of a dual road, a parallel street) that are
  // not this road's lanes. A parked car fills few rows of a bin and is no wall.
  const std::vector<uint8_t> before_walk = o.blocked_lane_beyond_dashed_edge ? r.code : std::vector<uint8_t>();
  {
    const int bin_rows = std::max(1, static_cast<int>(std::round(o.divider_bin_m / r.res)));
    const int wall_cols = std::max(1, static_cast<int>(std::round(o.carriageway_wall_m / r.res)));
    const int tol = static_cast<int>(std::round(o.line_tolerance_m / r.res));
    const int kerb_min_cols = static_cast<int>(std::round(0.5 * o.lane_width_min_m / r.res));
    std::vector<uint8_t> kerb_near(r.nd);
    for (int i0 = 0; i0 < r.ns; i0 += bin_rows) {
      const int i1 = std::min(r.ns, i0 + bin_rows);
      std::vector<float> wall(r.nd), good(r.nd), kerb(r.nd);
      for (int i = i0; i < i1; ++i) {
        std::fill(kerb_near.begin(), kerb_near.end(), 0);
        for (int j = 0; j < r.nd; ++j) {
          if (r.at(i, j) != kCurb) continue;
          for (int jj = std::max(0, j - tol); jj <= std::min(r.nd - 1, j + tol); ++jj) kerb_near[jj] = 1;
        }
        for (int j = 0; j < r.nd; ++j) kerb[j] += kerb_near[j];
      }
      for (int j = 0; j < r.nd; ++j) {
        int w = 0, g = 0;
        for (int i = i0; i < i1; ++i) {
          const uint8_t c = r.at(i, j);
          w += c == kBlocked || c == kCurb;
          g += c == kDrivable;
        }
        wall[j] = static_cast<float>(w) / (i1 - i0);
        good[j] = static_cast<float>(g) / (i1 - i0);
        kerb[j] /= (i1 - i0);
      }
      int start = -1;
      for (int k = 0; k < r.nd && start < 0; ++k) {
        for (int j : {r.col(0.0) - k, r.col(0.0) + k}) {
          if (j >= 0 && j < r.nd && good[j] > 0.3f) {
            start = j;
            break;
          }
        }
      }
      if (start < 0) continue;
      for (int dir : {1, -1}) {
        int run = 0;
        for (int j = start; j >= 0 && j < r.nd; j += dir) {
          run = wall[j] >= 0.8f ? run + 1 : 0;
          const bool kerb_line = o.kerb_wall_fraction > 0 && std::abs(j - start) >= kerb_min_cols && kerb[j] >= o.kerb_wall_fraction;
          if (run < wall_cols && !kerb_line) continue;
          // (a kerb: from about where it lies, line_tolerance_m past the first column near it)
          const int first_out = kerb_line && run < wall_cols ? std::clamp(j + dir * tol, 0, r.nd - 1) : j - dir * (wall_cols - 1);
          for (int i = i0; i < i1; ++i) {
            for (int jj = first_out; jj >= 0 && jj < r.nd; jj += dir) {
              uint8_t& c = r.code[static_cast<size_t>(i) * r.nd + jj];
              if (c != kCurb) c = kOutside;  // a curb stays a curb for the boundary type
            }
          }
          break;
        }
      }
    }
  }
  if (o.blocked_lane_beyond_dashed_edge) markBlockedLanesBeyondDashedEdges(r, before_walk, o);
  // Again, now that our carriageway's outer edges are known too (a lane beside a wall the curb of
  // which was not seen).
  if (o.unnamed_lanes) markUnnamedLanes(r, o, road.two_way);
  const int nd1 = r.nd + 1;
  r.dead_sat.assign(static_cast<size_t>(r.ns + 1) * nd1, 0);
  r.good_sat.assign(static_cast<size_t>(r.ns + 1) * nd1, 0);
  for (int i = 0; i < r.ns; ++i) {
    int32_t rd = 0, rg = 0;
    for (int j = 0; j < r.nd; ++j) {
      const uint8_t c = r.at(i, j);
      rd += c >= kBlocked;
      rg += c == kDrivable;
      r.dead_sat[static_cast<size_t>(i + 1) * nd1 + j + 1] = r.dead_sat[static_cast<size_t>(i) * nd1 + j + 1] + rd;
      r.good_sat[static_cast<size_t>(i + 1) * nd1 + j + 1] = r.good_sat[static_cast<size_t>(i) * nd1 + j + 1] + rg;
    }
  }
  return r;
}

// Footprint collision: the rectangle is cut into slices along its length, each tested with the
// axis-aligned box around it (exact for a heading along the road, ~0.1 m generous at 0.3 rad).
struct Footprint {
  double L, W;
  int slices;
  bool collides(const Raster& r, double s, double d, double phi) const {
    const double c = std::cos(phi), sn = std::sin(phi), ac = std::abs(c), as = std::abs(sn);
    const double hl = L / slices / 2;
    const double hs = hl * ac + W / 2 * as, hd = hl * as + W / 2 * ac;
    for (int k = 0; k < slices; ++k) {
      const double u = -L / 2 + (2 * k + 1) * hl;
      const double cs = s + u * c, cd = d + u * sn;
      if (r.deadly(cs - hs, cs + hs, cd - hd, cd + hd) > 0) return true;
    }
    return false;
  }
};

struct Cluster {
  double dmin, dmax, dmean, smean;
  std::vector<int> members;  // indices into the step's survivor list
};

struct Track {
  int id = 0;
  bool active = true;
  double d = 0.0;             // last offset
  double first_s = 0.0, last_seen_s = 0.0, last_alive_s = 0.0;
  bool initial = false;       // started with the start strip
  int parent = -1, merge_into = -1;
  std::vector<double> sum, cnt;  // per s-bin
  bool joined = false;           // its samples went to an earlier piece of its lane (joinLanePieces)
};

}  // namespace

const char* toString(RasterClass c) {
  switch (c) {
    case kUnobserved: return "unobserved";
    case kDrivable: return "drivable";
    case kBlocked: return "blocked";
    case kSeparation: return "separation";
    case kDashed: return "dashed";
    case kSolid: return "solid";
    case kCurb: return "curb";
    case kOutside: return "outside";
  }
  return "?";
}

RoadGeometry RoadGeometry::fromSkeleton(const skeleton::AtomicRoad& road) {
  RoadGeometry g;
  g.road_id = road.id;
  g.from_node = road.from;
  g.to_node = road.to;
  g.polyline = road.polyline;
  g.s_begin = road.s_begin;
  g.s_end = road.s_end;
  g.two_way = road.reverse_id >= 0;
  return g;
}

RoadGeometry explorationStretch(const RoadGeometry& road, double length, const ExplorerOptions& o) {
  RoadGeometry r = road;
  r.s_end = std::min(road.s_end, length);
  r.s_begin = std::clamp(road.s_begin, 0.0, r.s_end);
  if (r.s_end - r.s_begin < o.short_road_min_m) {
    // A link between close junctions: the ROIs leave (almost) nothing of it. Its lanes still exist
    // (the car drove one), so explore the middle short_road_min_m of the polyline, into the ROIs.
    const double want = std::min(o.short_road_min_m, length);
    const double mid = 0.5 * (r.s_begin + r.s_end);
    r.s_begin = std::clamp(mid - 0.5 * want, 0.0, length - want);
    r.s_end = r.s_begin + want;
  }
  return r;
}

namespace {

// A link between close junctions (its stretch between the two ROIs under short_road_min_m): the ROIs
// say nothing of where its lanes are, its painted lines do. Lane lines (dashed or solid) that run
// along the road, a column of the straightened raster holding one for short_road_line_run_m or more
// (gaps under 0.3 m bridged: a line seen with holes; a line across the road, another road's, is a
// few rows long), and that reach into the stretch explorationStretch chose: the stretch becomes
// their extent along s, at most short_road_min_m around its middle. nullopt (that stretch stays)
// on a longer road, with the rule off, or where such lines cover under 2 m.
std::optional<RoadGeometry> shortLinkStretch(const bev::BevGrid& grid, const FrenetFrame& frame, const RoadGeometry& road_in,
                                             const RoadGeometry& stretch, const ExplorerOptions& o) {
  const double length = frame.length();
  const double own_end = std::min(road_in.s_end, length);
  if (o.short_road_line_run_m <= 0.0 || own_end - std::clamp(road_in.s_begin, 0.0, own_end) >= o.short_road_min_m) {
    return std::nullopt;
  }
  RoadGeometry whole = stretch;
  whole.s_begin = 0.0;
  whole.s_end = length;
  const Raster r = buildRaster(grid, frame, whole, o);
  const int min_rows = static_cast<int>(std::ceil(o.short_road_line_run_m / r.res - 1e-9));
  const int max_gap = static_cast<int>(std::round(0.3 / r.res));
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int j = 0; j < r.nd; ++j) {
    int first = -1, last = -1;
    const auto close = [&] {
      if (first < 0 || last - first + 1 < min_rows) return;
      const double a = r.sOf(first) - 0.5 * r.res, b = r.sOf(last) + 0.5 * r.res;
      if (b < stretch.s_begin || a > stretch.s_end) return;
      lo = std::min(lo, a);
      hi = std::max(hi, b);
    };
    for (int i = 0; i < r.ns; ++i) {
      const uint8_t c = r.at(i, j);
      if (c != kDashed && c != kSolid) continue;
      if (first >= 0 && i - last - 1 > max_gap) {
        close();
        first = -1;
      }
      if (first < 0) first = i;
      last = i;
    }
    close();
  }
  lo = std::max(lo, 0.0);
  hi = std::min(hi, length);
  if (!(hi - lo >= 2.0)) return std::nullopt;
  if (hi - lo > o.short_road_min_m) {
    const double mid = 0.5 * (lo + hi);
    lo = mid - 0.5 * o.short_road_min_m;
    hi = mid + 0.5 * o.short_road_min_m;
  }
  RoadGeometry placed = stretch;
  placed.s_begin = lo;
  placed.s_end = hi;
  return placed;
}

}  // namespace

int ExplorationResult::laneCountAt(double s) const {
  int n = 0;
  for (const auto& l : lanes) n += s >= l.s_begin && s <= l.s_end;
  return n;
}

namespace {

// Algorithm 1's particle filter over one road's straightened raster (METHOD.md section 4, step 2
// and 3): N footprints, the start strip, then per step predict (Eq. 5), kill, cluster and track,
// resample and births, until the particles reach I_j. The steps draw from one random stream in a
// fixed order, so a run is deterministic for options.seed.
class ParticleFilter {
 public:
  ParticleFilter(const Raster& raster, const ExplorerOptions& o, double s_start, double s_stop, ExplorationStats* stats)
      : R_(raster), o_(o), N_(o.num_particles),
        fp_{o.footprint_length_m, o.footprint_width_m, std::max(1, static_cast<int>(std::ceil(o.footprint_length_m / 0.5)))},
        rng_(o.seed), S_(Eigen::ArrayXd::Constant(N_, s_start)), D_(Eigen::ArrayXd::Zero(N_)),
        PHI_(Eigen::ArrayXd::Zero(N_)), V_(N_), W_(N_), alive_(N_, 0),
        nbins_(static_cast<int>(std::ceil((raster.sa + raster.ns * raster.res) / o.bin_m)) + 1),
        s_start_(s_start), s_stop_(s_stop), stats_(*stats) {}

  // Start strip: across the road's observed drivable ground at the first s within 30 m that has
  // any (a road first seen some way in, after a turn: its lanes start there and are carried back
  // to the road's start by fitLanes, as lanes that began with the strip). A road first seen
  // farther in was entered there (a drive that began on it) or not seen before: its lanes start
  // where it was seen (seenFromStart() false: nothing to carry them back on). When none of it was
  // seen drivable, across the free (unobserved) part at the start. Returns the s it starts at.
  double seedStartStrip() {
    double s = s_start_;
    std::vector<std::pair<double, double>> iv;
    for (; s < s_stop_; s += 1.0) {
      iv = freeIntervals(s, true);
      if (!iv.empty()) break;
    }
    seen_from_start_ = iv.empty() || s < s_start_ + 30.0;
    if (iv.empty()) {
      s = s_start_;
      iv = freeIntervals(s, false);
    }
    double total = 0.0;
    for (auto& [a, b] : iv) total += b - a + R_.res;
    for (int n = 0; n < N_ && total > 0; ++n) {
      double u = (n + 0.5) / N_ * total;
      for (auto& [a, b] : iv) {
        const double w = b - a + R_.res;
        if (u <= w) {
          D_[n] = a - R_.res / 2 + u;
          break;
        }
        u -= w;
      }
      S_[n] = s;
      alive_[n] = 1;
    }
    if (total > 0) ++stats_.births;
    s_start_ = first_station_ = station_ = s;
    next_birth_ = s + o_.birth_every_m;
    return s;
  }

  bool seenFromStart() const { return seen_from_start_; }

  // Runs the steps until the particles reach I_j (or a bound on the steps). history: the
  // surviving particles (s, d) of every history_stride-th step.
  void run(std::vector<Eigen::Vector2d>* history, int history_stride) {
    const int max_steps = static_cast<int>(4.0 * (s_stop_ - s_start_) / (o_.v_min * o_.dt_s)) + 100;
    for (int step = 0; step < max_steps; ++step) {
      predict();
      kill();
      ++stats_.steps;
      advanceStation();
      if (history && history_stride > 0 && step % history_stride == 0) {
        for (int n : surv_) history->emplace_back(S_[n], D_[n]);
      }
      clusterAndTrack();
      resample();
      births();
      if (finished()) break;
    }
    stats_.tracks = static_cast<int>(tracks_.size());
  }

  const std::vector<Track>& tracks() const { return tracks_; }
  int bins() const { return nbins_; }
  double startS() const { return s_start_; }

 private:
  // Free footprint-centre intervals across the road at s (heading along the road); with
  // `need_good`, only intervals on observed drivable ground.
  std::vector<std::pair<double, double>> freeIntervals(double s, bool need_good) const {
    std::vector<std::pair<double, double>> out;
    const double hs = fp_.L / 2, hd = fp_.W / 2;
    double run0 = NAN, prev = NAN;
    for (int j = 0; j < R_.nd; ++j) {
      const double d = R_.dOf(j);
      bool ok = R_.deadly(s - hs, s + hs, d - hd, d + hd) == 0;
      if (ok && need_good) ok = R_.goodFraction(s - hs, s + hs, d - hd, d + hd) >= o_.birth_min_evidence;
      if (ok) {
        if (!std::isfinite(run0)) run0 = d;
        prev = d;
      }
      if ((!ok || j == R_.nd - 1) && std::isfinite(run0)) {
        if (prev - run0 >= o_.birth_min_free_m) out.push_back({run0, prev});
        run0 = NAN;
      }
    }
    return out;
  }

  // Predict (Eq. 5), vectorised over the particles: v ~ U(v_min, v_max), w ~ U(w_min, w_max) per
  // particle; particles that reached s_stop wait there.
  void predict() {
    for (int n = 0; n < N_; ++n) {
      V_[n] = o_.v_min + (o_.v_max - o_.v_min) * U01_(rng_);
      W_[n] = o_.w_min + (o_.w_max - o_.w_min) * U01_(rng_);
    }
    const Eigen::ArrayXd moving = (S_ < s_stop_).cast<double>();
    const Eigen::ArrayXd heading = PHI_ + W_;
    S_ += moving * V_ * heading.cos() * o_.dt_s;
    D_ += moving * V_ * heading.sin() * o_.dt_s;
    PHI_ += moving * W_ * o_.dt_s;
  }

  // Kill: a footprint touching a boundary cell (or turned too far from the road) dies; the
  // survivors are surv_.
  void kill() {
    surv_.clear();
    for (int n = 0; n < N_; ++n) {
      if (!alive_[n]) continue;
      ++stats_.particle_steps;
      const bool ok = std::abs(PHI_[n]) <= o_.max_heading_rad && !fp_.collides(R_, S_[n], D_[n], PHI_[n]);
      if (ok) surv_.push_back(n);
      else {
        alive_[n] = 0;
        ++stats_.deaths;
      }
    }
  }

  // The filter's station along s: the survivors' median (it never goes back); when everything
  // died, it moves on at the mean speed to look further for births.
  void advanceStation() {
    if (!surv_.empty()) {
      std::vector<double> ss;
      for (int n : surv_) ss.push_back(S_[n]);
      station_ = std::max(station_, upperMedian(std::move(ss)));
    } else {
      station_ += 0.5 * (o_.v_min + o_.v_max) * o_.dt_s;
    }
  }

  // Cluster and track: DBSCAN (the paper's eps) over this step's survivors gives its lanes;
  // clusters continue, split from or start lane tracks along s, and tracks with no particles for
  // lane_gap_max_m end (merging into a neighbour).
  void clusterAndTrack() {
    // DBSCAN runs on the lateral offsets only: the particles of one lane spread along s by more
    // than eps (speed noise, and those already waiting at I_j), which must not split a lane.
    pts_.clear();
    lat_.clear();
    for (int n : surv_) {
      pts_.emplace_back(S_[n], D_[n]);
      lat_.push_back(D_[n]);
    }
    int K = 0;
    const std::vector<int> label = dbscan1d(lat_, o_.dbscan_eps_m, o_.dbscan_min_points, &K);
    std::vector<Cluster> cl(K, Cluster{INFINITY, -INFINITY, 0.0, 0.0, {}});
    for (size_t i = 0; i < pts_.size(); ++i) {
      if (label[i] < 0) continue;
      Cluster& c = cl[label[i]];
      c.dmin = std::min(c.dmin, pts_[i].y());
      c.dmax = std::max(c.dmax, pts_[i].y());
      c.dmean += pts_[i].y();
      c.smean += pts_[i].x();
      c.members.push_back(static_cast<int>(i));
    }
    for (auto& c : cl) {
      c.dmean /= c.members.size();
      c.smean /= c.members.size();
    }
    // Each active track picks the nearest cluster whose extent (+ tolerance) contains its d.
    std::vector<int> primary(tracks_.size(), -1);
    std::vector<std::vector<int>> claim(K), touched(K);
    for (size_t t = 0; t < tracks_.size(); ++t) {
      if (!tracks_[t].active) continue;
      double best = INFINITY;
      for (int k = 0; k < K; ++k) {
        if (tracks_[t].d < cl[k].dmin - o_.track_tolerance_m || tracks_[t].d > cl[k].dmax + o_.track_tolerance_m) continue;
        touched[k].push_back(static_cast<int>(t));
        const double e = std::abs(cl[k].dmean - tracks_[t].d);
        if (e < best) {
          best = e;
          primary[t] = k;
        }
      }
      if (primary[t] >= 0) claim[primary[t]].push_back(static_cast<int>(t));
    }
    for (int k = 0; k < K; ++k) {
      auto& cs = claim[k];
      // Two tracks closer than same_lane_m in one cluster are one lane: the younger ends there.
      std::sort(cs.begin(), cs.end());
      for (size_t a = 0; a < cs.size(); ++a) {
        for (size_t b = a + 1; b < cs.size();) {
          if (std::abs(tracks_[cs[a]].d - tracks_[cs[b]].d) < o_.same_lane_m) {
            tracks_[cs[b]].active = false;
            tracks_[cs[b]].merge_into = cs[a];
            cs.erase(cs.begin() + b);
          } else {
            ++b;
          }
        }
      }
      if (cs.size() == 1) {
        record(tracks_[cs[0]], cl[k]);
      } else if (cs.size() >= 2) {
        for (int t : cs) tracks_[t].last_alive_s = cl[k].smean;  // distinct lanes in one wide cluster: coast
      } else {
        Track tr;
        tr.id = static_cast<int>(tracks_.size());
        tr.first_s = cl[k].smean;
        tr.initial = cl[k].smean < first_station_ + 5.0;
        tr.sum.assign(nbins_, 0.0);
        tr.cnt.assign(nbins_, 0.0);
        if (!touched[k].empty()) {
          tr.parent = touched[k].front();  // split off a lane whose cluster it was part of
        } else if (!tr.initial) {
          double best = o_.split_neighbour_m;
          for (const Track& other : tracks_) {
            if (other.active && std::abs(other.d - cl[k].dmean) < best) {
              best = std::abs(other.d - cl[k].dmean);
              tr.parent = other.id;
            }
          }
        }
        record(tr, cl[k]);
        tracks_.push_back(std::move(tr));
      }
    }
    for (auto& tr : tracks_) {
      if (tr.active && station_ - tr.last_alive_s > o_.lane_gap_max_m) {
        tr.active = false;
        double best = o_.split_neighbour_m;
        for (const Track& other : tracks_) {
          if (other.id != tr.id && other.active && std::abs(other.d - tr.d) < best) {
            best = std::abs(other.d - tr.d);
            tr.merge_into = other.id;
          }
        }
      }
    }
  }

  // A cluster's particles go into the track's per-s-bin sums (the regression's samples).
  void record(Track& tr, const Cluster& c) const {
    for (int m : c.members) {
      const int b = std::clamp(static_cast<int>(pts_[m].x() / o_.bin_m), 0, nbins_ - 1);
      tr.sum[b] += pts_[m].y();
      tr.cnt[b] += 1;
    }
    tr.d = c.dmean;
    tr.last_seen_s = tr.last_alive_s = c.smean;
  }

  // Resample (local): each dead particle becomes a copy of a survivor near it in d, so one lane's
  // particles do not take over another's.
  void resample() {
    if (surv_.empty()) return;
    byD_.clear();
    for (int n : surv_) byD_.emplace_back(D_[n], n);
    std::sort(byD_.begin(), byD_.end());
    const int ns = static_cast<int>(byD_.size());
    for (int n = 0; n < N_; ++n) {
      if (alive_[n]) continue;
      int pos = static_cast<int>(std::lower_bound(byD_.begin(), byD_.end(), std::make_pair(D_[n], -1)) - byD_.begin());
      pos = std::clamp(pos + static_cast<int>(std::floor(U01_(rng_) * 4.0)) - 2, 0, ns - 1);
      const int p = byD_[pos].second;
      S_[n] = S_[p];
      D_[n] = D_[p];
      PHI_[n] = PHI_[p];
      alive_[n] = 1;
    }
  }

  // Births: every birth_every_m, particles are seeded where a footprint fits on observed drivable
  // ground that no particle covers (a turn pocket opening, a bus bay, the lane after a parked car).
  void births() {
    if (!(station_ >= next_birth_ && station_ < s_stop_ - o_.footprint_length_m)) return;
    next_birth_ = station_ + o_.birth_every_m;
    const auto iv = freeIntervals(station_, true);
    for (const auto& [a, b] : iv) {
      bool covered = false;
      for (int n = 0; n < N_ && !covered; ++n) {
        covered = alive_[n] && D_[n] >= a - 0.3 && D_[n] <= b + 0.3 && std::abs(S_[n] - station_) < 4.0;
      }
      if (covered) continue;
      ++stats_.births;
      for (int q = 0; q < o_.birth_particles; ++q) {
        const int n = static_cast<int>(U01_(rng_) * N_) % N_;
        S_[n] = station_ + (U01_(rng_) - 0.5);
        D_[n] = a + (b - a) * (q + 0.5) / o_.birth_particles;
        PHI_[n] = 0.0;
        alive_[n] = 1;
      }
    }
  }

  // The particles have reached I_j (all that live are at s_stop), or everything died past it.
  bool finished() const {
    bool moving_left = false;
    for (int n = 0; n < N_ && !moving_left; ++n) moving_left = alive_[n] && S_[n] < s_stop_;
    if (!moving_left && station_ >= s_stop_ - 1.0) return true;
    return surv_.empty() && station_ >= s_stop_;
  }

  const Raster& R_;
  const ExplorerOptions& o_;
  const int N_;
  const Footprint fp_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> U01_{0.0, 1.0};
  Eigen::ArrayXd S_, D_, PHI_, V_, W_;
  std::vector<uint8_t> alive_;
  const int nbins_;
  double s_start_, s_stop_;
  double first_station_ = 0.0, station_ = 0.0, next_birth_ = 0.0;
  bool seen_from_start_ = true;
  ExplorationStats& stats_;
  std::vector<Track> tracks_;
  // Per-step scratch, kept to avoid reallocating.
  std::vector<int> surv_;
  std::vector<Eigen::Vector2d> pts_;
  std::vector<double> lat_;
  std::vector<std::pair<double, int>> byD_;
};

// Removes the lanes whose drop[id] is set and renumbers the others (ids are indices), their split
// and merge links with them (a link to a dropped lane is none).
void dropLanes(const std::vector<bool>& drop, std::vector<Lane>* lanes) {
  std::vector<int> new_id(lanes->size(), -1);
  std::vector<Lane> kept;
  for (auto& lane : *lanes) {
    if (drop[lane.id]) continue;
    new_id[lane.id] = static_cast<int>(kept.size());
    kept.push_back(std::move(lane));
  }
  for (auto& lane : kept) {
    lane.id = new_id[lane.id];
    if (lane.split_from >= 0) lane.split_from = new_id[lane.split_from];
    if (lane.merges_into >= 0) lane.merges_into = new_id[lane.merges_into];
  }
  *lanes = std::move(kept);
}

// A track's first and last binned samples: [s0, s1) and the mean offset over its first (last)
// three bins with samples. False when it has none.
struct TrackEnds {
  double s0, s1, d0, d1;
};
bool trackEnds(const Track& tr, double bin_m, TrackEnds* e) {
  const int n = static_cast<int>(tr.cnt.size());
  int b0 = 0, b1 = n - 1;
  while (b0 < n && tr.cnt[b0] <= 0) ++b0;
  while (b1 >= 0 && tr.cnt[b1] <= 0) --b1;
  if (b0 > b1) return false;
  auto meanOf = [&](int from, int step) {
    double s = 0, c = 0;
    for (int b = from, k = 0; b >= b0 && b <= b1 && k < 3; b += step) {
      if (tr.cnt[b] <= 0) continue;
      s += tr.sum[b];
      c += tr.cnt[b];
      ++k;
    }
    return s / c;
  };
  *e = {b0 * bin_m, (b1 + 1) * bin_m, meanOf(b0, 1), meanOf(b1, -1)};
  return true;
}

// A lane seen in pieces is one lane: the particles in a lane whose line or kerb the camera saw
// smeared (the far lane of a wide road, a worn line) die where a footprint touches a stray
// boundary cell, and births start its lane again farther on as a new track. A track that ended
// (no particles for lane_gap_max_m) and a track that starts at most join_gap_max_m after it, within
// same_lane_m of the offset it ended at, are joined when the straight line between them (every
// metre, in the raster) crosses observed drivable ground in join_min_drivable_share of its metres
// and no other track holds that offset there (within same_lane_m, in over a tenth of the metres): a
// bay out of a lane and back, then a kerb, then another bay is not one lane, nor a lane that another
// lane's particles took over. The later track's samples go to the earlier one, which takes its end
// and its merge; tracks that named it as parent or merge resolve to the earlier one (fitLanes).
// The regression then bridges the gap with a straight piece in (s, d).
int joinLanePieces(const Raster& R, const ExplorerOptions& o, std::vector<Track>* tracks) {
  if (o.join_gap_max_m <= 0) return 0;
  auto& T = *tracks;
  std::vector<TrackEnds> ends(T.size());
  std::vector<bool> has(T.size());
  for (size_t t = 0; t < T.size(); ++t) has[t] = trackEnds(T[t], o.bin_m, &ends[t]);
  auto offsetAt = [&](const Track& tr, double s, double* d) {
    const int b = static_cast<int>(std::floor(s / o.bin_m));
    if (b < 0 || b >= static_cast<int>(tr.cnt.size()) || tr.cnt[b] <= 0) return false;
    *d = tr.sum[b] / tr.cnt[b];
    return true;
  };
  auto gapIsLane = [&](size_t a, size_t b) {
    const double s0 = ends[a].s1, s1 = ends[b].s0;
    int n = 0, drivable = 0, held = 0;
    for (double s = s0 + 0.5; s < s1; s += 1.0, ++n) {
      const double d = ends[a].d1 + (ends[b].d0 - ends[a].d1) * (s - s0) / (s1 - s0);
      const int i = R.row(s), j = R.col(d);
      drivable += i >= 0 && i < R.ns && j >= 0 && j < R.nd && R.at(i, j) == kDrivable;
      for (size_t t = 0; t < T.size(); ++t) {
        double dt;
        if (t != a && t != b && !T[t].joined && offsetAt(T[t], s, &dt) && std::abs(dt - d) < o.same_lane_m) {
          ++held;
          break;
        }
      }
    }
    return drivable >= o.join_min_drivable_share * n && held <= 0.1 * n;
  };
  int joined = 0;
  for (size_t a = 0; a < T.size(); ++a) {
    while (has[a] && !T[a].joined && !T[a].active) {
      int best = -1;
      for (size_t b = 0; b < T.size(); ++b) {
        if (b == a || !has[b] || T[b].joined || T[b].initial) continue;
        const double gap = ends[b].s0 - ends[a].s1;
        if (gap < 0 || gap > o.join_gap_max_m || std::abs(ends[b].d0 - ends[a].d1) >= o.same_lane_m) continue;
        if (best < 0 || ends[b].s0 < ends[best].s0) best = static_cast<int>(b);
      }
      if (best < 0 || !gapIsLane(a, best)) break;
      Track& A = T[a];
      Track& B = T[best];
      for (size_t k = 0; k < A.cnt.size(); ++k) {
        A.sum[k] += B.sum[k];
        A.cnt[k] += B.cnt[k];
      }
      A.active = B.active;
      A.d = B.d;
      A.last_seen_s = B.last_seen_s;
      A.last_alive_s = B.last_alive_s;
      A.merge_into = B.merge_into == static_cast<int>(a) ? -1 : B.merge_into;
      ends[a].s1 = ends[best].s1;
      ends[a].d1 = ends[best].d1;
      B.joined = true;
      B.parent = B.merge_into = static_cast<int>(a);
      ++joined;
    }
  }
  return joined;
}

// Beyond its samples a fit runs on at its end segments' slopes: over the metres a track coasted
// beside another lane in one wide cluster (no samples of its own) to the junction, or back to the
// road's start from where a lane seen late was first sampled, that slope carries the lane off
// across the road (i5's exit lane: 11 m off over 24 m). Nothing was seen there: the lane is held
// at its last (first) fitted offset, parallel to the road, over [s_begin, s_end].
void holdBeyondSamples(double s_begin, double s_end, PiecewiseLinearFit* fit) {
  constexpr double kMinGap = 1.0;  // (a bin's half-width short of the end is no gap)
  if (fit->knots.empty()) return;
  if (s_end > fit->knots.back() + kMinGap) {
    fit->knots.push_back(s_end);
    fit->values.push_back(fit->values.back());
  }
  if (s_begin < fit->knots.front() - kMinGap) {
    fit->knots.insert(fit->knots.begin(), s_begin);
    fit->values.insert(fit->values.begin(), fit->values.front());
  }
}

// Fit (METHOD.md section 4, step 4): the tracks long enough become lanes, each regressed as d(s)
// (Eq. 6: piecewise linear with optimised break points, then a natural cubic spline); a lane that
// began with the start strip is carried back to the road's start when the road was seen from
// there (`seen_from_start`, ParticleFilter::seedStartStrip). Split and merge relations through
// dropped tracks go to those tracks' own relations. Beyond its samples a lane is held parallel to
// the road (holdBeyondSamples, flat_beyond_samples).
std::vector<Lane> fitLanes(const std::vector<Track>& tracks, int nbins, const RoadGeometry& road, double s_stop,
                           double min_lane_length, bool seen_from_start, const ExplorerOptions& o) {
  std::vector<Lane> lanes;
  std::vector<int> keep_index(tracks.size(), -1);
  for (const auto& tr : tracks) {
    if (tr.joined) continue;
    const double s_end = tr.active ? s_stop : tr.last_alive_s;
    const double s_beg = tr.initial && seen_from_start ? std::max(road.s_begin, 0.0) : tr.first_s;
    double support = 0.0;
    for (double c : tr.cnt) support += c > 0 ? o.bin_m : 0.0;
    if (s_end - s_beg < min_lane_length || support < 0.5 * min_lane_length) continue;
    BinnedSamples bs;
    for (int b = 0; b < nbins; ++b) {
      if (tr.cnt[b] <= 0) continue;
      bs.s.push_back((b + 0.5) * o.bin_m);
      bs.mean.push_back(tr.sum[b] / tr.cnt[b]);
      bs.weight.push_back(tr.cnt[b]);
    }
    if (bs.s.empty()) continue;
    Lane lane;
    lane.s_begin = s_beg;
    lane.s_end = s_end;
    PiecewiseLinearFit fit = fitPiecewiseLinear(bs, o.break_spacing_m, o.break_penalty_m2);
    if (o.flat_beyond_samples) holdBeyondSamples(s_beg, s_end, &fit);
    lane.centre = CentreLine(fit, s_beg, s_end);
    for (double w : bs.weight) lane.particle_samples += static_cast<int64_t>(w);
    lane.split_from = tr.parent;    // track ids for now
    lane.merges_into = tr.merge_into;
    keep_index[tr.id] = static_cast<int>(lanes.size());
    lane.id = static_cast<int>(lanes.size());
    lanes.push_back(std::move(lane));
  }
  auto resolve = [&](int t, bool up) {
    for (int guard = 0; t >= 0 && guard < 64; ++guard) {
      if (keep_index[t] >= 0) return keep_index[t];
      t = up ? tracks[t].parent : tracks[t].merge_into;
    }
    return -1;
  };
  for (auto& lane : lanes) {
    lane.split_from = resolve(lane.split_from, true);
    lane.merges_into = resolve(lane.merges_into, false);
    if (lane.split_from == lane.id) lane.split_from = -1;
    if (lane.merges_into == lane.id) lane.merges_into = -1;
  }
  // A piece beside a lane (it splits off it, merges into it, or both with the same one) holding
  // fewer particles per metre than bulge_density_fraction of that lane's is a stretch where a few
  // particles found room (noise the lines left), not a lane (a bus bay or a turn pocket holds its
  // share), unless it splits off and runs on to the junction, at least min_lane_length long and,
  // on a two-way road, on our side of its line at its end: a turn pocket, however thinly seen (one
  // seen obliquely holds 0.14 of its parent's on the benchmark's montlake, i5 and roosevelt). A
  // lane of its own, over half of whose stretch another lane holds more than
  // 1 / weak_density_fraction times its particles per metre, is a few particles that found room
  // beyond a kerb or between stray labels. Both are dropped, the others renumbered.
  auto density = [](const Lane& l) { return l.particle_samples / std::max(1.0, l.s_end - l.s_begin); };
  std::vector<bool> drop(lanes.size(), false);
  for (const auto& lane : lanes) {
    const int beside = lane.split_from >= 0 ? lane.split_from : lane.merges_into;
    const double d_end = lane.centre.d(lane.s_end);
    const bool our_side = !road.two_way || (o.right_hand_traffic ? d_end < 0.0 : d_end > 0.0);
    const bool to_junction = lane.split_from >= 0 && lane.merges_into < 0 && lane.s_end >= s_stop - 1e-6 &&
                             lane.s_end - lane.s_begin >= min_lane_length && our_side;
    drop[lane.id] = beside >= 0 && !to_junction && (lane.split_from < 0 || lane.merges_into < 0 || lane.split_from == lane.merges_into) &&
                    density(lane) < o.bulge_density_fraction * density(lanes[beside]);
    for (const auto& other : lanes) {
      const double overlap = std::min(lane.s_end, other.s_end) - std::max(lane.s_begin, other.s_begin);
      drop[lane.id] = drop[lane.id] || (other.id != lane.id && overlap >= 0.5 * (lane.s_end - lane.s_begin) &&
                                        density(lane) < o.weak_density_fraction * density(other));
    }
  }
  dropLanes(drop, &lanes);
  return lanes;
}

// A lane seen over under floating_lane_max_m beside a lane seen from lane_gap_max_m before it
// starts to lane_gap_max_m after it ends: a stretch where the camera glimpsed a lane beyond the
// ones it follows (the far lanes of a wide road, seen between passing cars), born beside a lane
// (so "split off" it) and lost beside another. A pocket runs on to the junction, a lane that ends
// began before the other, a lane added for a climb runs for hundreds of metres, and a bay (out of
// one lane and back into it, on the kerb side: no lane beside it there) is kept: a glimpse of the
// kerb-side lane can be one too, which this cannot tell. On a long road such pieces come and go,
// each off by the far lines' error. Dropped, the others renumbered.
void dropFloatingLanes(const ExplorerOptions& o, std::vector<Lane>* lanes) {
  if (o.floating_lane_max_m <= 0.0) return;
  std::vector<bool> drop(lanes->size(), false);
  for (const auto& lane : *lanes) {
    if (lane.s_end - lane.s_begin >= o.floating_lane_max_m) continue;
    // A bay: out of a lane and back into it, on the kerb side (nothing beside it there).
    if (lane.split_from >= 0 && lane.split_from == lane.merges_into) {
      const double sm = 0.5 * (lane.s_begin + lane.s_end), dm = lane.centre.d(sm);
      const bool kerb_side = std::none_of(lanes->begin(), lanes->end(), [&](const Lane& other) {
        return other.id != lane.id && other.s_begin <= sm && other.s_end >= sm &&
               (o.right_hand_traffic ? other.centre.d(sm) < dm : other.centre.d(sm) > dm);
      });
      if (kerb_side) continue;
    }
    for (const auto& other : *lanes) {
      if (other.id != lane.id && other.s_begin <= lane.s_begin - o.lane_gap_max_m && other.s_end >= lane.s_end + o.lane_gap_max_m) {
        drop[lane.id] = true;
      }
    }
  }
  dropLanes(drop, lanes);
}

// A lane whose centre line crosses observed drivable ground at under min_drivable_share of its
// length (sampled every metre) lies on nothing the camera saw as road: particles started across
// a road seen only from the junctions (no drivable cell at all) live on in unobserved ground beyond
// the kerbs. Dropped, the others renumbered.
void dropLanesOnNothing(const Raster& R, const ExplorerOptions& o, std::vector<Lane>* lanes) {
  if (o.min_drivable_share <= 0.0) return;
  std::vector<bool> drop(lanes->size(), false);
  for (const auto& lane : *lanes) {
    int n = 0, good = 0;
    for (double s = lane.s_begin; s <= lane.s_end; s += 1.0, ++n) {
      const int i = R.row(s), j = R.col(lane.centre.d(s));
      good += i >= 0 && i < R.ns && j >= 0 && j < R.nd && R.at(i, j) == kDrivable;
    }
    drop[lane.id] = n > 0 && good < o.min_drivable_share * n;
  }
  dropLanes(drop, lanes);
}

// Probe one side (dir +1 left, -1 right) from (s, d) along the normal until a marking, curb,
// blocked or outside cell: the boundary's offset (a marking's middle, shared with the neighbour
// lane; a curb's or blocked cell's near edge), and in *hit the class found (kUnobserved: nothing
// within probe_max_m, default_half_width_m away).
double probeBoundary(const Raster& R, const ExplorerOptions& o, double s, double d, int dir, uint8_t* hit) {
  const int i = std::clamp(R.row(s), 0, R.ns - 1);
  const int j0 = R.col(d);
  const int steps = static_cast<int>(o.probe_max_m / R.res);
  for (int k = 1; k <= steps; ++k) {
    const int j = j0 + dir * k;
    if (j < 0 || j >= R.nd) break;
    const uint8_t c = R.at(i, j);
    if (c < kBlocked) continue;
    *hit = c;
    if (c == kSeparation || c == kDashed || c == kSolid) {
      uint8_t strongest = c;
      int e = j;
      while (e + dir >= 0 && e + dir < R.nd) {
        const uint8_t n = R.at(i, e + dir);
        if (n != kSeparation && n != kDashed && n != kSolid) break;
        strongest = std::max(strongest, n);
        e += dir;
      }
      *hit = strongest;
      return R.dOf(j) + (R.dOf(e) - R.dOf(j)) / 2.0;
    }
    return R.dOf(j) - dir * R.res / 2.0;
  }
  *hit = kUnobserved;
  return d + dir * o.default_half_width_m;
}

// A lane boundary's probes are independent: one that slips through a gap of a dashed line or
// stops at a speck of noise makes the bound zigzag (Lanelet2's validator: curvature_too_big). A
// probe whose half-width (distance from the lane's centre line) is more than boundary_outlier_m
// off the median of its boundary_median_window neighbours takes that median. A real change of
// width (a lane opening) moves the median with it, so it is kept.
void rejectBoundaryOutliers(const FrenetFrame& frame, const Lane& lane, const ExplorerOptions& o, Boundary* b) {
  const int n = static_cast<int>(b->d.size());
  if (o.boundary_outlier_m <= 0.0 || o.boundary_median_window < 3 || n < 3) return;
  std::vector<double> width(n);
  for (int k = 0; k < n; ++k) width[k] = std::abs(b->d[k] - lane.centre.d(lane.waypoint_s[k]));
  const int half = o.boundary_median_window / 2;
  std::vector<double> window;
  for (int k = 0; k < n; ++k) {
    // The window shifted inside the lane at its ends, so every median sees a whole window.
    const int w = std::min(half, (n - 1) / 2);
    const int first = std::clamp(k - w, 0, n - 1 - 2 * w);
    window.assign(width.begin() + first, width.begin() + first + 2 * w + 1);
    std::nth_element(window.begin(), window.begin() + w, window.end());
    const double median = window[w];
    if (std::abs(width[k] - median) <= o.boundary_outlier_m) continue;
    const double s = lane.waypoint_s[k];
    const double d = lane.centre.d(s);
    b->d[k] = d + (b == &lane.left ? median : -median);
    b->points[k] = frame.toEnu(s, b->d[k]);
  }
}

// A lane's centre line lies midway between its bounds (Lanelet2 derives it so). The particles'
// mean lies midway between the lines' near edges instead: beside a double centre line (0.4 m of
// paint) and a kerb (the drivable area ends at its foot) it runs a fifth of a metre off. Where both
// probes found a boundary at at least half the way-points, the centre line moves by the median of
// (left + right) / 2 - centre over them, when that is at most recentre_max_m (more: the bounds
// are not this lane's). A lane splitting off or merging into another, or one another lane splits
// off or merges into, keeps its line (the two must meet there).
void recentreOnBounds(const FrenetFrame& frame, const ExplorerOptions& o, const std::vector<uint8_t>& both_hit,
                      bool has_branches, Lane* lane) {
  if (o.recentre_max_m <= 0.0 || has_branches || lane->split_from >= 0 || lane->merges_into >= 0) return;
  std::vector<double> e;
  for (size_t k = 0; k < lane->waypoint_s.size(); ++k) {
    if (both_hit[k]) e.push_back(0.5 * (lane->left.d[k] + lane->right.d[k]) - lane->centre.d(lane->waypoint_s[k]));
  }
  if (e.empty() || 2 * e.size() < lane->waypoint_s.size()) return;
  const double shift = upperMedian(std::move(e));
  if (!(std::abs(shift) <= o.recentre_max_m)) return;
  // The moved line stays well inside its bounds everywhere (a quarter of the lane's width from
  // each, at most half a metre), or the lane keeps its line: where a bound closes in (a taper at
  // the lane's end) a line moved across it would make the lanelet, and its connections, invalid.
  for (size_t k = 0; k < lane->waypoint_s.size(); ++k) {
    const double c = lane->centre.d(lane->waypoint_s[k]) + shift;
    const double margin = std::min(0.5, 0.25 * (lane->left.d[k] - lane->right.d[k]));
    if (!(lane->left.d[k] - c >= margin && c - lane->right.d[k] >= margin)) return;
  }
  PiecewiseLinearFit fit = lane->centre.piecewiseLinear();
  for (double& v : fit.values) v += shift;
  lane->centre = CentreLine(fit, lane->s_begin, lane->s_end);
  for (size_t k = 0; k < lane->waypoint_s.size(); ++k) {
    lane->waypoints[k] = frame.toEnu(lane->waypoint_s[k], lane->centre.d(lane->waypoint_s[k]));
  }
}

// Way-points and lane boundaries (METHOD.md section 4, step 5): way-points every
// waypoint_spacing_m along each lane's centre line, each boundary probed there on both sides
// (asymmetric, follows the drivable area) and typed by the classes its probes hit most.
void probeBoundaries(const Raster& R, const FrenetFrame& frame, const ExplorerOptions& o, std::vector<Lane>* lanes) {
  for (auto& lane : *lanes) {
    const double len = lane.s_end - lane.s_begin;
    const int n = std::max(2, static_cast<int>(std::ceil(len / o.waypoint_spacing_m)) + 1);
    int count[2][8] = {};
    std::vector<uint8_t> both_hit(n, 1);  // both probes found a boundary at way-point k
    for (int k = 0; k < n; ++k) {
      const double s = lane.s_begin + len * k / (n - 1);
      const double d = lane.centre.d(s);
      lane.waypoint_s.push_back(s);
      lane.waypoints.push_back(frame.toEnu(s, d));
      for (int side = 0; side < 2; ++side) {
        uint8_t hit = kUnobserved;
        const double db = probeBoundary(R, o, s, d, side == 0 ? 1 : -1, &hit);
        Boundary& b = side == 0 ? lane.left : lane.right;
        b.d.push_back(db);
        b.points.push_back(frame.toEnu(s, db));
        ++count[side][hit];
        if (hit == kUnobserved) both_hit[k] = 0;
      }
    }
    for (Boundary* b : {&lane.left, &lane.right}) rejectBoundaryOutliers(frame, lane, o, b);
    const bool has_branches = std::any_of(lanes->begin(), lanes->end(), [&](const Lane& other) {
      return other.split_from == lane.id || other.merges_into == lane.id;
    });
    recentreOnBounds(frame, o, both_hit, has_branches, &lane);
    for (int side = 0; side < 2; ++side) {
      const int* c = count[side];
      const int paint = c[kSolid] + c[kDashed];
      Boundary& b = side == 0 ? lane.left : lane.right;
      if (c[kCurb] > std::max(paint, c[kSeparation])) b.type = map::LineType::kCurb;
      else if (paint > 0 && c[kSolid] >= 0.5 * (paint + c[kSeparation])) b.type = map::LineType::kSolid;
      else if (paint > 0.1 * n) b.type = map::LineType::kDashed;
      else b.type = map::LineType::kVirtual;
    }
  }
}

// A lane split off another (a turn pocket, a bay) is found where a car's footprint fits beside
// its parent, metres after its taper began; its lanelet starts where the taper does. From the
// lane's start, walk back (0.5 m steps) along the two lines that bound it, probed each step from
// the middle between them: the pocket starts where they close in to under pocket_min_width_m.
// Each line is followed as it was last seen (straight on, at its slope over the last metres)
// where a probe finds nothing or something more than 0.5 m off it (a gap between dashes, a line
// the segmentation lost); more than 8 m with neither line seen, the inner line crossing to the
// other lane's side, or no closing within pocket_taper_max_m (or past the other lane's end):
// nothing changes, a pocket full width as far as that is not a taper. Over the taper the centre
// runs midway between the lines at each way-point, its bounds on the lines. A lane merging into
// another (a bay's end, a lane dropped) ends where its taper does, the same way
// forward from its end.

// Extends `lane` at its start (dir -1, beside `other`, the lane it split off) or its end (dir +1,
// beside the lane it merges into) to where its taper closes; false when none is found.
bool extendToTaper(const Raster& R, const FrenetFrame& frame, const ExplorerOptions& o, const Lane& other, int dir, Lane* lane) {
  constexpr double kStep = 0.5, kJump = 0.5, kMaxGap = 8.0, kSlopeOver = 3.0;
  if (lane->waypoint_s.size() < 2) return false;
  const bool at_start = dir < 0;
  const double s0 = at_start ? lane->s_begin : lane->s_end;
  const size_t k0 = at_start ? 0 : lane->waypoint_s.size() - 1;
  const bool left_of_other = lane->centre.d(s0) > other.dAt(s0);
  const double live0 = R.sOf(R.live_i0), live1 = R.sOf(R.live_i1);
  const double limit = at_start ? std::max({other.s_begin + 1.0, s0 - o.pocket_taper_max_m, live0})
                                : std::min({other.s_end - 1.0, s0 + o.pocket_taper_max_m, live1});
  // The lines where the lane ends, probed again (its stored bounds there may be its neighbours'
  // median: rejectBoundaryOutliers).
  uint8_t h0l = kUnobserved, h0r = kUnobserved;
  const double d0 = lane->centre.d(s0);
  const double l0 = probeBoundary(R, o, s0, d0, +1, &h0l), r0 = probeBoundary(R, o, s0, d0, -1, &h0r);
  std::vector<double> ss{s0}, ls{h0l != kUnobserved ? l0 : lane->left.d[k0]}, rs{h0r != kUnobserved ? r0 : lane->right.d[k0]};
  // The inner line (towards the other lane) is on this lane's side of the other's centre: a probe
  // through a gap between dashes finds the other lane's far line, and the stored bound is taken.
  const double other0 = other.dAt(s0);
  if (left_of_other && rs[0] < other0 + 0.5) rs[0] = std::max(lane->right.d[k0], 0.5 * (d0 + other0));
  if (!left_of_other && ls[0] > other0 - 0.5) ls[0] = std::min(lane->left.d[k0], 0.5 * (d0 + other0));
  // Each line's last sightings (s, d), to follow it across a gap.
  std::vector<std::pair<double, double>> seen_l{{s0, ls[0]}}, seen_r{{s0, rs[0]}};
  const auto predict = [&](const std::vector<std::pair<double, double>>& seen, double t) {
    const auto& last = seen.back();
    for (auto it = seen.rbegin(); it != seen.rend(); ++it) {
      if (std::abs(it->first - last.first) >= kSlopeOver) {  // an earlier sighting kSlopeOver away
        const double slope = (last.second - it->second) / (last.first - it->first);
        return last.second + slope * (t - last.first);
      }
    }
    return last.second;
  };
  // The walk may reach the explored stretch's end (a junction's ROI) with the lines still a lane
  // apart: then the lane was there from the junction (seen late after a turn, or lost in its last
  // metres), not a pocket; it runs to the stretch's end and splits from (merges into) nothing.
  const double stretch_end = at_start ? live0 : live1;
  const bool may_reach_end = o.pocket_to_junction && std::abs(limit - stretch_end) <= 1.0 + 1e-9;  // (the other lane's end: 1 m short of it)
  double min_width = INFINITY;
  bool closed = false;
  for (double t = s0 + dir * kStep; at_start ? t >= limit : t <= limit; t += dir * kStep) {
    const double pl = predict(seen_l, t), pr = predict(seen_r, t);
    uint8_t hl = kUnobserved, hr = kUnobserved;
    const double ml = probeBoundary(R, o, t, 0.5 * (pl + pr), +1, &hl), mr = probeBoundary(R, o, t, 0.5 * (pl + pr), -1, &hr);
    const bool ok_l = hl != kUnobserved && std::abs(ml - pl) <= kJump, ok_r = hr != kUnobserved && std::abs(mr - pr) <= kJump;
    if (ok_l) seen_l.push_back({t, ml});
    if (ok_r) seen_r.push_back({t, mr});
    if (std::min(std::abs(seen_l.back().first - t), std::abs(seen_r.back().first - t)) > kMaxGap) return false;  // neither seen for long
    const double l = ok_l ? ml : pl, r = ok_r ? mr : pr;
    // The inner line stays beside the other lane's centre (a pocket does not cross its parent).
    if (left_of_other ? r < other.dAt(t) + 0.5 : l > other.dAt(t) - 0.5) return false;
    ss.push_back(t);
    ls.push_back(l);
    rs.push_back(r);
    min_width = std::min(min_width, l - r);
    if (l - r < o.pocket_min_width_m) {
      closed = true;
      break;
    }
  }
  const bool to_junction = !closed && may_reach_end && min_width >= o.lane_width_min_m &&
                           std::abs(ss.back() - stretch_end) <= 1.0 + kStep + 1e-9;
  if (!(closed || to_junction) || ss.size() < 3) return false;
  if (to_junction && ss.back() != stretch_end) {  // on to the stretch's end, the lines as last found
    ss.push_back(stretch_end);
    ls.push_back(ls.back());
    rs.push_back(rs.back());
  }
  if (at_start) {  // in the order of s
    std::reverse(ss.begin(), ss.end());
    std::reverse(ls.begin(), ls.end());
    std::reverse(rs.begin(), rs.end());
  }
  const double st = at_start ? ss.front() : ss.back();  // where the taper closes
  const double s_begin = at_start ? st : lane->s_begin, s_end = at_start ? lane->s_end : st;
  const auto at = [&](const std::vector<double>& v, double s) {  // the walk's samples, interpolated
    const size_t i = std::clamp<size_t>(std::upper_bound(ss.begin(), ss.end(), s) - ss.begin(), 1, ss.size() - 1);
    const double u = std::clamp((s - ss[i - 1]) / (ss[i] - ss[i - 1]), 0.0, 1.0);
    return v[i - 1] + u * (v[i] - v[i - 1]);
  };
  // The taper's way-points, in the order of s, but the one at s0 (the lane's own).
  const double a = at_start ? st : s0, b = at_start ? s0 : st;
  const int n = std::max(2, static_cast<int>(std::ceil((b - a) / o.waypoint_spacing_m)) + 1);
  std::vector<double> taper_s;
  for (int k = at_start ? 0 : 1; k < (at_start ? n - 1 : n); ++k) taper_s.push_back(a + (b - a) * k / (n - 1));
  // The centre: midway between the lines at each of the taper's way-points (so it stays between
  // them where they close in), the lane's own fit beyond.
  PiecewiseLinearFit fit;
  const PiecewiseLinearFit& old = lane->centre.piecewiseLinear();
  const auto push = [&](double k, double v) {
    fit.knots.push_back(k);
    fit.values.push_back(v);
  };
  const auto mid = [&](double x) { return 0.5 * (at(ls, x) + at(rs, x)); };
  if (at_start) {
    for (double x : taper_s) push(x, mid(x));
    push(s0, lane->centre.d(s0));
    for (size_t k = 0; k < old.knots.size(); ++k) {
      if (old.knots[k] > s0 + 0.5 && old.knots[k] < lane->s_end - 0.5) push(old.knots[k], old.values[k]);
    }
    push(lane->s_end, lane->centre.d(lane->s_end));
  } else {
    push(lane->s_begin, lane->centre.d(lane->s_begin));
    for (size_t k = 0; k < old.knots.size(); ++k) {
      if (old.knots[k] > lane->s_begin + 0.5 && old.knots[k] < s0 - 0.5) push(old.knots[k], old.values[k]);
    }
    push(s0, lane->centre.d(s0));
    for (double x : taper_s) push(x, mid(x));
  }
  Lane out = *lane;
  out.centre = CentreLine(fit, s_begin, s_end);
  out.s_begin = s_begin;
  out.s_end = s_end;
  out.waypoint_s.clear();
  out.waypoints.clear();
  out.left.d.clear();
  out.left.points.clear();
  out.right.d.clear();
  out.right.points.clear();
  const auto taper = [&] {
    for (double x : taper_s) {
      out.waypoint_s.push_back(x);
      out.left.d.push_back(at(ls, x));
      out.right.d.push_back(at(rs, x));
    }
  };
  if (at_start) taper();  // before the lane's own way-points, which begin at s0
  for (size_t k = 0; k < lane->waypoint_s.size(); ++k) {
    out.waypoint_s.push_back(lane->waypoint_s[k]);
    out.left.d.push_back(lane->left.d[k]);
    out.right.d.push_back(lane->right.d[k]);
  }
  if (!at_start) taper();  // after them, which end at s0
  for (size_t k = 0; k < out.waypoint_s.size(); ++k) {
    const double s = out.waypoint_s[k];
    out.waypoints.push_back(frame.toEnu(s, out.centre.d(s)));
    out.left.points.push_back(frame.toEnu(s, out.left.d[k]));
    out.right.points.push_back(frame.toEnu(s, out.right.d[k]));
  }
  if (to_junction) (at_start ? out.split_from : out.merges_into) = -1;
  *lane = std::move(out);
  return true;
}

void extendPocketsToTheirTaper(const Raster& R, const FrenetFrame& frame, const ExplorerOptions& o, std::vector<Lane>* lanes) {
  if (o.pocket_taper_max_m <= 0.0) return;
  const int n = static_cast<int>(lanes->size());
  for (int i = 0; i < n; ++i) {
    Lane& lane = (*lanes)[i];
    if (lane.split_from >= 0 && lane.split_from < n && lane.split_from != i) {
      extendToTaper(R, frame, o, (*lanes)[lane.split_from], -1, &lane);
    }
    if (lane.merges_into >= 0 && lane.merges_into < n && lane.merges_into != i) {
      extendToTaper(R, frame, o, (*lanes)[lane.merges_into], +1, &lane);
    }
  }
}

// The far lanes of a wide road lie beyond the segmentation's lane classes (two either side of
// the ego lane) and are seen obliquely: their ground is drivable but sprayed with stray labels
// where particles find room only in pieces (dropped: a glimpse is no lane), and their far lines
// are too sparse for markUnnamedLanes, which needs both of a lane's lines within one bin. But a
// dashed line only ever separates two lanes of one direction: when the outermost lane (of those
// over half the explored stretch, at its middle) has a dashed bound on one side, a lane lies beyond
// it (addLanesBeyondDashedLines). It is added where the strip beyond, one lane wide (that lane's
// median width; or the distance to a line, paint within a cell of one column in at least 5 % of
// the rows and twice the median of the columns searched, within half a metre of that width), is
// observed in at least half its cells, drivable in 30 % (road: not a verge or a shoulder the
// segmentation calls background), holds no kerb or outside column (in 30 % of a 10 m bin's rows,
// within line_tolerance_m) in at least 60 % of its bins (beyond a two-way road's divider the
// raster is outside: none there; a bin beside a junction may hold the gore where a carriageway
// splits off), and no other lane runs in it but pieces of the lane itself (split off that lane,
// running on to the junction: the particles found room in its last metres), which the added lane
// replaces. The lane runs
// along that lane, its centre line shifted by half of each width, its near bound the other's
// (shared), its far bound that far beyond, typed by the line found there (virtual if none); no
// particle supports it (its confidence says so). Repeated while the new outermost lane's far bound
// is dashed, at most lanes_beyond_dashed lanes in all, the side with the more observed strip first.
struct BeyondCandidate {
  bool ok = false;
  double width = 0.0;       // near bound to far bound
  double observed = 0.0;    // share of the strip's cells observed (not outside)
  map::LineType far_type = map::LineType::kVirtual;
};

BeyondCandidate candidateBeyond(const Raster& R, const ExplorerOptions& o, const Lane& a, int side) {
  BeyondCandidate c;
  const Boundary& near = side > 0 ? a.left : a.right;
  if (near.type != map::LineType::kDashed || near.d.size() < 2) return c;
  const size_t n = near.d.size();
  std::vector<double> widths;
  for (size_t k = 0; k < n; ++k) widths.push_back(a.left.d[k] - a.right.d[k]);
  double w = std::clamp(upperMedian(std::move(widths)), o.lane_width_min_m, o.lane_width_max_m);
  // A line at the far side: the offset from the near bound (within half a metre of that lane's
  // width, lanes of one road being about as wide) where most rows show paint within a cell.
  const double half_step = 0.5 * o.waypoint_spacing_m;
  auto rowsOf = [&](size_t k, int* i0, int* i1) {
    *i0 = std::max(R.live_i0, R.row(a.waypoint_s[k] - half_step));
    *i1 = std::min(R.live_i1, R.row(a.waypoint_s[k] + half_step) - 1);
  };
  const int lo = static_cast<int>(std::round(std::max(o.lane_width_min_m, w - 0.5) / R.res));
  const int hi = static_cast<int>(std::round(std::min(o.lane_width_max_m, w + 0.5) / R.res));
  std::vector<int> line_rows(hi - lo + 1, 0), line_dashed(hi - lo + 1, 0);
  int rows = 0;
  for (size_t k = 0; k < n; ++k) {
    int i0, i1;
    rowsOf(k, &i0, &i1);
    const int j_near = R.col(near.d[k]);
    for (int i = i0; i <= i1; ++i, ++rows) {
      for (int m = lo; m <= hi; ++m) {
        bool line = false, dashed = false;
        for (int dj = -1; dj <= 1; ++dj) {
          const int j = j_near + side * m + dj;
          if (j < 0 || j >= R.nd) continue;
          const uint8_t v = R.at(i, j);
          line = line || v == kDashed || v == kSolid || v == kSeparation;
          dashed = dashed || v == kDashed;
        }
        line_rows[m - lo] += line;
        line_dashed[m - lo] += dashed;
      }
    }
  }
  if (rows == 0) return c;
  const int best = static_cast<int>(std::max_element(line_rows.begin(), line_rows.end()) - line_rows.begin());
  const bool far_line = line_rows[best] >= 0.05 * rows && line_rows[best] >= 2 * upperMedian(line_rows);
  if (far_line) {
    w = (lo + best) * R.res;
    c.far_type = line_dashed[best] * 2 > line_rows[best] ? map::LineType::kDashed : map::LineType::kSolid;
  }
  // The strip: observed, walls, in bins of divider_bin_m.
  const int tol = std::max(0, static_cast<int>(std::round(o.line_tolerance_m / R.res)));
  const int inner0 = tol + 1, inner1 = static_cast<int>(std::round(w / R.res)) - tol - 1;
  if (inner1 <= inner0) return c;
  const int bin_rows = std::max(1, static_cast<int>(std::round(o.divider_bin_m / R.res)));
  int64_t cells = 0, observed = 0, drivable = 0;
  int bins = 0, good_bins = 0;
  std::vector<int> wall(inner1 - inner0 + 1, 0);
  int bin_row_count = 0, bin_cells = 0, bin_observed = 0, next_bin = -1;
  auto closeBin = [&]() {
    if (bin_row_count == 0) return;
    ++bins;
    const bool walled = *std::max_element(wall.begin(), wall.end()) >= 0.3 * bin_row_count;
    good_bins += !walled && bin_observed >= 0.5 * bin_cells;
    std::fill(wall.begin(), wall.end(), 0);
    bin_row_count = bin_cells = bin_observed = 0;
  };
  for (size_t k = 0; k < n; ++k) {
    int i0, i1;
    rowsOf(k, &i0, &i1);
    const int j_near = R.col(near.d[k]);
    for (int i = i0; i <= i1; ++i) {
      if (i >= next_bin) {
        closeBin();
        next_bin = i + bin_rows;
      }
      ++bin_row_count;
      for (int m = inner0 - tol; m <= inner1 + tol; ++m) {
        const int j = j_near + side * m;
        const uint8_t v = (j < 0 || j >= R.nd) ? static_cast<uint8_t>(kOutside) : R.at(i, j);
        const bool is_wall = v == kCurb || v == kOutside;
        for (int q = std::max(inner0, m - tol); q <= std::min(inner1, m + tol); ++q) wall[q - inner0] += is_wall;
        if (m < inner0 || m > inner1) continue;
        ++cells;
        ++bin_cells;
        const bool obs = v != kUnobserved && v != kOutside;
        observed += obs;
        bin_observed += obs;
        drivable += v == kDrivable;
      }
    }
  }
  closeBin();
  if (cells == 0 || bins == 0) return c;
  c.width = w;
  c.observed = static_cast<double>(observed) / cells;
  c.ok = c.observed >= 0.5 && drivable >= 0.3 * cells && good_bins >= 0.6 * bins;
  return c;
}

void addLanesBeyondDashedLines(const Raster& R, const FrenetFrame& frame, const RoadGeometry& road, const ExplorerOptions& o,
                               std::vector<Lane>* lanes) {
  const double stretch = road.s_end - road.s_begin;
  const double sm = 0.5 * (road.s_begin + road.s_end);
  for (int added = 0; added < o.lanes_beyond_dashed && !lanes->empty(); ++added) {
    int best_lane = -1, best_side = 0;
    BeyondCandidate best;
    std::vector<bool> replaced;
    for (int side : {1, -1}) {
      // The outermost lane on this side at the middle, of those over half the stretch.
      int outer = -1;
      for (const auto& l : *lanes) {
        if (l.s_end - l.s_begin < 0.5 * stretch || sm < l.s_begin || sm > l.s_end) continue;
        if (outer < 0 || side * l.centre.d(sm) > side * (*lanes)[outer].centre.d(sm)) outer = l.id;
      }
      if (outer < 0) continue;
      BeyondCandidate c = candidateBeyond(R, o, (*lanes)[outer], side);
      // No other lane runs in the strip, but for pieces of this one split off that lane and
      // running on to the junction (where the particles found room in its last metres): the
      // added lane replaces them.
      const Lane& a = (*lanes)[outer];
      const Boundary& near = side > 0 ? a.left : a.right;
      std::vector<bool> in_strip(lanes->size(), false);
      for (size_t k = 0; c.ok && k < a.waypoint_s.size(); ++k) {
        const double s = a.waypoint_s[k], dc = near.d[k] + side * 0.5 * c.width;
        for (const auto& l : *lanes) {
          if (l.id == outer || s < l.s_begin || s > l.s_end || std::abs(l.centre.d(s) - dc) >= 0.5 * c.width) continue;
          in_strip[l.id] = true;
          if (l.split_from != outer || l.merges_into >= 0 || l.s_end < a.s_end - 1e-6) c.ok = false;
        }
      }
      if (c.ok && (!best.ok || c.observed > best.observed)) {
        best = c;
        best_lane = outer;
        best_side = side;
        replaced = in_strip;
      }
    }
    if (best_lane < 0) return;
    const Lane& a = (*lanes)[best_lane];
    const Boundary& near = best_side > 0 ? a.left : a.right;
    std::vector<double> half;
    for (size_t k = 0; k < near.d.size(); ++k) half.push_back(std::abs(near.d[k] - a.centre.d(a.waypoint_s[k])));
    Lane lane;
    lane.s_begin = a.s_begin;
    lane.s_end = a.s_end;
    PiecewiseLinearFit fit = a.centre.piecewiseLinear();
    const double shift = best_side * (upperMedian(std::move(half)) + 0.5 * best.width);
    for (double& v : fit.values) v += shift;
    lane.centre = CentreLine(fit, lane.s_begin, lane.s_end);
    lane.waypoint_s = a.waypoint_s;
    Boundary far;
    far.type = best.far_type;
    for (size_t k = 0; k < a.waypoint_s.size(); ++k) {
      lane.waypoints.push_back(frame.toEnu(a.waypoint_s[k], lane.centre.d(a.waypoint_s[k])));
      far.d.push_back(near.d[k] + best_side * best.width);
      far.points.push_back(frame.toEnu(a.waypoint_s[k], far.d.back()));
    }
    lane.left = best_side > 0 ? far : near;
    lane.right = best_side > 0 ? near : far;
    lane.id = static_cast<int>(lanes->size());
    lanes->push_back(std::move(lane));
    replaced.push_back(false);
    dropLanes(replaced, lanes);
  }
}

// Index from the left among the lanes present at each lane's middle.
void indexLanesFromLeft(std::vector<Lane>* lanes) {
  for (auto& lane : *lanes) {
    const double sm = 0.5 * (lane.s_begin + lane.s_end);
    int idx = 0;
    for (const auto& other : *lanes) {
      if (&other != &lane && sm >= other.s_begin && sm <= other.s_end && other.centre.d(sm) > lane.centre.d(sm)) ++idx;
    }
    lane.index_from_left = idx;
  }
}

}  // namespace

void removeLanes(const std::vector<bool>& drop, std::vector<Lane>* lanes) {
  dropLanes(drop, lanes);
  indexLanesFromLeft(lanes);
}

ExplorationResult startExploration(const RoadGeometry& road_in, const ExplorerOptions& o, RoadGeometry* stretch) {
  o.validate();
  if (road_in.polyline.size() < 2) throw LanesError("road " + std::to_string(road_in.road_id) + " has no polyline");
  ExplorationResult res;
  res.road_id = road_in.road_id;
  res.from_node = road_in.from_node;
  res.to_node = road_in.to_node;
  res.frame = std::make_shared<FrenetFrame>(road_in.polyline, o.frame_spacing_m, o.frame_smoothing_m);
  *stretch = explorationStretch(road_in, res.frame->length(), o);
  return res;
}

ExplorationResult exploreRoad(const bev::BevGrid& grid, const RoadGeometry& road_in, const ExplorerOptions& o,
                              const std::optional<EgoPose>& ego, int history_stride) {
  RoadGeometry road;
  ExplorationResult res = startExploration(road_in, o, &road);
  const FrenetFrame* frame = res.frame.get();
  if (auto placed = shortLinkStretch(grid, *frame, road_in, road, o)) road = std::move(*placed);
  const double s_stop = road.s_end;
  double s_start = road.s_begin;
  if (ego) s_start = std::clamp(frame->toFrenet(ego->position).x(), s_start, s_stop);
  if (!(s_stop - s_start > 1.0)) throw LanesError("road " + std::to_string(road.road_id) + " has no length to explore");
  // A lane must cover most of a short road's stretch, else min_lane_length_m.
  const double min_lane_length = std::min(o.min_lane_length_m, 0.8 * (road.s_end - road.s_begin));

  // 1. The straightened raster.
  auto t0 = Clock::now();
  const Raster R = buildRaster(grid, *frame, road, o);
  for (uint8_t c : R.code) ++res.stats.raster_cells[c];
  res.stats.raster_s = since(t0);
  if (history_stride > 0) res.raster = {R.sa, R.d0, R.res, R.ns, R.nd, R.code};

  // 2-3. The particle filter, DBSCAN and lane tracks.
  t0 = Clock::now();
  ParticleFilter filter(R, o, s_start, s_stop, &res.stats);
  filter.seedStartStrip();
  filter.run(history_stride > 0 ? &res.history : nullptr, history_stride);
  res.stats.filter_s = since(t0);

  // 4-5. Centre lines, way-points, boundaries.
  t0 = Clock::now();
  std::vector<Track> tracks = filter.tracks();
  res.stats.pieces_joined = joinLanePieces(R, o, &tracks);
  res.lanes = fitLanes(tracks, filter.bins(), road, s_stop, min_lane_length, filter.seenFromStart(), o);
  dropLanesOnNothing(R, o, &res.lanes);
  dropFloatingLanes(o, &res.lanes);
  probeBoundaries(R, *frame, o, &res.lanes);
  extendPocketsToTheirTaper(R, *frame, o, &res.lanes);
  addLanesBeyondDashedLines(R, *frame, road, o, &res.lanes);
  indexLanesFromLeft(&res.lanes);
  res.stats.fit_s = since(t0);
  return res;
}

}  // namespace lanemap::lanes
