#include "core/sim/simulator.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <variant>

namespace lanemap::sim {
namespace {

int64_t toUtime(int64_t start, double t) { return start + static_cast<int64_t>(std::llround(t * 1e6)); }

}  // namespace

Simulator::Simulator(const World& world, const Trajectory& trajectory, const geo::LocalFrame& frame,
                     const camera::CameraModel& camera, const RenderOptions& render,
                     const std::optional<LidarScannerOptions>& lidar, const SimulatorOptions& options)
    : world_(world), trajectory_(trajectory), frame_(frame), renderer_(camera, render), options_(options) {
  if (lidar) scanner_.emplace(*lidar);
}

PoseMeasurement Simulator::poseAt(double t, PoseNoise& noise, double dt) const {
  PoseMeasurement m;
  m.truth = trajectory_.at(t);
  m.utime = toUtime(options_.start_utime, t);
  const PoseError e = noise.next(dt);
  const Eigen::Vector3d p = m.truth.vehicle_to_enu.translation() + e.position;
  m.wgs84 = frame_.toWgs84(p);
  const Eigen::Matrix3d err = (Eigen::AngleAxisd(e.rpy.z(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(e.rpy.y(), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(e.rpy.x(), Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
  m.orientation = Eigen::Quaterniond(err * m.truth.vehicle_to_enu.linear()).normalized();
  m.velocity_enu = m.truth.vehicle_to_enu.linear().col(0) * m.truth.speed;
  m.angular_rate = Eigen::Vector3d(0.0, 0.0, m.truth.yaw_rate);
  const auto& o = noise.options();
  m.position_sigma_m = std::hypot(o.position_sigma_m, o.bias_sigma_m);
  m.yaw_sigma_rad = o.yaw_sigma_deg * M_PI / 180.0;
  return m;
}

CameraMeasurement Simulator::cameraAt(double t, int64_t seq) const {
  const VehicleState st = trajectory_.at(t);
  const RenderedFrame f = renderer_.render(world_, st.vehicle_to_enu, st.lanelet,
                                           options_.seed * 1000003ULL + static_cast<uint64_t>(seq));
  CameraMeasurement m;
  m.utime = toUtime(options_.start_utime, t);
  m.seq = seq;
  m.width = f.rgb.cols;
  m.height = f.rgb.rows;
  m.ego_lanelet = st.lanelet;
  cv::imencode(".jpg", f.rgb, m.jpeg, {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality});
  cv::imencode(".png", f.labels, m.labels_png, {cv::IMWRITE_PNG_COMPRESSION, 3});
  return m;
}

SimulatorCounts Simulator::run(SensorSink& sink, const std::function<void(double)>& progress) {
  SimulatorCounts counts;
  PoseNoise noise(options_.pose_noise, options_.seed);
  const double T = trajectory_.duration();
  const double pose_dt = 1.0 / options_.pose_rate_hz;
  const double cam_dt = 1.0 / options_.camera_rate_hz;
  const double sweep_dt = scanner_ ? scanner_->sweepPeriodS() : 0.0;
  const double t0_abs = static_cast<double>(options_.start_utime) * 1e-6;  // for LIDAR clock
  const int64_t hour_us = 3600LL * 1000000LL;
  const int64_t hour_base = options_.start_utime / hour_us * hour_us;

  // Each sensor keeps its own schedule; the earliest next measurement is emitted first, so the
  // sink sees time order. A LIDAR sweep is emitted when it is complete, as a driver publishes it.
  int64_t pose_i = 0, cam_i = 0, sweep_i = 0;
  int64_t last_packet_utime = 0;
  double last_progress = -1.0;
  for (;;) {
    const double tp = pose_i * pose_dt;
    const double tc = cam_i * cam_dt;
    const double ts = scanner_ ? (sweep_i + 1) * sweep_dt : 1e300;  // end of the sweep
    const double t = std::min({tp, tc, ts});
    if (t > T) break;
    if (t == tp) {
      sink.onPose(poseAt(tp, noise, pose_dt));
      ++pose_i;
      ++counts.poses;
    } else if (t == tc) {
      sink.onCamera(cameraAt(tc, cam_i));
      ++cam_i;
      ++counts.camera_frames;
    } else {
      const LidarSweep sweep = scanner_->scan(
          world_, t0_abs + sweep_i * sweep_dt,
          [this, t0_abs](double t_abs) { return trajectory_.at(t_abs - t0_abs).vehicle_to_enu; },
          options_.seed * 7777ULL + static_cast<uint64_t>(sweep_i));
      ++sweep_i;
      if (!sweep.packets.empty()) {
        LidarMeasurement m;
        m.packets = sweep.packets;
        for (const auto& pk : sweep.packets) {
          const uint32_t usec = static_cast<uint32_t>(pk[lidar::kTimestampOffset]) |
                                static_cast<uint32_t>(pk[lidar::kTimestampOffset + 1]) << 8 |
                                static_cast<uint32_t>(pk[lidar::kTimestampOffset + 2]) << 16 |
                                static_cast<uint32_t>(pk[lidar::kTimestampOffset + 3]) << 24;
          int64_t u = hour_base + usec;
          while (u < last_packet_utime - hour_us / 2) u += hour_us;  // the hour rolled over
          m.packet_utime.push_back(u);
          last_packet_utime = u;
        }
        m.utime = m.packet_utime.front();
        m.publish_utime = toUtime(options_.start_utime, ts);
        counts.lidar_packets += static_cast<int64_t>(m.packets.size());
        ++counts.lidar_sweeps;
        sink.onLidar(m);
      }
    }
    if (progress && t - last_progress >= 1.0) {
      progress(T > 0 ? t / T : 1.0);
      last_progress = t;
    }
  }
  if (progress) progress(1.0);
  return counts;
}

}  // namespace lanemap::sim
