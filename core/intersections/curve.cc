// Connection curves of intersection lanelets (see curve.h).
#include "core/intersections/curve.h"
#include "core/geo/polyline.h"

#include <algorithm>
#include <cmath>

namespace lanemap::intersections {

namespace {

using Eigen::Vector2d;

constexpr double kPi = 3.14159265358979323846;

using geo::cross;  // core/geo/polyline.h
using geo::unit;

bool segmentsCross(const Vector2d& a, const Vector2d& b, const Vector2d& c, const Vector2d& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  const auto on = [](const Vector2d& p, const Vector2d& q, const Vector2d& r, double o) {
    return std::abs(o) < 1e-12 && std::min(p.x(), q.x()) - 1e-12 <= r.x() && r.x() <= std::max(p.x(), q.x()) + 1e-12 &&
           std::min(p.y(), q.y()) - 1e-12 <= r.y() && r.y() <= std::max(p.y(), q.y()) + 1e-12;
  };
  return on(a, b, c, d1) || on(a, b, d, d2) || on(c, d, a, d3) || on(c, d, b, d4);
}

}  // namespace

Vector2d BezierConnection::point(double a) const {
  const double b = 1.0 - a;
  if (quadratic) return b * b * control[0] + 2.0 * a * b * control[1] + a * a * control[2];
  return b * b * b * control[0] + 3.0 * b * b * a * control[1] + 3.0 * b * a * a * control[2] + a * a * a * control[3];
}

Vector2d BezierConnection::derivative(double a) const {
  const double b = 1.0 - a;
  if (quadratic) return 2.0 * b * (control[1] - control[0]) + 2.0 * a * (control[2] - control[1]);
  return 3.0 * b * b * (control[1] - control[0]) + 6.0 * a * b * (control[2] - control[1]) +
         3.0 * a * a * (control[3] - control[2]);
}

std::vector<Vector2d> BezierConnection::sample(double step_m) const {
  double polygon = 0.0;  // control polygon length: an upper bound of the curve length
  for (size_t i = 1; i < control.size(); ++i) polygon += (control[i] - control[i - 1]).norm();
  const double approx = 0.5 * (polygon + (control.back() - control.front()).norm());
  int n = std::max(5, static_cast<int>(std::ceil(approx / std::max(1e-3, step_m))) + 1);
  if (n % 2 == 0) ++n;
  std::vector<Vector2d> out(n);
  for (int i = 0; i < n; ++i) out[i] = point(static_cast<double>(i) / (n - 1));
  out.front() = control.front();
  out.back() = control.back();
  return out;
}

BezierConnection bezierConnection(const Vector2d& p0, const Vector2d& t0_in, const Vector2d& p2,
                                const Vector2d& t2_in, const CurveOptions& o) {
  const Vector2d t0 = unit(t0_in, unit(p2 - p0, Vector2d::UnitX()));
  const Vector2d t2 = unit(t2_in, t0);
  const double chord = (p2 - p0).norm();
  BezierConnection c;
  // Tangent lines p0 + a t0 and p2 - b t2 meet where a t0 + b t2 = p2 - p0.
  const double det = cross(t0, t2);
  if (std::abs(det) > std::sin(o.parallel_deg * kPi / 180.0) && chord > 1e-6) {
    const Vector2d r = p2 - p0;
    const double a = cross(r, t2) / det;
    const double b = cross(t0, r) / det;
    if (a > o.min_control_fraction * chord && b > o.min_control_fraction * chord &&
        a < o.max_control_fraction * chord && b < o.max_control_fraction * chord) {
      c.quadratic = true;
      c.control = {p0, p0 + a * t0, p2};
      return c;
    }
  }
  const double h = o.cubic_handle_fraction * chord;
  c.control = {p0, p0 + h * t0, p2 - h * t2, p2};
  return c;
}

namespace {

// The circular arc of a quadratic connection (connectionPolyline): its turn (signed, |turn| < pi),
// the length of the straight before and after it, and its radius.
struct Arc {
  Vector2d t0, t2;
  double turn = 0.0, tangent = 0.0, radius = 0.0;
};

Arc arcOf(const BezierConnection& c) {
  Arc arc;
  const Vector2d& p0 = c.control[0];
  const Vector2d& p2 = c.control[2];
  arc.t0 = unit(c.control[1] - p0, Vector2d::UnitX());
  arc.t2 = unit(p2 - c.control[1], arc.t0);
  const double a = (c.control[1] - p0).norm(), b = (p2 - c.control[1]).norm();
  arc.turn = std::atan2(cross(arc.t0, arc.t2), arc.t0.dot(arc.t2));
  arc.tangent = std::min(a, b);
  arc.radius = arc.tangent / std::tan(0.5 * std::abs(arc.turn));
  return arc;
}

// Whether the polyline turns one way only (no S bend): its chord then lies on the inner side of it.
bool turnsOneWay(const std::vector<Vector2d>& p) {
  int sign = 0;
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const double c = cross(p[i] - p[i - 1], p[i + 1] - p[i]);
    if (std::abs(c) < 1e-9) continue;
    const int s = c > 0 ? 1 : -1;
    if (sign != 0 && s != sign) return false;
    sign = s;
  }
  return true;
}

}  // namespace

double maxCurvature(const std::vector<Vector2d>& p) {
  double k = 0.0;
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const Vector2d a = p[i] - p[i - 1], b = p[i + 1] - p[i], c = p[i + 1] - p[i - 1];
    const double denom = a.norm() * b.norm() * c.norm();
    if (denom > 1e-12) k = std::max(k, 2.0 * std::abs(cross(a, b)) / denom);
  }
  return k;
}

std::vector<Vector2d> connectionPolyline(const Vector2d& p0, const Vector2d& t0_in, const Vector2d& p2,
                                         const Vector2d& t2_in, const CurveOptions& o) {
  const BezierConnection c = bezierConnection(p0, t0_in, p2, t2_in, o);
  if (!c.quadratic) return c.sample(o.step_m);
  const Arc arc = arcOf(c);
  const Vector2d& t0 = arc.t0;
  const Vector2d& t2 = arc.t2;
  const double turn = arc.turn;
  const double tangent = arc.tangent;
  const double radius = arc.radius;
  const Vector2d start = c.control[1] - tangent * t0;  // where the arc begins and ends
  const Vector2d end = c.control[1] + tangent * t2;
  const Vector2d normal = turn > 0 ? Vector2d(-t0.y(), t0.x()) : Vector2d(t0.y(), -t0.x());
  const Vector2d centre = start + radius * normal;
  const double step = std::max(1e-3, o.step_m);
  std::vector<Vector2d> out;
  const auto straight = [&](const Vector2d& from, const Vector2d& to) {
    const int n = std::max(1, static_cast<int>(std::ceil((to - from).norm() / step)));
    for (int i = 0; i < n; ++i) out.push_back(from + (to - from) * (static_cast<double>(i) / n));
  };
  if ((start - p0).norm() > 1e-9) straight(p0, start);
  const int n = std::max(2, static_cast<int>(std::ceil(radius * std::abs(turn) / step)));
  const Vector2d r0 = start - centre;
  for (int i = 0; i < n; ++i) {
    const double ang = turn * static_cast<double>(i) / n;
    out.push_back(centre + Vector2d(std::cos(ang) * r0.x() - std::sin(ang) * r0.y(),
                                    std::sin(ang) * r0.x() + std::cos(ang) * r0.y()));
  }
  if ((p2 - end).norm() > 1e-9) straight(end, p2);
  out.push_back(p2);
  out.front() = p0;
  return out;
}

ConnectorBounds connectorBounds(const Vector2d& left0, const Vector2d& right0, const Vector2d& t0,
                                const Vector2d& left2, const Vector2d& right2, const Vector2d& t2,
                                const CurveOptions& o, const std::vector<Vector2d>* centre) {
  ConnectorBounds b;
  b.left = connectionPolyline(left0, t0, left2, t2, o);
  b.right = connectionPolyline(right0, t0, right2, t2, o);
  if (o.min_bound_radius_m <= 0.0) return b;
  // A bound that turns tighter than min_bound_radius_m somewhere (the inside of a sharp turn
  // between lane ends close together: a quadratic's arc, a cubic's hook at an end) is the straight
  // chord between its ends: the edge cuts the corner, as a vehicle's swept path does. A bound
  // that turns one way has its chord on its inner side; one with an S bend only where the chord
  // leaves the outline simple and does not cross the centre line, so the lanelet stays one that
  // Lanelet2 reads the right way round.
  for (const bool left : {true, false}) {
    std::vector<Vector2d>& side = left ? b.left : b.right;
    if (side.size() <= 2 || maxCurvature(side) <= 1.0 / o.min_bound_radius_m) continue;
    const std::vector<Vector2d> chord{side.front(), side.back()};
    if (turnsOneWay(side)) {
      side = chord;
      continue;
    }
    if (!(left ? outlineIsSimple(chord, b.right) : outlineIsSimple(b.left, chord))) continue;
    bool crosses = false;
    for (size_t i = 0; centre && i + 1 < centre->size() && !crosses; ++i) {
      crosses = segmentsCross(chord[0], chord[1], (*centre)[i], (*centre)[i + 1]);
    }
    if (!crosses) side = chord;
  }
  return b;
}

double headingChange(const Vector2d& t_in, const Vector2d& t_out) {
  return std::atan2(cross(t_in, t_out), t_in.dot(t_out));
}

map::TurnDirection turnDirection(const Vector2d& t_in, const Vector2d& t_out, double straight_max_deg) {
  const double ang = headingChange(t_in, t_out);
  if (std::abs(ang) < straight_max_deg * kPi / 180.0) return map::TurnDirection::kStraight;
  return ang > 0 ? map::TurnDirection::kLeft : map::TurnDirection::kRight;
}

bool selfIntersects(const std::vector<Vector2d>& pts) {
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    for (size_t j = i + 2; j + 1 < pts.size(); ++j) {
      if (segmentsCross(pts[i], pts[i + 1], pts[j], pts[j + 1])) return true;
    }
  }
  return false;
}

bool outlineIsSimple(const std::vector<Vector2d>& left, const std::vector<Vector2d>& right) {
  std::vector<Vector2d> ring = left;
  ring.insert(ring.end(), right.rbegin(), right.rend());
  ring.push_back(left.front());
  const size_t n = ring.size() - 1;  // segments
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // the closing segment meets the first one
      if (segmentsCross(ring[i], ring[i + 1], ring[j], ring[j + 1])) return false;
    }
  }
  return true;
}

bool centreLeavesOutline(const std::vector<Vector2d>& centre, const std::vector<Vector2d>& left,
                         const std::vector<Vector2d>& right) {
  if (centre.size() < 2 || left.size() < 2 || right.size() < 2) return false;
  const size_t last = centre.size() - 2;  // the centre's last segment
  for (size_t i = 0; i + 1 < centre.size(); ++i) {
    for (const auto* bound : {&left, &right}) {
      for (size_t j = 0; j + 1 < bound->size(); ++j) {
        // The centre's first and last segments may touch the bounds' first and last ones where the
        // lane ends are narrow (a U-turn's inner bound): only a crossing further in counts.
        const bool at_start = i == 0 && j == 0, at_end = i == last && j + 2 == bound->size();
        if (!at_start && !at_end && segmentsCross(centre[i], centre[i + 1], (*bound)[j], (*bound)[j + 1])) return true;
      }
    }
    // The centre's first and last points lie on the lanelet's ends, between the bounds' ends.
    if (i != 0 && segmentsCross(centre[i], centre[i + 1], left.front(), right.front())) return true;
    if (i != last && segmentsCross(centre[i], centre[i + 1], left.back(), right.back())) return true;
  }
  return false;
}

}  // namespace lanemap::intersections
