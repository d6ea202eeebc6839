#include "core/bev/road_crown.h"

#include <algorithm>
#include <cmath>

namespace lanemap::bev {

std::optional<RoadCrown> RoadCrown::around(const skeleton::Skeleton& skeleton, const Eigen::Isometry3d& vehicle_to_enu,
                                           const CrownOptions& options) {
  if (!(options.slope > 0.0)) return std::nullopt;
  const Eigen::Matrix3d& R = vehicle_to_enu.linear();
  const Eigen::Vector2d car = vehicle_to_enu.translation().head<2>();
  const double heading = std::atan2(R(1, 0), R(0, 0));
  const auto matches = skeleton.nearestRoads(car, options.max_car_offset_m, heading);
  if (matches.empty()) return std::nullopt;
  const skeleton::AtomicRoad* road = skeleton.road(matches.front().road_id);
  if (!road || road->polyline.size() < 2 || !(road->length > 0.0)) return std::nullopt;

  RoadCrown c;
  c.o_ = options;
  c.road_id_ = road->id;
  c.s_begin_ = road->s_begin;
  c.s_end_ = road->s_end;
  // The line from behind_m behind the car to ahead_m ahead, straight on past its ends.
  const double s_car = matches.front().s;
  const auto at = [&](double s) -> Eigen::Vector2d {
    if (s < 0.0) return skeleton.pointAt(*road, 0.0) + s * skeleton.tangentAt(*road, 0.0);
    if (s > road->length) return skeleton.pointAt(*road, road->length) + (s - road->length) * skeleton.tangentAt(*road, road->length);
    return skeleton.pointAt(*road, s);
  };
  const double s0 = s_car - options.behind_m, s1 = s_car + options.ahead_m;
  const int n = std::max(2, static_cast<int>(std::ceil(s1 - s0)) + 1);
  for (int i = 0; i < n; ++i) {
    const double s = s0 + (s1 - s0) * i / (n - 1);
    c.pts_.push_back(at(s));
    c.s_.push_back(s);
  }
  for (size_t i = 0; i + 1 < c.pts_.size(); ++i) {
    const Eigen::Vector2d t = c.pts_[i + 1] - c.pts_[i];
    c.tangent_.push_back(t.norm() > 1e-9 ? Eigen::Vector2d(t.normalized()) : Eigen::Vector2d::UnitX());
  }
  // The plane the car rests on: ENU z = plane_z0_ + plane_g_ . (p - car).
  const Eigen::Vector3d up = R.col(2);
  if (!(up.z() > 0.5)) return std::nullopt;  // not a car on the ground
  c.car_ = car;
  c.plane_z0_ = vehicle_to_enu.translation().z();
  c.plane_g_ = Eigen::Vector2d(-up.x() / up.z(), -up.y() / up.z());
  size_t hint = static_cast<size_t>(std::max(0.0, std::min(options.behind_m, static_cast<double>(n - 2))));
  c.frenet(car, hint);  // the hint at the car
  c.car_segment_ = hint;
  // The car rests on its four wheels (origin: the rear axle's middle): its plane rises, relative to
  // the profile at the origin, as the profile does from its rear wheels to its front ones and from
  // its right wheels to its left ones, whichever way it faces the road (a U-turn's car faces across
  // the crown).
  const Eigen::Vector2d fwd = R.col(0).head<2>().normalized(), left(-fwd.y(), fwd.x());
  const auto at_wheel = [&](double ahead, double side) {
    const Eigen::Vector2d sdw = c.frenet(car + ahead * fwd + side * left, hint);
    return c.profile(sdw.x(), sdw.y());
  };
  const double h = 0.5 * options.track_m, b = options.wheelbase_m;
  const double rl = at_wheel(0.0, h), rr = at_wheel(0.0, -h), fl = at_wheel(b, h), fr = at_wheel(b, -h);
  c.car_grad_ = ((fl + fr) - (rl + rr)) / (2.0 * b) * fwd + ((rl + fl) - (rr + fr)) / (2.0 * options.track_m) * left;
  // The plane through the wheels at the origin: their mean less the rise to the middle of the car.
  c.car_profile_ = 0.25 * (rl + rr + fl + fr) - c.car_grad_.dot(0.5 * b * fwd);
  return c;
}

Eigen::Vector2d RoadCrown::frenet(const Eigen::Vector2d& p, size_t& hint) const {
  const size_t last = tangent_.size() - 1;
  size_t i = std::min(hint, last);
  int moved = 0;  // -1 down, +1 up: a walk never turns back (a corner's two segments both "behind")
  for (size_t guard = 0; guard <= tangent_.size(); ++guard) {
    const double u = (p - pts_[i]).dot(tangent_[i]);
    const double len = s_[i + 1] - s_[i];
    if (u < 0.0 && i > 0 && moved <= 0) {
      --i;
      moved = -1;
    } else if (u > len && i < last && moved >= 0) {
      ++i;
      moved = 1;
    } else {
      break;
    }
  }
  hint = i;
  const Eigen::Vector2d v = p - pts_[i];
  const Eigen::Vector2d& t = tangent_[i];
  return {s_[i] + v.dot(t), t.x() * v.y() - t.y() * v.x()};
}

double RoadCrown::profile(double s, double d) const {
  const double in = std::min(s - s_begin_, s_end_ - s);
  const double fade = o_.fade_m > 0.0 ? std::clamp(in / o_.fade_m, 0.0, 1.0) : (in >= 0.0 ? 1.0 : 0.0);
  return -o_.slope * std::min(std::abs(d), o_.max_offset_m) * fade;
}

double RoadCrown::planeZ(const Eigen::Vector2d& p) const { return plane_z0_ + plane_g_.dot(p - car_); }

double RoadCrown::aboveCarPlane(const Eigen::Vector2d& p, size_t& hint) const {
  const Eigen::Vector2d sd = frenet(p, hint);
  // The car's plane (planeZ, from the pose) is the plane of its wheels on the profile.
  return profile(sd.x(), sd.y()) - car_profile_ - car_grad_.dot(p - car_);
}

double RoadCrown::groundZ(const Eigen::Vector2d& p) const {
  size_t hint = car_segment_;
  return planeZ(p) + aboveCarPlane(p, hint);
}

std::optional<Eigen::Vector2d> RoadCrown::hit(const Eigen::Vector3d& c, const Eigen::Vector3d& dir, double t_flat,
                                              double max_t, size_t& hint) const {
  // Height of the ray above the ground at t (zero at the hit), and the point under it.
  Eigen::Vector2d p;
  const auto above = [&](double t) {
    const Eigen::Vector3d x = c + t * dir;
    p = x.head<2>();
    return x.z() - planeZ(p) - aboveCarPlane(p, hint);
  };
  constexpr double kTolM = 1e-4;
  double t0 = t_flat, f0 = above(t0);
  if (std::abs(f0) < kTolM) return p;
  // First step along the ray's descent onto the car's plane, then secant steps (exact where the
  // ground is one plane between the two points).
  const double descent = dir.z() - plane_g_.dot(dir.head<2>());
  if (!(descent < -1e-9)) return std::nullopt;
  double t1 = t0 - f0 / descent;
  for (int iter = 0; iter < 8; ++iter) {
    if (!(t1 > 0.0 && t1 <= max_t)) return std::nullopt;
    const double f1 = above(t1);
    if (std::abs(f1) < kTolM) return p;
    const double df = f1 - f0;
    if (std::abs(df) < 1e-12) return std::nullopt;
    const double t2 = t1 - f1 * (t1 - t0) / df;
    t0 = t1;
    f0 = f1;
    t1 = t2;
  }
  return std::nullopt;
}

}  // namespace lanemap::bev
