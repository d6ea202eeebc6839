#include "core/map/simplify.h"

#include <algorithm>
#include <utility>

namespace lanemap::map {

namespace {

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 <= 0.0) return (p - a).norm();
  const double u = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return (p - (a + u * ab)).norm();
}

}  // namespace

std::vector<Eigen::Vector3d> simplifyPolyline(const std::vector<Eigen::Vector3d>& points, double tolerance) {
  if (tolerance <= 0.0 || points.size() < 3) return points;
  std::vector<bool> keep(points.size(), false);
  keep.front() = keep.back() = true;
  // Iterative Douglas-Peucker (no recursion depth limit on long lines).
  std::vector<std::pair<size_t, size_t>> stack{{0, points.size() - 1}};
  while (!stack.empty()) {
    const auto [first, last] = stack.back();
    stack.pop_back();
    double worst = -1.0;
    size_t worst_i = first;
    for (size_t i = first + 1; i < last; ++i) {
      const double d = distanceToSegment(points[i], points[first], points[last]);
      if (d > worst) {
        worst = d;
        worst_i = i;
      }
    }
    if (worst > tolerance) {
      keep[worst_i] = true;
      stack.push_back({first, worst_i});
      stack.push_back({worst_i, last});
    }
  }
  std::vector<Eigen::Vector3d> out;
  for (size_t i = 0; i < points.size(); ++i) {
    if (keep[i]) out.push_back(points[i]);
  }
  return out;
}

LaneMap simplified(const LaneMap& map, double tolerance) {
  LaneMap out = map;
  for (auto& l : out.lines) l.points = simplifyPolyline(l.points, tolerance);
  for (auto& l : out.lanelets) l.centre = simplifyPolyline(l.centre, tolerance);
  return out;
}

}  // namespace lanemap::map
