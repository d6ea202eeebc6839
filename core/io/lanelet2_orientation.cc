// The orientation check of Lanelet2 lanelets (see lanelet2_orientation.h).

#include "core/io/lanelet2_orientation.h"
#include "core/io/lanelet2_internal.h"

#include <algorithm>
#include <limits>

namespace lanemap::io {

using map::LaneMap;

namespace {

// True when `right` runs the other way than `left` (its ends are nearer the other ends).
bool runsAgainst(const std::vector<Eigen::Vector3d>& left, const std::vector<Eigen::Vector3d>& right) {
  const auto d = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return (a - b).head<2>().norm();
  };
  const double same = d(left.front(), right.front()) + d(left.back(), right.back());
  const double crossed = d(left.front(), right.back()) + d(left.back(), right.front());
  return crossed < same;
}

// Lanelet2's geometry::signedDistance(lineString, p) in xy: the distance to the nearest segment
// (the first of equals), positive when p lies on its left; where p projects onto the segment's end
// vertex, the side is decided with the next segment as Lanelet2's internal::isLeftOf does.
double signedDistance2d(const std::vector<Eigen::Vector3d>& ls, const Eigen::Vector2d& p) {
  const auto leftOf = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& q) {
    const Eigen::Vector2d u = b - a, v = q - a;
    return u.x() * v.y() - u.y() * v.x() > 0.0;
  };
  double best = std::numeric_limits<double>::infinity();
  size_t seg = 0;
  bool at_end = false;
  for (size_t i = 0; i + 1 < ls.size(); ++i) {
    const Eigen::Vector2d a = ls[i].head<2>(), b = ls[i + 1].head<2>();
    const double len2 = (b - a).squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    const double d = (a + t * (b - a) - p).norm();
    if (d < best) {
      best = d;
      seg = i;
      at_end = t >= 1.0;
    }
  }
  const Eigen::Vector2d s1 = ls[seg].head<2>(), s2 = ls[seg + 1].head<2>();
  bool left = leftOf(s1, s2, p);
  if (at_end && seg + 2 < ls.size()) {
    const Eigen::Vector2d next = ls[seg + 2].head<2>();
    if (left != leftOf(s2, next, p) && left == leftOf(s1, s2, next)) left = !left;
  }
  return left ? best : -best;
}

}  // namespace

namespace lanelet2_internal {

Alignment lanelet2Alignment(const std::vector<Eigen::Vector3d>& left, const std::vector<Eigen::Vector3d>& right) {
  Alignment a;
  if (left.empty() || right.empty() || (left.size() <= 1 && right.size() <= 1)) return a;
  const auto middle = [](const std::vector<Eigen::Vector3d>& ls, bool inverted) -> Eigen::Vector2d {
    if (ls.size() <= 2) return 0.5 * (ls.front() + ls.back()).head<2>();
    return ls[inverted ? ls.size() - 1 - ls.size() / 2 : ls.size() / 2].head<2>();
  };
  a.invert_left = left.size() > 1 && !(signedDistance2d(left, middle(right, false)) < 0.0);
  a.invert_right = right.size() > 1 && !(signedDistance2d(right, middle(left, a.invert_left)) > 0.0);
  return a;
}

}  // namespace lanelet2_internal

using lanelet2_internal::Alignment;
using lanelet2_internal::lanelet2Alignment;

// Lanelet2's loader aligns a lanelet's bounds by geometry alone (OSM cannot say "inverted"), with
// lanelet2::geometry::align (lanelet2Alignment above). A bound may therefore run against the
// driving direction, as the line shared by two lanes of opposite directions does for one of them.
std::string orientationProblem(const map::Lanelet& ll, const map::LineString& left,
                               const map::LineString& right) {
  if (left.points.size() < 2 || right.points.size() < 2) return {};
  std::vector<Eigen::Vector3d> l = left.points;
  std::vector<Eigen::Vector3d> r = right.points;
  const Alignment a = lanelet2Alignment(l, r);
  if (a.invert_left) std::reverse(l.begin(), l.end());
  if (a.invert_right) std::reverse(r.begin(), r.end());
  const std::string bounds = "lanelet " + std::to_string(ll.id) + ": Lanelet2 would read its bounds (left " +
                             std::to_string(left.id) + ", right " + std::to_string(right.id) + ") ";
  if (runsAgainst(l, r)) return bounds + "running against each other";
  if (ll.centre.size() >= 2 && runsAgainst(l, ll.centre)) {
    return bounds + "against its driving direction: the left bound must lie on the left";
  }
  return {};
}

bool boundTurnedOnLoad(const map::LineString& left, const map::LineString& right) {
  if (left.points.size() < 2 || right.points.size() < 2) return false;
  // A bound that is one point (a U-turn's inner bound about the road's line) gives align nothing
  // to go by: such a lanelet is orientationProblem's to judge.
  const auto isPoint = [](const std::vector<Eigen::Vector3d>& p) {
    return std::all_of(p.begin(), p.end(), [&](const Eigen::Vector3d& q) { return (q - p.front()).head<2>().norm() < 0.05; });
  };
  if (isPoint(left.points) || isPoint(right.points)) return false;
  const Alignment a = lanelet2Alignment(left.points, right.points);
  return a.invert_left || a.invert_right;
}

std::vector<std::string> orientationProblems(const LaneMap& map) {
  std::vector<std::string> problems;
  for (const auto& ll : map.lanelets) {
    const auto* left = map.line(ll.left_id);
    const auto* right = map.line(ll.right_id);
    if (!left || !right) continue;
    std::string p = orientationProblem(ll, *left, *right);
    if (!p.empty()) problems.push_back(std::move(p));
  }
  return problems;
}

std::vector<Eigen::Vector3d> laneletOutline(const LaneMap& map, const map::Lanelet& lanelet) {
  const auto* left = map.line(lanelet.left_id);
  const auto* right = map.line(lanelet.right_id);
  if (!left || !right || left->points.empty() || right->points.empty()) return {};
  std::vector<Eigen::Vector3d> ring = left->points;
  if (runsAgainst(left->points, right->points)) {
    ring.insert(ring.end(), right->points.begin(), right->points.end());
  } else {
    ring.insert(ring.end(), right->points.rbegin(), right->points.rend());
  }
  return ring;
}

}  // namespace lanemap::io
