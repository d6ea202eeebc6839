// Plane geometry of the evaluation (core/eval/evaluate.h): polylines resampled by spacing or count,
// the one-sided centre-line distance over the overlapping part, MapTR's Chamfer distance, and
// polygon IoU (Boost.Geometry, kept out of this header).
#pragma once

#include "core/geo/polyline.h"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace lanemap::eval {

using Polyline = std::vector<Eigen::Vector2d>;

using geo::polylineLength;  // core/geo/polyline.h
// Points every `step` metres of arc length from the first point; the last point is always kept.
Polyline resampleSpacing(const Polyline& pts, double step);
// `n` points evenly spread by arc length from the first to the last point (n >= 2).
Polyline resampleCount(const Polyline& pts, size_t n);

// Distance from a built centre line to a truth centre line over their overlapping part:
// the built line is resampled every `step` metres; a sample belongs to the overlap when its closest
// point on the truth line is not beyond one of the truth line's ends (its foot lies on the truth
// line: the sample is not more than 1 cm before the truth's start or after its end along the end
// tangent);
// its distance is the distance to that closest point.
//   rms = sqrt(mean of squared distances over the overlap samples)
//   covered_m = arc length of the truth line between the first and last feet of overlap samples
// samples = 0 (rms = +inf) when nothing overlaps.
struct OverlapDistance {
  double rms = 0.0;
  double mean = 0.0;
  double max = 0.0;
  size_t samples = 0;
  double covered_m = 0.0;
};
OverlapDistance overlapDistance(const Polyline& built, const Polyline& truth, double step);

// Chamfer distance of MapTR's evaluation between two point sets (in practice 100 resampled points
// each): (mean over a of the distance to the nearest b + mean over b of the nearest a) / 2.
double chamferDistance(const Polyline& a, const Polyline& b);

// Area of a simple polygon ring (not closed; either orientation); 0 for fewer than 3 points.
double ringArea(const Polyline& ring);

// A lane polygon prepared once for many IoU computations. Built from a left bound and a right bound
// running in the same direction (the ring is left + reversed right). A ring that is not a valid
// simple polygon (a bound that folds on itself) is rebuilt as the union of the quadrilaterals
// between the two bounds resampled every metre.
class LanePolygon {
 public:
  LanePolygon();
  LanePolygon(const Polyline& left, const Polyline& right);
  ~LanePolygon();
  LanePolygon(const LanePolygon& other);
  LanePolygon& operator=(const LanePolygon& other);
  LanePolygon(LanePolygon&&) noexcept;
  LanePolygon& operator=(LanePolygon&&) noexcept;

  double area() const;
  bool empty() const;
  bool repaired() const;  // the fallback was used
  // Axis-aligned bounds.
  Eigen::Vector2d min() const;
  Eigen::Vector2d max() const;
  // Intersection over union with another polygon (0 when either is empty).
  double iou(const LanePolygon& other) const;

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace lanemap::eval
