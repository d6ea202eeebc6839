#include "core/bev/pose_buffer.h"

#include <algorithm>
#include <cmath>

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

PoseBuffer::Lookup PoseBuffer::lookup(int64_t utime, Eigen::Isometry3d* out, bool partial) const {
  if (poses_.empty()) return Lookup::kEmpty;
  if (utime > poses_.back().utime) return Lookup::kTooNew;
  if (utime < poses_.front().utime) return Lookup::kTooOld;
  if (smooth_us_ > 0 && !partial && static_cast<double>(poses_.back().utime) - static_cast<double>(utime) < smooth_us_) {
    return Lookup::kTooNew;  // the window is not complete yet
  }
  auto it = std::lower_bound(poses_.begin(), poses_.end(), utime,
                             [](const TimedPose& p, int64_t u) { return p.utime < u; });
  const TimedPose& b = *it;
  const TimedPose& a = it == poses_.begin() ? b : *(it - 1);
  const double span = static_cast<double>(b.utime) - static_cast<double>(a.utime);
  if (span > max_gap_us_) return Lookup::kGap;
  const double f = b.utime == a.utime ? 0.0 : (static_cast<double>(utime) - static_cast<double>(a.utime)) / span;
  if (!out) return Lookup::kOk;
  Eigen::Quaterniond q = a.orientation.slerp(f, b.orientation);
  Eigen::Vector3d p = (1.0 - f) * a.position + f * b.position;
  if (smooth_us_ > 0) {
    // Local linear fit over t +- smooth_us_: x(dt) = c0 + c1 dt, evaluated at dt = 0.
    const double t = static_cast<double>(utime);
    auto first = std::lower_bound(poses_.begin(), poses_.end(), t - smooth_us_,
                                  [](const TimedPose& s, double u) { return static_cast<double>(s.utime) < u; });
    double n = 0, st = 0, stt = 0;
    Eigen::Vector3d sp = Eigen::Vector3d::Zero(), stp = Eigen::Vector3d::Zero(), sr = Eigen::Vector3d::Zero(),
                    str = Eigen::Vector3d::Zero();
    for (auto s = first; s != poses_.end() && static_cast<double>(s->utime) <= t + smooth_us_; ++s) {
      const double dt = (static_cast<double>(s->utime) - t) * 1e-6;
      const Eigen::AngleAxisd r(q.conjugate() * s->orientation);  // about the interpolated orientation
      const Eigen::Vector3d rv = r.angle() * r.axis();  // angle in [0, pi]
      const Eigen::Vector3d rel = s->position - p;
      n += 1;
      st += dt;
      stt += dt * dt;
      sp += rel;
      stp += dt * rel;
      sr += rv;
      str += dt * rv;
    }
    const double det = n * stt - st * st;
    if (n >= 3 && det > 1e-12) {
      // c0 = (stt * sum(x) - st * sum(t x)) / det
      p += (stt * sp - st * stp) / det;
      const Eigen::Vector3d c = (stt * sr - st * str) / det;
      if (c.norm() > 1e-12) q = q * Eigen::Quaterniond(Eigen::AngleAxisd(c.norm(), c.normalized()));
    }
  }
  out->setIdentity();
  out->linear() = q.normalized().toRotationMatrix();
  out->translation() = p;
  return Lookup::kOk;
}

std::optional<Eigen::Isometry3d> PoseBuffer::at(int64_t utime, bool partial) const {
  Eigen::Isometry3d t;
  if (lookup(utime, &t, partial) != Lookup::kOk) return std::nullopt;
  return t;
}

}  // namespace lanemap::bev
