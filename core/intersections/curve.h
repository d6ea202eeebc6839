// Plane geometry of intersection lanelets (METHOD.md section 5): the quadratic Bezier reference
// trajectory through the tangent-intersection control point, its cubic fallback, the lanelet's
// bounds, and the turn direction from the heading change. The simulator builds its ground-truth
// connections with these same functions (core/sim/world_builder.cc).
#pragma once

#include "core/map/lane_map.h"

#include <Eigen/Core>

#include <vector>

namespace lanemap::intersections {

struct CurveOptions {
  // Below this angle between the two tangents they count as parallel: cubic fallback.
  double parallel_deg = 10.0;
  // The control point must lie in front of both ends by at least this fraction of the chord, and
  // not farther than max_control_fraction chords (a far control point makes a loop or a kink).
  double min_control_fraction = 0.05;
  double max_control_fraction = 3.0;
  double cubic_handle_fraction = 1.0 / 3.0;  // cubic fallback: handles along the tangents, * chord
  double step_m = 0.5;                       // sampling density
  // connectorBounds: a bound turning tighter than this somewhere is the straight chord between
  // its ends instead, where that chord leaves the lanelet sound (Lanelet2's validator warns above
  // curvature 0.5, i.e. under a 2 m radius). 0: off.
  double min_bound_radius_m = 2.0;
};

// A connection from p0 (leaving with heading t0) to p2 (arriving with heading t2).
struct BezierConnection {
  bool quadratic = false;  // else the cubic fallback
  // Control points: quadratic uses c[0] = P0, c[1] = P, c[2] = P2; cubic c[0..3].
  std::vector<Eigen::Vector2d> control;
  Eigen::Vector2d point(double a) const;      // a in [0, 1]
  Eigen::Vector2d derivative(double a) const; // dB/da
  // Samples at a = i / (n - 1), n odd and >= 5 so the middle sample is a = 1/2; ends exact.
  std::vector<Eigen::Vector2d> sample(double step_m) const;
};

BezierConnection bezierConnection(const Eigen::Vector2d& p0, const Eigen::Vector2d& t0,
                                const Eigen::Vector2d& p2, const Eigen::Vector2d& t2,
                                const CurveOptions& options = {});

// The connection as a polyline with points every step_m at most (ends exact). Where the two
// tangent lines meet in front of both ends (bezierConnection's quadratic case): a straight piece,
// a circular arc and a straight piece, the arc's tangent length being the shorter leg, so its
// radius is the largest any curve between the two tangent lines can keep everywhere (a quadratic
// Bezier on the same legs turns up to 1.4 times tighter at its apex and much tighter near the end
// of a short leg: the curvature Lanelet2's validator flags above 0.5 1/m). Else the cubic, sampled.
std::vector<Eigen::Vector2d> connectionPolyline(const Eigen::Vector2d& p0, const Eigen::Vector2d& t0,
                                                const Eigen::Vector2d& p2, const Eigen::Vector2d& t2,
                                                const CurveOptions& options = {});

// The two bounds of an intersection lanelet, each its own connectionPolyline: from the in-lane's
// bound end points (left0, right0), leaving with heading t0, to the out-lane's bound start points
// (left2, right2), arriving with heading t2. They meet the road lanelets' bounds exactly and never
// loop back, which offsets of a tight centre curve do wherever the offset exceeds the curve's
// radius (the inner bound of a sharp turn on a small junction). A bound tighter than
// options.min_bound_radius_m is its chord where the outline stays simple and the chord does not
// cross `centre` (the lanelet's centre line, when given).
struct ConnectorBounds {
  std::vector<Eigen::Vector2d> left, right;
};
ConnectorBounds connectorBounds(const Eigen::Vector2d& left0, const Eigen::Vector2d& right0,
                                const Eigen::Vector2d& t0, const Eigen::Vector2d& left2,
                                const Eigen::Vector2d& right2, const Eigen::Vector2d& t2,
                                const CurveOptions& options = {},
                                const std::vector<Eigen::Vector2d>* centre = nullptr);

// Signed heading change from t_in to t_out in (-pi, pi], counter-clockwise positive (left).
double headingChange(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out);
// kStraight when |change| < straight_max_deg, else kLeft (positive) or kRight.
map::TurnDirection turnDirection(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out,
                                 double straight_max_deg = 40.0);

// The largest curvature of a polyline at its interior points: 1 / the radius of the circle through
// each point and its two neighbours (what Lanelet2's validator computes on a bound).
double maxCurvature(const std::vector<Eigen::Vector2d>& p);

// True when two segments of the polyline that are not neighbours cross or touch.
bool selfIntersects(const std::vector<Eigen::Vector2d>& pts);

// True when the outline of a lanelet (left bound, then the right bound backwards, closed) is a
// simple polygon: no bound crosses itself or the other one.
bool outlineIsSimple(const std::vector<Eigen::Vector2d>& left, const std::vector<Eigen::Vector2d>& right);

// True when the centre line leaves the lanelet's outline: it crosses a bound, or the segment
// across the lanelet's start or end anywhere but at its own first or last point (a connection
// whose centre hooks past lane ends that nearly overlap).
bool centreLeavesOutline(const std::vector<Eigen::Vector2d>& centre, const std::vector<Eigen::Vector2d>& left,
                         const std::vector<Eigen::Vector2d>& right);

}  // namespace lanemap::intersections
