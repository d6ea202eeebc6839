#include "core/lanes/frenet.h"

#include "core/lanes/options.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanemap::lanes {

FrenetFrame::FrenetFrame(const std::vector<Eigen::Vector2d>& poly, double spacing, double smoothing) : h_(spacing) {
  std::vector<double> cum{0.0};
  for (size_t i = 1; i < poly.size(); ++i) cum.push_back(cum.back() + (poly[i] - poly[i - 1]).norm());
  if (poly.size() < 2 || cum.back() < 1e-6) throw LanesError("Frenet frame needs a polyline of 2+ distinct points");
  length_ = cum.back();
  const int n = std::max(2, static_cast<int>(std::ceil(length_ / h_)) + 1);
  h_ = length_ / (n - 1);
  std::vector<Eigen::Vector2d> raw(n);
  size_t seg = 0;
  for (int i = 0; i < n; ++i) {
    const double s = std::min(length_, i * h_);
    while (seg + 2 < cum.size() && cum[seg + 1] < s) ++seg;
    const double len = cum[seg + 1] - cum[seg];
    const double t = len > 1e-9 ? std::clamp((s - cum[seg]) / len, 0.0, 1.0) : 0.0;
    raw[i] = poly[seg] + t * (poly[seg + 1] - poly[seg]);
  }
  // Moving average with a window that shrinks symmetrically at the ends (end points stay).
  const int r = static_cast<int>(std::round(smoothing / h_));
  pts_.resize(n);
  std::vector<Eigen::Vector2d> prefix(n + 1, Eigen::Vector2d::Zero());
  for (int i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + raw[i];
  for (int i = 0; i < n; ++i) {
    const int w = std::min({r, i, n - 1 - i});
    pts_[i] = (prefix[i + w + 1] - prefix[i - w]) / (2 * w + 1);
  }
  nrm_.resize(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d t = pts_[std::min(i + 1, n - 1)] - pts_[std::max(i - 1, 0)];
    const Eigen::Vector2d u = t.norm() > 1e-12 ? Eigen::Vector2d(t.normalized()) : Eigen::Vector2d(1, 0);
    nrm_[i] = Eigen::Vector2d(-u.y(), u.x());
  }
}

void FrenetFrame::interp(double s, Eigen::Vector2d* p, Eigen::Vector2d* nrm) const {
  const int n = static_cast<int>(pts_.size());
  const double x = std::clamp(s, 0.0, length_) / h_;
  const int i = std::clamp(static_cast<int>(std::floor(x)), 0, n - 2);
  const double t = x - i;
  *p = (1 - t) * pts_[i] + t * pts_[i + 1];
  const Eigen::Vector2d m = (1 - t) * nrm_[i] + t * nrm_[i + 1];
  *nrm = m.normalized();
}

Eigen::Vector2d FrenetFrame::point(double s) const {
  Eigen::Vector2d p, n;
  interp(s, &p, &n);
  return p;
}

Eigen::Vector2d FrenetFrame::normal(double s) const {
  Eigen::Vector2d p, n;
  interp(s, &p, &n);
  return n;
}

Eigen::Vector2d FrenetFrame::tangent(double s) const {
  const Eigen::Vector2d n = normal(s);
  return Eigen::Vector2d(n.y(), -n.x());
}

Eigen::Vector2d FrenetFrame::toEnu(double s, double d) const {
  Eigen::Vector2d p, n;
  interp(s, &p, &n);
  const Eigen::Vector2d t(n.y(), -n.x());
  double extra = 0.0;
  if (s < 0) extra = s;
  if (s > length_) extra = s - length_;
  return p + extra * t + d * n;
}

Eigen::Vector2d FrenetFrame::toFrenet(const Eigen::Vector2d& q) const {
  const int n = static_cast<int>(pts_.size());
  double best = std::numeric_limits<double>::infinity();
  int bi = 0;
  for (int i = 0; i + 1 < n; ++i) {
    const Eigen::Vector2d a = pts_[i], b = pts_[i + 1];
    const Eigen::Vector2d ab = b - a;
    const double t = std::clamp((q - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
    const double dist = (a + t * ab - q).squaredNorm();
    if (dist < best) {
      best = dist;
      bi = i;
    }
  }
  // Refine s on the segment so that q - point(s) is along normal(s) (normals are interpolated).
  // The root can lie a segment or two away from the nearest one (normals fan out with |d|).
  double lo = std::max(0, bi - 2) * h_, hi = std::min(n - 1, bi + 3) * h_;
  if (bi <= 2) lo = -1e4;
  if (bi >= n - 4) hi = length_ + 1e4;
  auto f = [&](double s) { return (q - toEnu(s, 0.0)).dot(tangent(s)); };
  double flo = f(lo), fhi = f(hi);
  double s = (lo + hi) / 2;
  if (flo * fhi < 0) {
    for (int it = 0; it < 60; ++it) {
      s = (lo + hi) / 2;
      const double fs = f(s);
      if ((fs < 0) == (flo < 0)) {
        lo = s;
        flo = fs;
      } else {
        hi = s;
      }
      if (hi - lo < 1e-7) break;
    }
  } else {
    s = std::abs(flo) < std::abs(fhi) ? lo : hi;
    s = std::clamp(s, -1e4, length_ + 1e4);
  }
  return Eigen::Vector2d(s, (q - toEnu(s, 0.0)).dot(normal(s)));
}

}  // namespace lanemap::lanes
