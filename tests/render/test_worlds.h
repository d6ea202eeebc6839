// Small hand-made Worlds for the sensor tests: a straight road along +east with three lanes,
// painted dashes, curbs and sidewalks on a ground that may be sloped and bumpy, plus box obstacles.
// Every geometric fact is analytic, so a test can compute what a sensor must see.
#pragma once

#include "core/sim/world.h"

#include <cmath>
#include <optional>
#include <vector>

namespace lanemap::sim::testing {

// Cross-section (north = y): lanelet 2 (left) [1.75, 5.25], lanelet 1 (ego) [-1.75, 1.75],
// lanelet 3 (right) [-5.25, -1.75]. Lane lines: dashes 0.15 m wide centred on y = +-1.75, painted
// where fmod(east, 9) is in [0, 3) (so a dash spans east 9..12, 18..21, ...); solid edge lines
// 0.15 m wide inside the curbs; curbs |y| in [5.25, 5.45]; sidewalk to |y| 8; grass beyond.
class StripedRoadWorld : public World {
 public:
  // Ground z = base + grade_e * east + grade_n * north + bump * sin(2 pi east / bump_period).
  double base = 0.0, grade_e = 0.0, grade_n = 0.0, bump = 0.0, bump_period = 4.0;
  // When set, lanelet 2 (left) runs the other way: no lane offset to it, and the line between it
  // and the ego lane is solid (painted like a centre line).
  bool left_is_opposite = false;
  bool solid_left_line = false;  // the line between ego and left lane is solid (not dashed)
  std::vector<Obstacle> obstacles;

  static constexpr double kHalfLane = 1.75;
  static constexpr double kLineHalfWidth = 0.075;

  double height(double e, double n) const override {
    return base + grade_e * e + grade_n * n + bump * std::sin(2.0 * M_PI * e / bump_period);
  }

  static bool inDash(double e) {
    const double m = std::fmod(e, 9.0);
    return (m < 0 ? m + 9.0 : m) < 3.0;
  }

  GroundSample sample(double e, double n) const override {
    const double a = std::abs(n);
    if (a >= 8.0) return {Surface::kOffRoad, -1};
    if (a >= 5.45) return {Surface::kSidewalk, -1};
    if (a >= 5.25) return {Surface::kCurb, -1};
    const int64_t lanelet = n >= kHalfLane ? 2 : (n < -kHalfLane ? 3 : 1);
    if (a >= 5.25 - 2 * kLineHalfWidth) return {Surface::kSolidPaint, lanelet};
    if (std::abs(a - kHalfLane) <= kLineHalfWidth) {
      if ((left_is_opposite || solid_left_line) && n > 0) return {Surface::kSolidPaint, lanelet};
      if (inDash(e)) return {Surface::kDashedPaint, lanelet};
    }
    return {Surface::kAsphalt, lanelet};
  }

  void obstaclesNear(const Eigen::Vector2d& p, double radius,
                     std::vector<const Obstacle*>* out) const override {
    for (const Obstacle& o : obstacles) {
      const double reach = std::hypot(o.half_extent.x(), o.half_extent.y());
      if ((o.centre.head<2>() - p).norm() <= radius + reach) out->push_back(&o);
    }
  }

  std::optional<int> laneOffset(int64_t ego, int64_t other) const override {
    auto index = [](int64_t id) { return id == 2 ? 0 : (id == 1 ? 1 : (id == 3 ? 2 : -100)); };
    if (index(ego) < 0 || index(other) < 0) return std::nullopt;
    if (left_is_opposite && (ego == 2) != (other == 2)) return std::nullopt;
    return index(other) - index(ego);
  }

  // The label the ground truth says a camera in the ego lane (lanelet 1) sees at (e, n).
  LabelClass expectedLabel(double e, double n) const { return labelFor(*this, sample(e, n), 1); }
};

inline Obstacle makeBox(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw,
                        Obstacle::Kind kind = Obstacle::Kind::kParkedCar) {
  Obstacle o;
  o.kind = kind;
  o.centre = centre;
  o.half_extent = half;
  o.yaw = yaw;
  o.colour = Eigen::Vector3f(0.6f, 0.1f, 0.1f);
  return o;
}

}  // namespace lanemap::sim::testing
