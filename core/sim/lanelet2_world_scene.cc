// The Lanelet2 world, step 9: the scene (asphalt, paint, curbs, sidewalks, crosswalks, stop lines)
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

void Builder::addFill(Surface s, detail::Layer layer, std::vector<Vector2d> poly, int64_t lanelet) {
  if (poly.size() < 3) return;
  detail::FillPrimitive f;
  f.surface = s;
  f.layer = layer;
  f.lanelet = lanelet;
  f.polygon = std::move(poly);
  impl_->fills.push_back(std::move(f));
}

// A band of `width` centred `offset` to the left of pts[a..b] (arc lengths).
void Builder::stroke(const std::vector<Vector2d>& pts, double a, double b, double offset, double width,
                     Surface s, detail::Layer layer) {
  std::vector<double> cum(pts.size(), 0.0);
  for (size_t i = 1; i < pts.size(); ++i) cum[i] = cum[i - 1] + (pts[i] - pts[i - 1]).norm();
  auto interp = [&](double x) {
    size_t i = std::upper_bound(cum.begin(), cum.end(), x) - cum.begin();
    i = std::clamp<size_t>(i, 1, cum.size() - 1);
    const double l = cum[i] - cum[i - 1];
    const double u = l > 0 ? std::clamp((x - cum[i - 1]) / l, 0.0, 1.0) : 0.0;
    return Vector2d(pts[i - 1] + u * (pts[i] - pts[i - 1]));
  };
  std::vector<Vector2d> sub{interp(a)};
  for (size_t i = 0; i < cum.size(); ++i) {
    if (cum[i] > a + 1e-3 && cum[i] < b - 1e-3) sub.push_back(pts[i]);
  }
  sub.push_back(interp(b));
  if ((sub.back() - sub.front()).norm() < 1e-4) return;
  std::vector<double> d1(sub.size(), offset + width / 2.0), d2(sub.size(), offset - width / 2.0);
  auto left = geom::offsetPolyline(sub, d1);
  const auto right = geom::offsetPolyline(sub, d2);
  left.insert(left.end(), right.rbegin(), right.rend());
  addFill(s, layer, std::move(left));
}

// 9. The scene.
void Builder::buildScene() {
  // Lanes: road lanelets carry their id; junction lanelets are intersection asphalt.
  for (const auto& v : vls_) {
    if (v.junction) addFill(Surface::kIntersection, detail::kLayerIntersection, v.poly);
    else addFill(Surface::kAsphalt, detail::kLayerLane, v.poly, v.ll.id);
  }
  // Zebra stripes of a crosswalk between its two edges (same direction).
  auto paintCrosswalk = [&](const std::vector<Vector2d>& left, const std::vector<Vector2d>& right) {
    // Zebra stripes across the walking direction: 0.5 m of paint every 1 m.
    const double len = 0.5 * (length(left) + length(right));
    if (len < 0.6) return;
    const size_t n = static_cast<size_t>(std::ceil(len / 0.05)) + 1;
    const auto L = resample(left, n), R = resample(right, n);
    auto at = [&](const std::vector<Vector2d>& P, double s) {
      const double f = std::clamp(s / len, 0.0, 1.0) * static_cast<double>(n - 1);
      const size_t i = std::min(static_cast<size_t>(f), n - 2);
      return Vector2d(P[i] + (f - static_cast<double>(i)) * (P[i + 1] - P[i]));
    };
    for (double s = 0.25; s + 0.5 <= len - 0.1; s += 1.0) {
      // Inset 0.2 m from the ends of each stripe.
      Vector2d a0 = at(L, s), b0 = at(R, s), a1 = at(L, s + 0.5), b1 = at(R, s + 0.5);
      const Vector2d u0 = (b0 - a0).normalized(), u1 = (b1 - a1).normalized();
      addFill(Surface::kCrosswalkPaint, detail::kLayerCrosswalk,
              {a0 + 0.2 * u0, a1 + 0.2 * u1, b1 - 0.2 * u1, b0 - 0.2 * u0});
    }
    ++stats_.crosswalks;
  };
  // Other lanelets: bicycle lanes, walkways, crosswalks.
  for (const auto& l : file_.map.lanelets) {
    const auto st = file_.lanelet_subtype.find(l.id);
    const std::string subtype = st == file_.lanelet_subtype.end() ? "" : st->second;
    const auto* lb = file_.map.line(l.left_id);
    const auto* rb = file_.map.line(l.right_id);
    if (!lb || !rb || isVehicleSubtype(subtype)) continue;
    auto left = xy(lb->points), right = xy(rb->points);
    if (left.size() < 2 || right.size() < 2) continue;
    if (direction(left).dot(direction(right)) < 0) std::reverse(right.begin(), right.end());
    std::vector<Vector2d> poly = left;
    poly.insert(poly.end(), right.rbegin(), right.rend());
    if (subtype == "bicycle_lane") {
      addFill(Surface::kBikeLane, detail::kLayerShoulder, poly);
    } else if (subtype == "walkway") {
      addFill(Surface::kSidewalk, detail::kLayerSidewalk, poly);
    } else if (subtype == "crosswalk") {
      paintCrosswalk(left, right);
    }
  }
  // Crosswalks as the Lanelet2 reader gives them (map.crosswalks: their two edges).
  for (const auto& c : file_.map.crosswalks) {
    auto left = xy(c.left), right = xy(c.right);
    if (left.size() < 2 || right.size() < 2) continue;
    if (direction(left).dot(direction(right)) < 0) std::reverse(right.begin(), right.end());
    paintCrosswalk(left, right);
  }
  // Which side of a line the road is on: from a lanelet that uses it as a bound.
  std::map<int64_t, std::pair<int64_t, int>> outward;  // key -> (line id, +1: paint to its left)
  auto note = [&](int64_t line_id, bool is_left, const std::vector<Vector2d>& dir_pts) {
    const auto* ls = anyLine(line_id);
    if (!ls) return;
    const int64_t k = key(line_id);
    if (outward.count(k)) return;
    const auto pts = xy(ls->points);
    if (pts.size() < 2) return;
    const bool same = direction(pts).dot(direction(dir_pts)) > 0;
    outward[k] = {line_id, (is_left == same) ? 1 : -1};
  };
  for (const auto& v : vls_) {
    note(v.ll.left_id, true, v.centre);
    note(v.ll.right_id, false, v.centre);
  }
  for (const auto& l : file_.map.lanelets) {
    const auto st = file_.lanelet_subtype.find(l.id);
    if (st == file_.lanelet_subtype.end() || st->second != "bicycle_lane" || l.centre.size() < 2) continue;
    note(l.left_id, true, xy(l.centre));
    note(l.right_id, false, xy(l.centre));
  }
  std::set<int64_t> painted;
  for (const auto& ls : file_.map.lines) {
    const int64_t k = key(ls.id);
    if (!painted.insert(k).second) continue;
    const auto pts = xy(ls.points);
    if (pts.size() < 2) continue;
    const double L = length(pts);
    if (L < 1e-3) continue;
    switch (ls.type) {
      case LineType::kCurb: {
        auto it = outward.find(k);
        const int out = it == outward.end() ? 0 : it->second.second;
        // The curb band beside the road edge, the sidewalk behind it.
        const auto& geo_pts = it == outward.end() ? pts : xy(anyLine(it->second.first)->points);
        stroke(geo_pts, 0.0, length(geo_pts), out * kCurbWidth / 2.0, kCurbWidth, Surface::kCurb, detail::kLayerCurb);
        if (out != 0) {
          stroke(geo_pts, 0.0, length(geo_pts), out * (kCurbWidth + kSidewalkWidth / 2.0), kSidewalkWidth,
                 Surface::kSidewalk, detail::kLayerSidewalk);
        }
        ++stats_.curbs;
        break;
      }
      case LineType::kDashed:
        for (double a = 0.0; a < L; a += kDashPeriod) {
          stroke(pts, a, std::min(L, a + kDashLength), 0.0, kLinePaintWidth, Surface::kDashedPaint,
                 detail::kLayerLinePaint);
        }
        ++stats_.painted_lines;
        break;
      case LineType::kSolid:
        stroke(pts, 0.0, L, 0.0, kLinePaintWidth, Surface::kSolidPaint, detail::kLayerLinePaint);
        ++stats_.painted_lines;
        break;
      case LineType::kSolidSolid:
        stroke(pts, 0.0, L, kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint);
        stroke(pts, 0.0, L, -kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint);
        ++stats_.painted_lines;
        break;
      case LineType::kStopLine:
        stroke(pts, 0.0, L, 0.0, kStopLineWidth, Surface::kStopLinePaint, detail::kLayerStopLine);
        ++stats_.stop_lines;
        break;
      case LineType::kVirtual:
        break;
    }
  }
  double km = 0.0;
  for (const auto& v : vls_) {
    if (!v.junction) km += length(v.centre);
  }
  impl_->stats.driving_lane_km = km / 1000.0;
}

}  // namespace lanemap::sim::l2w
