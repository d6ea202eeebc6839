// Plane geometry the world builder needs: an arc-length parametrised reference line (resampled,
// smoothed OSM polyline with left normals), lateral offsets, quadratic/cubic Bezier connections,
// point-in-polygon and rectangle distances.
#pragma once

#include "core/geo/polyline.h"

#include <Eigen/Core>

#include <vector>

namespace lanemap::sim::geom {

using Eigen::Vector2d;
using Eigen::Vector3d;

using geo::cross;           // core/geo/polyline.h
using geo::polylineLength;  // core/geo/polyline.h

// A polyline with cumulative arc lengths, unit tangents and left normals at its points.
class RefLine {
 public:
  RefLine() = default;
  // Resamples `pts` every ~step metres and smooths it with a moving average over
  // +-smooth_half_window metres (the window shrinks at the ends, so the end points stay put).
  RefLine(const std::vector<Vector2d>& pts, double step, double smooth_half_window);

  double length() const { return s_.empty() ? 0.0 : s_.back(); }
  const std::vector<Vector2d>& points() const { return p_; }
  const std::vector<double>& arcLengths() const { return s_; }
  Vector2d pointAt(double s) const;
  Vector2d tangentAt(double s) const;
  Vector2d normalAt(double s) const;  // left unit normal
  // Arc lengths of the samples strictly inside (s0, s1), with s0 and s1 added at the ends.
  std::vector<double> samplesBetween(double s0, double s1) const;
  // Smallest radius of curvature over the samples strictly inside (s0, s1) (over 2 m chords).
  double minRadius(double s0, double s1) const;
  // Point at arc length s, moved by d along the left normal.
  Vector2d offsetPoint(double s, double d) const { return pointAt(s) + d * normalAt(s); }

 private:
  size_t segmentOf(double s, double* u) const;
  std::vector<Vector2d> p_;
  std::vector<double> s_;
  std::vector<Vector2d> t_;  // per-point tangents (central differences)
};

// Smooth 0 -> 1 over x in [0, 1] (clamped), zero slope at both ends.
double smoothstep(double x);

// Offsets a polyline by d along its left normals (normals from neighbouring points).
std::vector<Vector2d> offsetPolyline(const std::vector<Vector2d>& pts, const std::vector<double>& d);

// Cuts the loops out of a polyline (xy; z interpolated at the cut): where segment i crosses a
// later segment j within `window` samples, the points in between are replaced by the crossing
// point. A bound offset from a curve tighter than the offset loops (a swallowtail); on the ground
// the inner edge of such a hairpin is a corner. Returns how many loops were cut.
int removeLoops(std::vector<Vector3d>& pts, size_t window);
// Drops the points of a polyline that do not advance along the direction dirs[i] of the reference
// line they were offset from (sizes equal): the reversed part of a fold, also one that begins
// before the polyline does. The first and the last point stay. Returns how many were dropped.
int dropBackwardPoints(std::vector<Vector3d>& pts, const std::vector<Vector2d>& dirs);

bool pointInPolygon(const Vector2d& p, const std::vector<Vector2d>& poly);
double pointSegmentDistance(const Vector2d& p, const Vector2d& a, const Vector2d& b);

// An oriented rectangle (centre, unit axis along its length, half length, half width).
struct Rect {
  Vector2d c = Vector2d::Zero();
  Vector2d axis = Vector2d::UnitX();
  double hl = 1.0, hw = 1.0;
  std::vector<Vector2d> corners() const;
  bool contains(const Vector2d& p) const;
};
double rectSegmentDistance(const Rect& r, const Vector2d& a, const Vector2d& b);
bool rectsOverlap(const Rect& a, const Rect& b);

}  // namespace lanemap::sim::geom
