// POSE (lanemap::pose_t, WGS84 + vehicle->ENU quaternion) in the ENU frame of a map: the one
// conversion the road tracker, the BEV builder, the offline runner and the replay tests share.
//
//   const EnuPose p = toEnuPose(msg, skeleton.frame());
//   builder.addPose(toTimedPose(p));    // bev: NaN position when the pose is invalid (counted there)
//   tracker.update(toPoseInput(p));     // tracking: valid = false when the pose is invalid
#pragma once

#include "core/bev/pose_buffer.h"
#include "core/geo/local_frame.h"
#include "core/tracking/road_tracker.h"
#include "lanemap/pose_t.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <limits>

namespace lanemap {

struct EnuPose {
  int64_t utime = 0;
  // A fix: status is not STATUS_INVALID and latitude/longitude are finite.
  bool valid = false;
  // ENU metres in the frame; NaN when !valid.
  Eigen::Vector3d position = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  // Vehicle -> ENU, as the message gives it (w, x, y, z).
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  // Of the vehicle x axis in ENU: radians from east, counter-clockwise (the rotation's first column).
  double heading = 0.0;
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // ENU m/s (velocity_enu east, north)
};

inline EnuPose toEnuPose(const pose_t& m, const geo::LocalFrame& frame) {
  EnuPose p;
  p.utime = m.utime;
  p.valid = m.status != pose_t::STATUS_INVALID && std::isfinite(m.latitude) && std::isfinite(m.longitude);
  if (p.valid) p.position = frame.toEnu(m.latitude, m.longitude, m.altitude);
  const double w = m.orientation[0], x = m.orientation[1], y = m.orientation[2], z = m.orientation[3];
  p.orientation = Eigen::Quaterniond(w, x, y, z);
  // R(1,0) and R(0,0) of the unit quaternion's rotation matrix.
  p.heading = std::atan2(2.0 * (x * y + w * z), 1.0 - 2.0 * (y * y + z * z));
  p.velocity = Eigen::Vector2d(m.velocity_enu[0], m.velocity_enu[1]);
  return p;
}

// For core/bev: an invalid pose keeps its NaN position, which BevBuilder::addPose counts as invalid.
inline bev::TimedPose toTimedPose(const EnuPose& p) {
  bev::TimedPose t;
  t.utime = p.utime;
  t.position = p.position;
  t.orientation = p.orientation;
  return t;
}

// For core/tracking: position, heading and velocity only when the pose is valid.
inline tracking::PoseInput toPoseInput(const EnuPose& p) {
  tracking::PoseInput in;
  in.utime = p.utime;
  in.valid = p.valid;
  if (p.valid) {
    in.position = p.position.head<2>();
    in.heading = p.heading;
    in.velocity = p.velocity;
  }
  return in;
}

}  // namespace lanemap
