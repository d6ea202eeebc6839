// The world's paint and fills: marking lines (dashes, double lines, worn and missing stretches),
// surface fills, crosswalks and stop lines. Part of buildWorld (core/sim/world_build.h).
#include "core/sim/world_build.h"

namespace lanemap::sim::world_build {

void Builder::addFill(Surface s, detail::Layer layer, std::vector<Vector2d> poly, int64_t lanelet, bool faded) {
  if (poly.size() < 3) return;
  FillPrimitive f;
  f.surface = s;
  f.level = fill_level_;
  f.layer = layer;
  f.lanelet = lanelet;
  f.faded = faded;
  f.polygon = std::move(poly);
  impl_->fills.push_back(std::move(f));
}

std::vector<Vector2d> Builder::stripPolygon(const CrossSection& xs, const Section& sec, int ca, int cb) const {
  std::vector<Vector2d> poly = columnPoints(xs, sec, ca);
  const auto other = columnPoints(xs, sec, cb);
  poly.insert(poly.end(), other.rbegin(), other.rend());
  return poly;
}

void Builder::emitLinePaint(const std::vector<Vector2d>& pts, LineType type, double outward,
    const std::vector<MarkingGap>& gaps) {
  if (pts.size() < 2) return;
  std::vector<double> cum(pts.size(), 0.0);
  for (size_t i = 1; i < pts.size(); ++i) cum[i] = cum[i - 1] + (pts[i] - pts[i - 1]).norm();
  const double L = cum.back();
  if (L < 1e-3) return;
  if (type == LineType::kCurb) {
    emitStroke(pts, cum, 0.0, L, outward * kCurbPaintWidth / 2.0, kCurbPaintWidth, Surface::kCurb, detail::kLayerCurb, false);
    return;
  }
  std::vector<std::pair<double, double>> pieces;
  if (type == LineType::kDashed) {
    for (double a = 0.0; a < L; a += kDashPeriod) pieces.emplace_back(a, std::min(L, a + kDashLength));
  } else {
    pieces.emplace_back(0.0, L);
  }
  // Split the pieces at the gaps.
  std::vector<std::tuple<double, double, bool>> parts;
  for (const auto& [a, b] : pieces) {
    double cur = a;
    std::vector<MarkingGap> sorted = gaps;
    std::sort(sorted.begin(), sorted.end(), [](const MarkingGap& x, const MarkingGap& y) { return x.s0 < y.s0; });
    for (const auto& g : sorted) {
      const double g0 = std::max(g.s0, cur), g1 = std::min(g.s1, b);
      if (g1 <= g0) continue;
      if (g0 > cur) parts.emplace_back(cur, g0, false);
      if (!g.missing) parts.emplace_back(g0, g1, true);
      cur = g1;
    }
    if (cur < b) parts.emplace_back(cur, b, false);
  }
  for (const auto& [a, b, faded] : parts) {
    if (b - a < 0.05) continue;
    if (type == LineType::kSolidSolid) {
      emitStroke(pts, cum, a, b, kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint, faded);
      emitStroke(pts, cum, a, b, -kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint, faded);
    } else if (type == LineType::kSolid) {
      emitStroke(pts, cum, a, b, 0.0, kLinePaintWidth, Surface::kSolidPaint, detail::kLayerLinePaint, faded);
    } else if (type == LineType::kDashed) {
      emitStroke(pts, cum, a, b, 0.0, kLinePaintWidth, Surface::kDashedPaint, detail::kLayerLinePaint, faded);
    }
  }
}

void Builder::emitStroke(const std::vector<Vector2d>& pts, const std::vector<double>& cum, double a, double b,
    double offset, double width, Surface surface, detail::Layer layer, bool faded) {
  std::vector<Vector2d> sub;
  auto interp = [&](double s) {
    size_t i = std::upper_bound(cum.begin(), cum.end(), s) - cum.begin();
    i = std::clamp<size_t>(i, 1, cum.size() - 1);
    const double l = cum[i] - cum[i - 1];
    const double u = l > 0 ? std::clamp((s - cum[i - 1]) / l, 0.0, 1.0) : 0.0;
    return Vector2d(pts[i - 1] + u * (pts[i] - pts[i - 1]));
  };
  sub.push_back(interp(a));
  for (size_t i = 0; i < cum.size(); ++i) {
    if (cum[i] > a + 1e-3 && cum[i] < b - 1e-3) sub.push_back(pts[i]);
  }
  sub.push_back(interp(b));
  if (sub.size() < 2 || (sub.back() - sub.front()).norm() < 1e-4) return;
  std::vector<double> d1(sub.size(), offset + width / 2.0), d2(sub.size(), offset - width / 2.0);
  auto left = geom::offsetPolyline(sub, d1);
  const auto right = geom::offsetPolyline(sub, d2);
  left.insert(left.end(), right.rbegin(), right.rend());
  addFill(surface, layer, std::move(left), -1, faded);
}

std::vector<MarkingGap> Builder::chooseGaps(int64_t line_id, LineType type, double length) {
  std::vector<MarkingGap> out;
  if (type != LineType::kDashed && type != LineType::kSolid && type != LineType::kSolidSolid) return out;
  if (length < 15.0) return out;
  auto r = rngFor(o_.seed, line_id, 4);
  const double max_len = std::min(30.0, 0.45 * length);
  if (chance(r, o_.p_missing_marking)) {
    const double len = uni(r, std::min(6.0, max_len), max_len);
    const double s0 = uni(r, 0.0, std::max(0.0, length / 2.0 - len));
    out.push_back({line_id, s0, s0 + len, true});
  }
  if (chance(r, o_.p_faded_marking)) {
    const double len = uni(r, std::min(6.0, max_len), max_len);
    const double s0 = uni(r, length / 2.0, std::max(length / 2.0, length - len));
    out.push_back({line_id, s0, s0 + len, false});
  }
  return out;
}

void Builder::emitCrosswalk(const CrossSection& xs, const Section& sec, double a, double b) {
  const int cl = curbColumn(sec, 1), cr = curbColumn(sec, 0);
  const double mid = (a + b) / 2.0;
  const auto v = columnValues(xs, sec, mid);
  const double d_hi = std::max(v[cl], v[cr]), d_lo = std::min(v[cl], v[cr]);
  constexpr double kStripe = 0.5, kGap = 0.5;
  for (double d = d_lo + 0.25; d + kStripe <= d_hi - 0.1; d += kStripe + kGap) {
    std::vector<Vector2d> poly = {at(xs, a, d), at(xs, b, d), at(xs, b, d + kStripe), at(xs, a, d + kStripe)};
    addFill(Surface::kCrosswalkPaint, detail::kLayerCrosswalk, std::move(poly));
  }
  // The truth's crosswalk lanelet: its two edges (s = a and s = b) from one curb to the other,
  // the left edge on the walker's left; the road lanelets of both directions under it.
  map::Crosswalk cw;
  cw.id = 0;  // given in run(), after every line and lanelet (their ids stay as they were)
  cw.road_id = xs.ref->id;
  const auto edge = [&](double s) {
    std::vector<Vector3d> e;
    for (double d : {d_lo, d_hi}) {
      const Vector2d p = at(xs, s, d);
      const double l = m_ * v[cl], r = m_ * v[cr];
      e.emplace_back(p.x(), p.y(), terrainAt(p) + profileAt(xs, s, m_ * d, std::max(l, r), std::min(l, r)));
    }
    return e;
  };
  std::vector<Vector3d> ea = edge(a), eb = edge(b);
  const Vector2d w = (ea.back() - ea.front()).head<2>(), q = (eb.front() - ea.front()).head<2>();
  const bool b_left = w.x() * q.y() - w.y() * q.x() > 0.0;
  cw.left = b_left ? eb : ea;
  cw.right = b_left ? ea : eb;
  for (int k = 0; k < 2; ++k) cw.crossing.insert(cw.crossing.end(), sec.lanes[k].begin(), sec.lanes[k].end());
  truth().crosswalks.push_back(std::move(cw));
}

void Builder::emitStopLine(const CrossSection& xs, const Section& sec, int k, double s) {
  const auto v = columnValues(xs, sec, s);
  int anchor = 0, edge = 0;
  for (int c = 0; c < static_cast<int>(sec.cols.size()); ++c) {
    if (sec.cols[c].kind == ColKind::kAnchor) anchor = c;
    if (sec.cols[c].side == k && (sec.cols[c].kind == ColKind::kLaneOuter || sec.cols[c].kind == ColKind::kPocketDiv)) edge = c;
  }
  const double din = v[anchor], dout = v[edge];
  LineString ls;
  ls.id = nextId();
  ls.type = LineType::kStopLine;
  Vector2d pin = at(xs, s, din), pout = at(xs, s, dout);
  const bool left_is_inner = o_.right_hand_traffic;
  Vector2d p0 = left_is_inner ? pin : pout, p1 = left_is_inner ? pout : pin;
  auto z = [&](const Vector2d& p, double dcan) {
    const double l = m_ * v[curbColumn(sec, 1)], r = m_ * v[curbColumn(sec, 0)];
    return terrainAt(p) + profileAt(xs, s, m_ * dcan, std::max(l, r), std::min(l, r));
  };
  ls.points = {Vector3d(p0.x(), p0.y(), z(p0, left_is_inner ? din : dout)),
               Vector3d(p1.x(), p1.y(), z(p1, left_is_inner ? dout : din))};
  const double h = kStopLineWidth / 2.0;
  addFill(Surface::kStopLinePaint, detail::kLayerStopLine,
          {at(xs, s - h, din), at(xs, s + h, din), at(xs, s + h, dout), at(xs, s - h, dout)});
  for (int64_t id : sec.lanes[k]) laneletRef(id).stop_line_id = ls.id;
  pushLine(std::move(ls));
  ++impl_->stats.stop_lines;
}

}  // namespace lanemap::sim::world_build
