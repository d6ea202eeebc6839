// Polyline helpers (see polyline.h).
#include "core/geo/polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanemap::geo {

double polylineLength(const std::vector<Eigen::Vector2d>& pts) {
  double len = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).norm();
  return len;
}

double polylineLength(const std::vector<Eigen::Vector3d>& pts) {
  double len = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).norm();
  return len;
}

double polylineLengthXy(const std::vector<Eigen::Vector3d>& pts) {
  double len = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).head<2>().norm();
  return len;
}

std::vector<Eigen::Vector2d> pointsEvery(const std::vector<Eigen::Vector2d>& pl, double step) {
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i + 1 < pl.size(); ++i) {
    const double len = (pl[i + 1] - pl[i]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int k = 0; k < n; ++k) out.push_back(pl[i] + (pl[i + 1] - pl[i]) * (static_cast<double>(k) / n));
  }
  if (!pl.empty()) out.push_back(pl.back());
  return out;
}

std::vector<Eigen::Vector2d> pointsEveryXy(const std::vector<Eigen::Vector3d>& pl, double step) {
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(pl.size());
  for (const auto& p : pl) xy.push_back(p.head<2>());
  return pointsEvery(xy, step);
}

namespace {

template <typename Point>
double distanceTo(const std::vector<Point>& pl, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < pl.size(); ++i) {
    const Eigen::Vector2d a = pl[i].template head<2>(), b = pl[i + 1].template head<2>();
    const double len2 = (b - a).squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * (b - a) - p).norm());
  }
  if (pl.size() == 1) best = (pl[0].template head<2>() - p).norm();
  return best;
}

}  // namespace

double distanceToPolyline(const std::vector<Eigen::Vector2d>& pl, const Eigen::Vector2d& p) { return distanceTo(pl, p); }

double distanceToPolylineXy(const std::vector<Eigen::Vector3d>& pl, const Eigen::Vector2d& p) { return distanceTo(pl, p); }

}  // namespace lanemap::geo
