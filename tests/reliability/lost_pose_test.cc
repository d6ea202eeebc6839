// A lost POSE message and the BEV builder's pose of a frame (issue 18): without smoothing the pose
// of a frame whose own pose sample was lost is interpolated from its neighbours, so it moves by
// the white noise of one sample (centimetres, a tenth of a degree: on the test drive that was
// enough to flip a lane, docs/robustness.md). With PoseBuffer's smoothing (smooth_s) the pose is
// the local linear fit of the samples around it: closer to the truth, and a lost sample barely
// moves it; the fit is linear, so a gap does not bias a moving car's position.
#include "core/bev/pose_buffer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using lanemap::bev::PoseBuffer;
using lanemap::bev::TimedPose;

constexpr int64_t kT0 = 1'767'225'600'000'000;
constexpr double kDeg = M_PI / 180.0;

// The car at time t (s): 11 m/s on a circle of 55 m radius (0.2 rad/s), level.
TimedPose truthAt(double t) {
  TimedPose p;
  p.utime = kT0 + static_cast<int64_t>(std::llround(t * 1e6));
  const double yaw = 0.2 * t, r = 55.0;
  p.position = Eigen::Vector3d(r * std::sin(yaw), r * (1.0 - std::cos(yaw)), 0.0);
  p.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return p;
}

// 100 Hz poses with the simulator's white noise (3 cm, 0.1 deg yaw, 0.05 deg roll and pitch).
std::vector<TimedPose> noisyPoses(double seconds, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<TimedPose> out;
  for (int i = 0; i <= static_cast<int>(seconds * 100); ++i) {
    TimedPose p = truthAt(i * 0.01);
    p.position += Eigen::Vector3d(0.03 * n(rng), 0.03 * n(rng), 0.05 * n(rng));
    p.orientation = p.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * kDeg * n(rng), Eigen::Vector3d::UnitZ())) *
                    Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * kDeg * n(rng), Eigen::Vector3d::UnitY())) *
                    Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * kDeg * n(rng), Eigen::Vector3d::UnitX()));
    out.push_back(p);
  }
  return out;
}

double angleDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() / kDeg;
}

struct Figures {
  double moved_cm = 0, moved_deg = 0;      // mean change of a frame's pose when its sample is lost
  double error_cm = 0, error_deg = 0;      // RMS error against the truth, every sample present
  double along_bias_cm = 0;                // mean along-track error with the sample lost
};

// Frames every 0.2 s (on a pose sample, as the simulator's camera), each with and without its
// own pose sample (and the one after it: a 30 ms gap).
Figures measure(double smooth_s) {
  const auto poses = noisyPoses(21.0, 7);
  PoseBuffer all(30.0, 0.25, smooth_s);
  for (const auto& p : poses) EXPECT_TRUE(all.add(p));
  Figures f;
  int frames = 0;
  for (int k = 5; k < 100; ++k) {
    const size_t i = static_cast<size_t>(k * 20);
    PoseBuffer lost(30.0, 0.25, smooth_s);
    for (size_t j = 0; j < poses.size(); ++j) {
      if (j != i && j != i + 1) lost.add(poses[j]);
    }
    Eigen::Isometry3d a, b;
    EXPECT_EQ(all.lookup(poses[i].utime, &a), PoseBuffer::Lookup::kOk);
    EXPECT_EQ(lost.lookup(poses[i].utime, &b), PoseBuffer::Lookup::kOk);
    const TimedPose t = truthAt(i * 0.01);
    f.moved_cm += (a.translation() - b.translation()).norm() * 100;
    f.moved_deg += angleDeg(a, b);
    f.error_cm += (a.translation() - t.position).head<2>().squaredNorm() * 1e4;
    f.error_deg += std::pow(angleDeg(a, Eigen::Isometry3d(t.orientation)), 2);
    const Eigen::Vector3d along = t.orientation * Eigen::Vector3d::UnitX();
    f.along_bias_cm += (b.translation() - t.position).dot(along) * 100;
    ++frames;
  }
  f.moved_cm /= frames;
  f.moved_deg /= frames;
  f.error_cm = std::sqrt(f.error_cm / frames);
  f.error_deg = std::sqrt(f.error_deg / frames);
  f.along_bias_cm /= frames;
  return f;
}

TEST(LostPose, SmoothingKeepsAFramesPoseWhenItsOwnSampleIsLost) {
  const Figures raw = measure(0.0), smooth = measure(0.05);
  std::printf("lost sample moves a frame's pose: %.2f cm %.3f deg (interpolation), %.2f cm %.3f deg (smoothed +-50 ms)\n",
              raw.moved_cm, raw.moved_deg, smooth.moved_cm, smooth.moved_deg);
  std::printf("RMS error against the truth: %.2f cm %.3f deg (interpolation), %.2f cm %.3f deg (smoothed); along-track bias "
              "with the gap %.2f cm / %.2f cm\n",
              raw.error_cm, raw.error_deg, smooth.error_cm, smooth.error_deg, raw.along_bias_cm, smooth.along_bias_cm);
  // Interpolation: the lost sample's white noise (3 cm per axis, ~0.12 deg) moves the pose.
  EXPECT_GT(raw.moved_cm, 2.0);
  EXPECT_GT(raw.moved_deg, 0.05);
  // Smoothed over 11 samples: a third of that at most, and closer to the truth.
  EXPECT_LT(smooth.moved_cm, raw.moved_cm / 3);
  EXPECT_LT(smooth.moved_deg, raw.moved_deg / 3);
  EXPECT_LT(smooth.error_cm, raw.error_cm / 2);
  EXPECT_LT(smooth.error_deg, raw.error_deg / 2);
  // A linear fit: the 30 ms gap does not shift the car along its track (a mean would: 1.2 cm at 11 m/s).
  EXPECT_LT(std::abs(smooth.along_bias_cm), 0.5);
}

TEST(LostPose, ASmoothedLookupWaitsForItsWindowUnlessPartial) {
  PoseBuffer b(10.0, 0.25, 0.05);
  const auto poses = noisyPoses(1.0, 3);
  for (const auto& p : poses) b.add(p);
  Eigen::Isometry3d t;
  const int64_t last = poses.back().utime;
  EXPECT_EQ(b.lookup(last - 60'000, &t), PoseBuffer::Lookup::kOk);
  EXPECT_EQ(b.lookup(last - 40'000, &t), PoseBuffer::Lookup::kTooNew) << "the poses do not reach 50 ms past it yet";
  EXPECT_EQ(b.lookup(last - 40'000, &t, true), PoseBuffer::Lookup::kOk) << "the end of the input: what there is";
  EXPECT_EQ(b.leadUs(), 50'000);
  EXPECT_EQ(PoseBuffer(10.0, 0.25).leadUs(), 0);
}

}  // namespace
