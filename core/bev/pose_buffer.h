// A short history of vehicle poses (vehicle -> ENU) and their interpolation at any utime inside it:
// the camera frame and every LIDAR packet get the pose of their own time (METHOD.md section 3's
// "synchronised" poses), not the nearest one (at 11 m/s, 10 ms is 11 cm).
// Position: linear; orientation: slerp. Poses must come in utime order; older ones beyond
// `keep_s` are dropped, so the buffer stays small on a long drive.
//
// Smoothing (smooth_s > 0, off by default): the pose at t is the local linear least-squares fit
// of the poses within t +- smooth_s (positions, and orientations as rotation vectors about the
// interpolated one), evaluated at t. A linear fit, not a mean, so a missing pose (a message lost)
// does not shift the window's time and bias a moving car's position. White noise of the pose
// samples shrinks by about sqrt(samples in the window), and the pose of a frame no longer hangs on
// whether the one sample at its time arrived. A lookup then waits (kTooNew) until the poses reach
// t + smooth_s, unless `partial` (end of input).
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

  explicit PoseBuffer(double keep_s = 10.0, double max_gap_s = 0.25, double smooth_s = 0.0)
      : keep_us_(keep_s * 1e6), max_gap_us_(max_gap_s * 1e6), smooth_us_(smooth_s * 1e6) {}

  // Adds a pose. Returns false (and keeps nothing) when it is not newer than the last one or not
  // finite.
  bool add(const TimedPose& pose);
  // The interpolated pose at `utime`: kTooNew when utime is after the newest pose (wait for more),
  // kTooOld before the oldest kept one, kGap when the two poses around it are more than max_gap_s
  // apart.
  Lookup lookup(int64_t utime, Eigen::Isometry3d* vehicle_to_enu, bool partial = false) const;
  std::optional<Eigen::Isometry3d> at(int64_t utime, bool partial = false) const;
  // How far past a time the poses must reach for its lookup (the smoothing window's half).
  int64_t leadUs() const { return static_cast<int64_t>(smooth_us_); }

  void clear() { poses_.clear(); }  // a restarted stream (core/geo/time_order.h)
  bool empty() const { return poses_.empty(); }
  size_t size() const { return poses_.size(); }
  int64_t newest() const { return poses_.empty() ? 0 : poses_.back().utime; }
  int64_t oldest() const { return poses_.empty() ? 0 : poses_.front().utime; }

 private:
  double keep_us_, max_gap_us_, smooth_us_;
  std::deque<TimedPose> poses_;
};

}  // namespace lanemap::bev
