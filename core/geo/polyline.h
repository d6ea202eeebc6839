// Polyline helpers shared by the mapping, the simulator, the evaluation and the map writers: the
// length of a polyline (in the plane, in 3-D, or of a 3-D polyline's xy projection), a point's
// distance to one, points along one, and the plane cross product and unit vector.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace lanemap::geo {

// Sum of the segment lengths; 0 for fewer than 2 points.
double polylineLength(const std::vector<Eigen::Vector2d>& pts);
double polylineLength(const std::vector<Eigen::Vector3d>& pts);  // 3-D segment lengths
// The length of the polyline's projection on the xy plane (z ignored).
double polylineLengthXy(const std::vector<Eigen::Vector3d>& pts);

// Distance from p to the nearest point of the polyline's segments (a single point: to it; none:
// +infinity). The Xy form measures a 3-D polyline's projection on the xy plane.
double distanceToPolyline(const std::vector<Eigen::Vector2d>& pl, const Eigen::Vector2d& p);
double distanceToPolylineXy(const std::vector<Eigen::Vector3d>& pl, const Eigen::Vector2d& p);

// Points at most `step` apart along the polyline: its vertices, and each segment cut into the
// fewest equal parts no longer than step. The Xy form samples a 3-D polyline's xy projection.
std::vector<Eigen::Vector2d> pointsEvery(const std::vector<Eigen::Vector2d>& pl, double step);
std::vector<Eigen::Vector2d> pointsEveryXy(const std::vector<Eigen::Vector3d>& pl, double step);

// The z component of the 3-D cross product of a and b: > 0 when b turns left of a.
inline double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// v / |v|, or `fallback` when v is (nearly) zero.
inline Eigen::Vector2d unit(const Eigen::Vector2d& v, const Eigen::Vector2d& fallback) {
  const double n = v.norm();
  return n > 1e-12 ? Eigen::Vector2d(v / n) : fallback;
}

}  // namespace lanemap::geo
