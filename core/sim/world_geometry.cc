// Plane geometry for the world builder (see world_geometry.h).
#include "core/sim/world_geometry.h"

#include <algorithm>
#include <cmath>

namespace lanemap::sim::geom {

namespace {

std::vector<double> cumulative(const std::vector<Vector2d>& pts) {
  std::vector<double> s(pts.size(), 0.0);
  for (size_t i = 1; i < pts.size(); ++i) s[i] = s[i - 1] + (pts[i] - pts[i - 1]).norm();
  return s;
}

// Drops consecutive duplicates (closer than 1 mm).
std::vector<Vector2d> dedupe(const std::vector<Vector2d>& pts) {
  std::vector<Vector2d> out;
  for (const auto& p : pts) {
    if (out.empty() || (p - out.back()).norm() > 1e-3) out.push_back(p);
  }
  return out;
}

Vector2d safeNormalized(const Vector2d& v, const Vector2d& fallback) {
  const double n = v.norm();
  return n > 1e-12 ? Vector2d(v / n) : fallback;
}

}  // namespace

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

RefLine::RefLine(const std::vector<Vector2d>& raw, double step, double smooth_half_window) {
  std::vector<Vector2d> pts = dedupe(raw);
  if (pts.size() < 2) {
    const Vector2d p = pts.empty() ? Vector2d::Zero() : pts.front();
    pts = {p, p + Vector2d(0.1, 0.0)};
  }
  // 1. Resample at a uniform step.
  const std::vector<double> cum = cumulative(pts);
  const double len = cum.back();
  const int n = std::max(2, static_cast<int>(std::ceil(len / step)) + 1);
  std::vector<Vector2d> res(n);
  size_t seg = 1;
  for (int i = 0; i < n; ++i) {
    const double s = len * i / (n - 1);
    while (seg + 1 < pts.size() && cum[seg] < s) ++seg;
    const double l = cum[seg] - cum[seg - 1];
    const double u = l > 0 ? std::clamp((s - cum[seg - 1]) / l, 0.0, 1.0) : 0.0;
    res[i] = pts[seg - 1] + u * (pts[seg] - pts[seg - 1]);
  }
  // 2. Moving average with a window that shrinks at the ends (end points fixed).
  const double ds = len / (n - 1);
  const int half = std::max(0, static_cast<int>(std::lround(smooth_half_window / std::max(ds, 1e-6))));
  std::vector<Vector2d> sm(n);
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < n; ++i) {
      const int h = std::min({half, i, n - 1 - i});
      Vector2d acc = Vector2d::Zero();
      for (int k = -h; k <= h; ++k) acc += res[i + k];
      sm[i] = acc / (2 * h + 1);
    }
    res = sm;
  }
  p_ = res;
  s_ = cumulative(p_);
  t_.resize(p_.size());
  const Vector2d chord = safeNormalized(p_.back() - p_.front(), Vector2d::UnitX());
  for (size_t i = 0; i < p_.size(); ++i) {
    const size_t a = i == 0 ? 0 : i - 1;
    const size_t b = std::min(i + 1, p_.size() - 1);
    t_[i] = safeNormalized(p_[b] - p_[a], chord);
  }
}

size_t RefLine::segmentOf(double s, double* u) const {
  s = std::clamp(s, 0.0, length());
  size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin();
  i = std::clamp<size_t>(i, 1, s_.size() - 1);
  const double l = s_[i] - s_[i - 1];
  *u = l > 0 ? std::clamp((s - s_[i - 1]) / l, 0.0, 1.0) : 0.0;
  return i;
}

Vector2d RefLine::pointAt(double s) const {
  double u = 0.0;
  const size_t i = segmentOf(s, &u);
  return p_[i - 1] + u * (p_[i] - p_[i - 1]);
}

Vector2d RefLine::tangentAt(double s) const {
  double u = 0.0;
  const size_t i = segmentOf(s, &u);
  return safeNormalized((1.0 - u) * t_[i - 1] + u * t_[i], t_[i]);
}

Vector2d RefLine::normalAt(double s) const {
  const Vector2d t = tangentAt(s);
  return Vector2d(-t.y(), t.x());
}

double RefLine::minRadius(double s0, double s1) const {
  double best = 1e300;
  for (size_t i = 1; i + 1 < p_.size(); ++i) {
    if (s_[i] <= s0 || s_[i] >= s1) continue;
    const double ang = std::acos(std::clamp(t_[i - 1].dot(t_[i + 1]), -1.0, 1.0));
    const double chord = s_[i + 1] - s_[i - 1];
    if (ang > 1e-9) best = std::min(best, chord / ang);
  }
  return best;
}

std::vector<double> RefLine::samplesBetween(double s0, double s1) const {
  std::vector<double> out{s0};
  const double lo = std::min(s0, s1), hi = std::max(s0, s1);
  std::vector<double> mid;
  for (double s : s_) {
    if (s > lo + 0.05 && s < hi - 0.05) mid.push_back(s);
  }
  if (s1 < s0) std::reverse(mid.begin(), mid.end());
  out.insert(out.end(), mid.begin(), mid.end());
  out.push_back(s1);
  return out;
}

std::vector<Vector2d> offsetPolyline(const std::vector<Vector2d>& pts, const std::vector<double>& d) {
  std::vector<Vector2d> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const size_t a = i == 0 ? 0 : i - 1;
    const size_t b = std::min(i + 1, pts.size() - 1);
    const Vector2d t = safeNormalized(pts[b] - pts[a], Vector2d::UnitX());
    out[i] = pts[i] + d[i] * Vector2d(-t.y(), t.x());
  }
  return out;
}

int removeLoops(std::vector<Vector3d>& pts, size_t window) {
  int cut = 0;
  for (size_t i = 0; i + 3 < pts.size(); ++i) {
    const Vector2d a = pts[i].head<2>(), b = pts[i + 1].head<2>();
    for (size_t j = std::min(pts.size() - 2, i + window); j >= i + 2; --j) {
      // The last crossing in the window: everything between the two segments is the loop.
      const Vector2d c = pts[j].head<2>(), d = pts[j + 1].head<2>();
      const double den = cross(b - a, d - c);
      if (std::abs(den) < 1e-12) continue;
      const double t = cross(c - a, d - c) / den, u = cross(c - a, b - a) / den;
      if (t <= 0.0 || t >= 1.0 || u <= 0.0 || u >= 1.0) continue;
      const Vector2d x = a + t * (b - a);
      const Vector3d crossing(x.x(), x.y(), pts[i].z() + t * (pts[i + 1].z() - pts[i].z()));
      pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(i + 1), pts.begin() + static_cast<std::ptrdiff_t>(j + 1));
      pts.insert(pts.begin() + static_cast<std::ptrdiff_t>(i + 1), crossing);
      ++cut;
      break;
    }
  }
  return cut;
}

int dropBackwardPoints(std::vector<Vector3d>& pts, const std::vector<Vector2d>& dirs) {
  if (pts.size() < 3 || dirs.size() != pts.size()) return 0;
  std::vector<Vector3d> kept{pts.front()};
  for (size_t i = 1; i + 1 < pts.size(); ++i) {
    if ((pts[i] - kept.back()).head<2>().dot(dirs[i]) > 0.0) kept.push_back(pts[i]);
  }
  // The last point stays (it joins the next lanelet): drop the kept points it does not advance from.
  while (kept.size() > 1 && (pts.back() - kept.back()).head<2>().dot(dirs.back()) <= 0.0) kept.pop_back();
  kept.push_back(pts.back());
  const int dropped = static_cast<int>(pts.size() - kept.size());
  pts = std::move(kept);
  return dropped;
}

bool pointInPolygon(const Vector2d& p, const std::vector<Vector2d>& poly) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vector2d& a = poly[i];
    const Vector2d& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

double pointSegmentDistance(const Vector2d& p, const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double u = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + u * ab - p).norm();
}

std::vector<Vector2d> Rect::corners() const {
  const Vector2d n(-axis.y(), axis.x());
  return {c + hl * axis + hw * n, c - hl * axis + hw * n, c - hl * axis - hw * n, c + hl * axis - hw * n};
}

bool Rect::contains(const Vector2d& p) const {
  const Vector2d q = p - c;
  const Vector2d n(-axis.y(), axis.x());
  return std::abs(q.dot(axis)) <= hl && std::abs(q.dot(n)) <= hw;
}

namespace {
bool segmentsIntersect(const Vector2d& a, const Vector2d& b, const Vector2d& c, const Vector2d& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}
}  // namespace

double rectSegmentDistance(const Rect& r, const Vector2d& a, const Vector2d& b) {
  if (r.contains(a) || r.contains(b)) return 0.0;
  const auto c = r.corners();
  double best = 1e300;
  for (int i = 0; i < 4; ++i) {
    const Vector2d& p = c[i];
    const Vector2d& q = c[(i + 1) % 4];
    if (segmentsIntersect(a, b, p, q)) return 0.0;
    best = std::min({best, pointSegmentDistance(p, a, b), pointSegmentDistance(a, p, q),
                     pointSegmentDistance(b, p, q)});
  }
  return best;
}

bool rectsOverlap(const Rect& a, const Rect& b) {
  // Separating axis theorem over the four edge normals.
  const auto ca = a.corners(), cb = b.corners();
  const Vector2d axes[4] = {a.axis, Vector2d(-a.axis.y(), a.axis.x()), b.axis,
                            Vector2d(-b.axis.y(), b.axis.x())};
  for (const auto& ax : axes) {
    double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
    for (const auto& p : ca) {
      amin = std::min(amin, p.dot(ax));
      amax = std::max(amax, p.dot(ax));
    }
    for (const auto& p : cb) {
      bmin = std::min(bmin, p.dot(ax));
      bmax = std::max(bmax, p.dot(ax));
    }
    if (amax < bmin || bmax < amin) return false;
  }
  return true;
}

}  // namespace lanemap::sim::geom
