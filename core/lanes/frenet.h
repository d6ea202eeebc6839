// The Frenet frame of an atomic road: s = arc length along the skeleton polyline (the same s as
// AtomicRoad::s_begin/s_end), d = lateral offset along the left normal of a smoothed copy of it.
// The polyline is resampled and smoothed (moving average) so normals turn continuously at OSM
// vertices; toEnu and toFrenet are exact inverses near the road (|d| below the curve radius).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace lanemap::lanes {

class FrenetFrame {
 public:
  // Throws LanesError for fewer than 2 distinct points.
  FrenetFrame(const std::vector<Eigen::Vector2d>& polyline, double spacing_m = 0.5, double smoothing_m = 6.0);

  double length() const { return length_; }
  Eigen::Vector2d point(double s) const;    // the smoothed reference at s (clamped to [0, length])
  Eigen::Vector2d tangent(double s) const;  // unit
  Eigen::Vector2d normal(double s) const;   // unit, left of the driving direction
  // Beyond the ends the reference is extended along the end tangents.
  Eigen::Vector2d toEnu(double s, double d) const;
  // (s, d) of the nearest reference point (s may leave [0, length] along the end tangents).
  Eigen::Vector2d toFrenet(const Eigen::Vector2d& p) const;

 private:
  void interp(double s, Eigen::Vector2d* p, Eigen::Vector2d* n) const;
  double h_ = 0.5, length_ = 0.0;
  std::vector<Eigen::Vector2d> pts_, nrm_;
};

}  // namespace lanemap::lanes
