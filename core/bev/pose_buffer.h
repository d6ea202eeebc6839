// A short history of vehicle poses (vehicle -> ENU) and their interpolation at any utime inside it:
// the camera frame and every LIDAR packet get the pose of their own time (METHOD.md section 3's
// "synchronised" poses), not the nearest one (at 11 m/s, 10 ms is 11 cm).
// Position: linear; orientation: slerp. Poses must come in utime order; older ones beyond
// `keep_s` are dropped, so the buffer stays small on a long drive.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <deque>
#include <optional>

namespace lanemap::bev {

struct TimedPose {
  int64_t utime = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();           // ENU
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // vehicle -> ENU
};

class PoseBuffer {
 public:
  enum class Lookup { kOk, kTooNew, kTooOld, kGap, kEmpty };

  explicit PoseBuffer(double keep_s = 10.0, double max_gap_s = 0.25) : keep_us_(keep_s * 1e6), max_gap_us_(max_gap_s * 1e6) {}

  // Adds a pose. Returns false (and keeps nothing) when it is not newer than the last one or not
  // finite.
  bool add(const TimedPose& pose);
  // The interpolated pose at `utime`: kTooNew when utime is after the newest pose (wait for more),
  // kTooOld before the oldest kept one, kGap when the two poses around it are more than max_gap_s
  // apart.
  Lookup lookup(int64_t utime, Eigen::Isometry3d* vehicle_to_enu) const;
  std::optional<Eigen::Isometry3d> at(int64_t utime) const;

  void clear() { poses_.clear(); }  // a restarted stream (core/geo/time_order.h)
  bool empty() const { return poses_.empty(); }
  size_t size() const { return poses_.size(); }
  int64_t newest() const { return poses_.empty() ? 0 : poses_.back().utime; }
  int64_t oldest() const { return poses_.empty() ? 0 : poses_.front().utime; }

 private:
  double keep_us_, max_gap_us_;
  std::deque<TimedPose> poses_;
};

}  // namespace lanemap::bev
