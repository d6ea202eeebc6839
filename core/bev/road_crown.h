// The road's crown: the ground a camera-only BEV projects on (METHOD.md section 3 puts the pixels of
// a frame on the flat plane under the car when there is no LIDAR mesh).
//
// Roads are built with a cross-slope so that rain runs off: from the crown (a two-way road's centre
// line, a one-way carriageway's middle: where OSM draws the way) down to the kerbs, typically
// 1.5-2.5 % (AASHTO's 1.5-2 % for paved lanes; about 2.5 % in several European guidelines). The car rests on
// that slope, so the plane under it (z = 0 of the vehicle frame, tilted by the pose's roll) is the
// ground on its own side of the crown; across the crown the ground falls away from that plane, 2 k
// per metre beyond it. A pixel whose ray reaches that ground meets the plane short of it, so the
// lanes beyond the crown come out pulled towards the car, more the farther they are: on the broad
// benchmark's simulated drives (whose roads have a 2 % crown), truth labels, by 0.12 m a lane over
// and 0.36 m two lanes over (0.48 m on the shipped model's labels; README, "The road's crown").
//
// RoadCrown models the ground around the car as the road's profile z = -k |d| f(s) about its OSM
// line (d: the offset to the left of the line, s: along it), the crown fading out over fade_m
// towards the road's junction ROIs (f from 0 at the ROI edge to 1 fade_m in: a junction's surface
// is warped flat to meet its roads), |d| capped at max_offset_m (past the kerbs the profile says
// nothing). The car's road is the skeleton road nearest the car (with its heading). Relative to the
// car's plane (the pose's), the ground at a point is the profile there less the plane the car rests
// on: the plane through the profile under its four wheels (track_m and wheelbase_m apart), whichever
// way the car faces. So with the car on one side of the crown and the road straight, the ground on
// that side is the plane exactly, as before. A pixel's ground point is where its ray meets that
// surface (a few secant steps from the flat hit); where they do not settle it keeps its flat hit.
//
// What it does not know: a road's real cross-slope (superelevated bends, one-way carriageways that
// fall to one side), a crown off the OSM line, kerbs and sidewalks. The LIDAR mesh measures the
// ground instead, and is used wherever a frame has one.
#pragma once

#include "core/skeleton/skeleton.h"

#include <Eigen/Geometry>

#include <optional>
#include <vector>

namespace lanemap::bev {

struct CrownOptions {
  double slope = 0.0;              // k, the cross-slope from the crown to the kerbs (0.02: 2 %); 0: the
                                   //   flat plane (the default: README, "The road's crown")
  double fade_m = 8.0;             // the crown grows from none at a junction ROI's edge to k this far in
  double max_offset_m = 10.0;      // |d| beyond this counts as this (past the kerbs)
  double max_car_offset_m = 8.0;   // the car's road: the nearest road within this of the car
  double track_m = 1.6;            // the car rests on its wheels: this far apart across ...
  double wheelbase_m = 2.8;        // ... and along (the vehicle origin: the rear axle's middle)
  double behind_m = 10.0;          // the road's line is followed this far behind the car ...
  double ahead_m = 50.0;           // ... and this far ahead (beyond its ends: straight on)
};

class RoadCrown {
 public:
  // The crown of the road the car at vehicle_to_enu drives on; nullopt with slope 0 or no road
  // within max_car_offset_m.
  static std::optional<RoadCrown> around(const skeleton::Skeleton& skeleton, const Eigen::Isometry3d& vehicle_to_enu,
                                         const CrownOptions& options);

  // The road the crown is of.
  int64_t roadId() const { return road_id_; }
  // The ground's ENU height at p (x, y).
  double groundZ(const Eigen::Vector2d& p) const;
  // Where the ray c + t dir (ENU; t >= 0) meets the ground, starting from its hit on the car's plane
  // at t_flat; nullopt when the search does not settle within max_t (the caller keeps the flat hit).
  // `hint`: a segment index kept by the caller between nearby rays (any value is valid).
  std::optional<Eigen::Vector2d> hit(const Eigen::Vector3d& c, const Eigen::Vector3d& dir, double t_flat, double max_t,
                                     size_t& hint) const;

 private:
  RoadCrown() = default;
  // s along the road and d to the left of its line at p.
  Eigen::Vector2d frenet(const Eigen::Vector2d& p, size_t& hint) const;
  double profile(double s, double d) const;
  // The ground's height above the car's plane at p.
  double aboveCarPlane(const Eigen::Vector2d& p, size_t& hint) const;
  double planeZ(const Eigen::Vector2d& p) const;

  CrownOptions o_;
  int64_t road_id_ = -1;
  double s_begin_ = 0.0, s_end_ = 0.0;  // the road's ROI edges
  std::vector<Eigen::Vector2d> pts_;    // the line around the car, about 1 m apart
  std::vector<double> s_;               // arc length of each point along the road
  std::vector<Eigen::Vector2d> tangent_;  // per segment, unit
  size_t car_segment_ = 0;              // the segment the car is on (frenet's hint there)
  // The car and its plane from the pose: ENU z = plane_z0_ + plane_g_ . (p - car_).
  Eigen::Vector2d car_ = Eigen::Vector2d::Zero();
  double plane_z0_ = 0.0;
  Eigen::Vector2d plane_g_ = Eigen::Vector2d::Zero();
  // The plane of the car's wheels on the profile: its height at the car and its gradient (ENU).
  double car_profile_ = 0.0;
  Eigen::Vector2d car_grad_ = Eigen::Vector2d::Zero();
};

}  // namespace lanemap::bev
