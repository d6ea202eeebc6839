#include "core/bev/pose_buffer.h"

#include <algorithm>

namespace lanemap::bev {

bool PoseBuffer::add(const TimedPose& p) {
  if (!p.position.allFinite() || !p.orientation.coeffs().allFinite() || p.orientation.norm() < 1e-6) return false;
  if (!poses_.empty() && p.utime <= poses_.back().utime) return false;
  poses_.push_back(p);
  poses_.back().orientation.normalize();
  // Time differences in double here and below: hostile utimes (INT64_MIN, INT64_MAX) must not
  // overflow int64 (fuzz/harness/lcm_decode.cc, pose_t).
  while (poses_.size() > 2 && static_cast<double>(poses_.back().utime) - static_cast<double>(poses_.front().utime) > keep_us_) {
    poses_.pop_front();
  }
  return true;
}

PoseBuffer::Lookup PoseBuffer::lookup(int64_t utime, Eigen::Isometry3d* out) const {
  if (poses_.empty()) return Lookup::kEmpty;
  if (utime > poses_.back().utime) return Lookup::kTooNew;
  if (utime < poses_.front().utime) return Lookup::kTooOld;
  auto it = std::lower_bound(poses_.begin(), poses_.end(), utime,
                             [](const TimedPose& p, int64_t u) { return p.utime < u; });
  const TimedPose& b = *it;
  const TimedPose& a = it == poses_.begin() ? b : *(it - 1);
  const double span = static_cast<double>(b.utime) - static_cast<double>(a.utime);
  if (span > max_gap_us_) return Lookup::kGap;
  const double f = b.utime == a.utime ? 0.0 : (static_cast<double>(utime) - static_cast<double>(a.utime)) / span;
  if (out) {
    out->setIdentity();
    out->linear() = a.orientation.slerp(f, b.orientation).toRotationMatrix();
    out->translation() = (1.0 - f) * a.position + f * b.position;
  }
  return Lookup::kOk;
}

std::optional<Eigen::Isometry3d> PoseBuffer::at(int64_t utime) const {
  Eigen::Isometry3d t;
  if (lookup(utime, &t) != Lookup::kOk) return std::nullopt;
  return t;
}

}  // namespace lanemap::bev
