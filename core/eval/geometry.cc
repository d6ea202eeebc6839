// Evaluation geometry (see geometry.h).
#include "core/eval/geometry.h"

// Boost 1.74 Geometry includes a header Boost itself marks deprecated; nothing to fix on our side.
#define BOOST_ALLOW_DEPRECATED_HEADERS
#include <boost/geometry.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#include <boost/geometry/geometries/multi_polygon.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanemap::eval {

namespace bg = boost::geometry;
using Eigen::Vector2d;
using BPoint = bg::model::d2::point_xy<double>;
using BPolygon = bg::model::polygon<BPoint>;  // clockwise, closed
using BMulti = bg::model::multi_polygon<BPolygon>;

namespace {

// Point at arc length s (clamped) of `pts`, walking from segment `*seg` with `*seg_start` the arc
// length at pts[*seg] (monotone queries).
Vector2d walk(const Polyline& pts, double s, size_t* seg, double* seg_start) {
  while (*seg + 2 < pts.size() && *seg_start + (pts[*seg + 1] - pts[*seg]).norm() < s) {
    *seg_start += (pts[*seg + 1] - pts[*seg]).norm();
    ++*seg;
  }
  const double len = (pts[*seg + 1] - pts[*seg]).norm();
  const double t = len > 0.0 ? std::clamp((s - *seg_start) / len, 0.0, 1.0) : 0.0;
  return pts[*seg] + t * (pts[*seg + 1] - pts[*seg]);
}

}  // namespace

Polyline resampleSpacing(const Polyline& pts, double step) {
  if (pts.size() < 2) return pts;
  const double total = polylineLength(pts);
  Polyline out;
  size_t seg = 0;
  double seg_start = 0.0;
  for (double s = 0.0; s < total - 1e-9; s += step) out.push_back(walk(pts, s, &seg, &seg_start));
  out.push_back(pts.back());
  return out;
}

Polyline resampleCount(const Polyline& pts, size_t n) {
  n = std::max<size_t>(n, 2);
  if (pts.empty()) return Polyline(n, Vector2d::Zero());
  if (pts.size() < 2) return Polyline(n, pts.front());
  const double total = polylineLength(pts);
  Polyline out;
  out.reserve(n);
  size_t seg = 0;
  double seg_start = 0.0;
  for (size_t i = 0; i < n; ++i) out.push_back(walk(pts, total * static_cast<double>(i) / static_cast<double>(n - 1), &seg, &seg_start));
  out.back() = pts.back();
  return out;
}

OverlapDistance overlapDistance(const Polyline& built, const Polyline& truth, double step) {
  OverlapDistance r;
  r.rms = std::numeric_limits<double>::infinity();
  if (built.size() < 2 || truth.size() < 2) return r;
  const Polyline samples = resampleSpacing(built, step);
  std::vector<double> cum(truth.size(), 0.0);
  for (size_t i = 1; i < truth.size(); ++i) cum[i] = cum[i - 1] + (truth[i] - truth[i - 1]).norm();
  const Vector2d t_first = (truth[1] - truth[0]).normalized();
  const Vector2d t_last = (truth[truth.size() - 1] - truth[truth.size() - 2]).normalized();
  double sum2 = 0.0, sum = 0.0, s_min = std::numeric_limits<double>::infinity(), s_max = -s_min;
  for (const Vector2d& p : samples) {
    double best = std::numeric_limits<double>::infinity(), best_s = 0.0;
    for (size_t i = 0; i + 1 < truth.size(); ++i) {
      const Vector2d ab = truth[i + 1] - truth[i];
      const double len2 = ab.squaredNorm();
      const double t = len2 > 0.0 ? std::clamp((p - truth[i]).dot(ab) / len2, 0.0, 1.0) : 0.0;
      const double d = (p - (truth[i] + t * ab)).norm();
      if (d < best) {
        best = d;
        best_s = cum[i] + t * std::sqrt(len2);
      }
    }
    // Beyond an end: the foot is the end point and the sample lies more than kSlack along the
    // end's tangent past it (the slack absorbs the chords of a polygonal curve).
    constexpr double kEps = 1e-9, kSlack = 0.01;
    if (best_s <= kEps && (p - truth.front()).dot(t_first) < -kSlack) continue;
    if (best_s >= cum.back() - kEps && (p - truth.back()).dot(t_last) > kSlack) continue;
    ++r.samples;
    sum += best;
    sum2 += best * best;
    r.max = std::max(r.max, best);
    s_min = std::min(s_min, best_s);
    s_max = std::max(s_max, best_s);
  }
  if (r.samples == 0) return r;
  r.rms = std::sqrt(sum2 / static_cast<double>(r.samples));
  r.mean = sum / static_cast<double>(r.samples);
  r.covered_m = s_max - s_min;
  return r;
}

double chamferDistance(const Polyline& a, const Polyline& b) {
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  std::vector<double> nearest_b(b.size(), std::numeric_limits<double>::infinity());
  double sum_a = 0.0;
  for (const Vector2d& p : a) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < b.size(); ++j) {
      const double d = (p - b[j]).squaredNorm();
      best = std::min(best, d);
      nearest_b[j] = std::min(nearest_b[j], d);
    }
    sum_a += std::sqrt(best);
  }
  double sum_b = 0.0;
  for (double d : nearest_b) sum_b += std::sqrt(d);
  return 0.5 * (sum_a / static_cast<double>(a.size()) + sum_b / static_cast<double>(b.size()));
}

double ringArea(const Polyline& ring) {
  if (ring.size() < 3) return 0.0;
  double a2 = 0.0;
  for (size_t i = 0; i < ring.size(); ++i) {
    const Vector2d& p = ring[i];
    const Vector2d& q = ring[(i + 1) % ring.size()];
    a2 += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * std::abs(a2);
}

struct LanePolygon::Impl {
  BMulti shape;
  double area = 0.0;
  bool repaired = false;
  Vector2d lo = Vector2d::Zero(), hi = Vector2d::Zero();
};

namespace {

BPolygon toPolygon(const Polyline& ring) {
  BPolygon poly;
  for (const auto& p : ring) bg::append(poly.outer(), BPoint(p.x(), p.y()));
  if (!ring.empty()) bg::append(poly.outer(), BPoint(ring.front().x(), ring.front().y()));
  bg::correct(poly);
  return poly;
}

// Consecutive duplicate points removed (they make Boost report spikes).
Polyline dedupe(const Polyline& pts) {
  Polyline out;
  for (const auto& p : pts) {
    if (out.empty() || (p - out.back()).norm() > 1e-6) out.push_back(p);
  }
  return out;
}

}  // namespace

LanePolygon::LanePolygon() : impl_(new Impl) {}

LanePolygon::LanePolygon(const Polyline& left, const Polyline& right) : impl_(new Impl) {
  if (left.size() < 2 || right.size() < 2) return;
  Polyline ring = dedupe(left);
  for (auto it = right.rbegin(); it != right.rend(); ++it) ring.push_back(*it);
  ring = dedupe(ring);
  while (ring.size() > 1 && (ring.front() - ring.back()).norm() <= 1e-6) ring.pop_back();
  BPolygon poly = toPolygon(ring);
  if (ring.size() >= 3 && bg::is_valid(poly)) {
    impl_->shape.push_back(std::move(poly));
  } else {
    // Union of the quadrilaterals between the bounds resampled every metre.
    impl_->repaired = true;
    const double len = std::max(polylineLength(left), polylineLength(right));
    const size_t n = std::max<size_t>(2, static_cast<size_t>(std::ceil(len / 1.0)) + 1);
    const Polyline l = resampleCount(left, n), r = resampleCount(right, n);
    BMulti acc;
    for (size_t i = 0; i + 1 < n; ++i) {
      Polyline quad = dedupe({l[i], l[i + 1], r[i + 1], r[i]});
      if (quad.size() < 3) continue;
      BPolygon q = toPolygon(quad);
      if (!bg::is_valid(q)) {
        // A bow tie: the bounds cross at X inside this step, two triangles meet there.
        std::vector<Polyline> tris{{l[i], l[i + 1], r[i]}, {l[i + 1], r[i + 1], r[i]}};
        const Vector2d a = l[i], da = l[i + 1] - l[i], b = r[i], db = r[i + 1] - r[i];
        const double den = da.x() * db.y() - da.y() * db.x();
        if (std::abs(den) > 1e-12) {
          const Vector2d ab = b - a;
          const double u = (ab.x() * db.y() - ab.y() * db.x()) / den;
          const double v = (ab.x() * da.y() - ab.y() * da.x()) / den;
          if (u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0) {
            const Vector2d x = a + u * da;
            tris = {{l[i], x, r[i]}, {x, l[i + 1], r[i + 1]}};
          }
        }
        for (const Polyline& tri : tris) {
          if (ringArea(tri) < 1e-9) continue;
          BMulti next;
          bg::union_(acc, toPolygon(tri), next);
          acc = std::move(next);
        }
        continue;
      }
      BMulti next;
      bg::union_(acc, q, next);
      acc = std::move(next);
    }
    impl_->shape = std::move(acc);
  }
  impl_->area = bg::area(impl_->shape);
  bg::model::box<BPoint> box;
  bg::envelope(impl_->shape, box);
  impl_->lo = Vector2d(box.min_corner().x(), box.min_corner().y());
  impl_->hi = Vector2d(box.max_corner().x(), box.max_corner().y());
}

LanePolygon::~LanePolygon() { delete impl_; }
LanePolygon::LanePolygon(const LanePolygon& other) : impl_(new Impl(*other.impl_)) {}
LanePolygon& LanePolygon::operator=(const LanePolygon& other) {
  if (this != &other) *impl_ = *other.impl_;
  return *this;
}
LanePolygon::LanePolygon(LanePolygon&& other) noexcept : impl_(other.impl_) { other.impl_ = nullptr; }
LanePolygon& LanePolygon::operator=(LanePolygon&& other) noexcept {
  std::swap(impl_, other.impl_);
  return *this;
}

double LanePolygon::area() const { return impl_ ? impl_->area : 0.0; }
bool LanePolygon::empty() const { return !impl_ || impl_->shape.empty() || impl_->area <= 0.0; }
bool LanePolygon::repaired() const { return impl_ && impl_->repaired; }
Vector2d LanePolygon::min() const { return impl_ ? impl_->lo : Vector2d::Zero(); }
Vector2d LanePolygon::max() const { return impl_ ? impl_->hi : Vector2d::Zero(); }

double LanePolygon::iou(const LanePolygon& other) const {
  if (empty() || other.empty()) return 0.0;
  if ((min().array() > other.max().array()).any() || (other.min().array() > max().array()).any()) return 0.0;
  BMulti inter;
  try {
    bg::intersection(impl_->shape, other.impl_->shape, inter);
  } catch (const bg::exception&) {
    return 0.0;  // Boost could not clip these two (degenerate overlaps): no overlap counted
  }
  const double i = bg::area(inter);
  const double u = area() + other.area() - i;
  return u > 0.0 ? std::clamp(i / u, 0.0, 1.0) : 0.0;
}

}  // namespace lanemap::eval
