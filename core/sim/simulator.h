// Runs a simulated drive: samples the true trajectory into noisy poses, renders camera frames
// (JPEG + ground-truth labels) and LIDAR sweeps (VLP-16 packets), and hands every measurement, in
// time order, to a SensorSink. LCM-free: the sim tool's sink writes an LCM log, a test's sink
// checks values.
#pragma once

#include "core/camera/camera_model.h"
#include "core/geo/local_frame.h"
#include "core/lidar/velodyne.h"
#include "core/sim/camera_renderer.h"
#include "core/sim/drive.h"
#include "core/sim/lidar_scanner.h"
#include "core/sim/pose_noise.h"
#include "core/sim/world_builder.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace lanemap::sim {

struct PoseMeasurement {
  int64_t utime = 0;
  geo::LatLonAlt wgs84;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // vehicle -> ENU
  Eigen::Vector3d velocity_enu = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_rate = Eigen::Vector3d::Zero();           // vehicle frame
  double position_sigma_m = 0.0;
  double yaw_sigma_rad = 0.0;
  VehicleState truth;                                               // what really happened
};

struct CameraMeasurement {
  int64_t utime = 0;   // exposure time
  int64_t seq = 0;
  int width = 0, height = 0;
  std::vector<uint8_t> jpeg;        // the camera image
  std::vector<uint8_t> labels_png;  // ground-truth class image (sim::LabelClass), PNG
  int64_t ego_lanelet = -1;         // the lanelet the labels are relative to (VehicleState::label_lanelet)
};

struct LidarMeasurement {
  int64_t utime = 0;                 // first packet
  int64_t publish_utime = 0;         // end of the sweep: when a driver could publish it
  std::vector<lidar::Packet> packets;
  std::vector<int64_t> packet_utime; // time of each packet's first firing
};

class SensorSink {
 public:
  virtual ~SensorSink() = default;
  virtual void onPose(const PoseMeasurement& m) = 0;
  virtual void onCamera(const CameraMeasurement& m) = 0;
  virtual void onLidar(const LidarMeasurement& m) = 0;
};

struct SimulatorOptions {
  int64_t start_utime = 1767225600000000;  // 2026-01-01T00:00:00Z
  double pose_rate_hz = 100.0;
  double camera_rate_hz = 10.0;
  bool lidar = true;
  int jpeg_quality = 90;
  uint64_t seed = 1;
  PoseNoiseOptions pose_noise;
  // Threads that render camera frames and cast LIDAR sweeps ahead of the one being emitted
  // (0: one per core; 1: everything on the calling thread). The output is the same for any count:
  // every frame and sweep depends only on its time and the seed, and the packet encoder, the pose
  // noise and the sink run on the calling thread in time order.
  int threads = 0;
};

struct SimulatorCounts {
  int64_t poses = 0, camera_frames = 0, lidar_sweeps = 0, lidar_packets = 0;
};

class Simulator {
 public:
  Simulator(const World& world, const Trajectory& trajectory, const geo::LocalFrame& frame,
            const camera::CameraModel& camera, const RenderOptions& render,
            const std::optional<LidarScannerOptions>& lidar, const SimulatorOptions& options);

  // Emits everything of the drive to `sink` in time order; `progress(fraction)` now and then.
  SimulatorCounts run(SensorSink& sink, const std::function<void(double)>& progress = {});

 private:
  PoseMeasurement poseAt(double t, PoseNoise& noise, double dt) const;
  CameraMeasurement cameraAt(double t, int64_t seq) const;
  // Calls f with the world as a car in `lanelet` sees it: a world of several OSM levels from that
  // lanelet's level (a bridge over it is not on its ground), any other world as it is.
  template <typename F>
  auto seenFrom(int64_t lanelet, F&& f) const {
    if (!sim_world_) return f(world_);
    return f(WorldSeenFromLevel(*sim_world_, sim_world_->levelOf(lanelet)));
  }

  const World& world_;
  const SimWorld* sim_world_ = nullptr;  // world_, when it is the simulator's own
  const Trajectory& trajectory_;
  geo::LocalFrame frame_;
  CameraRenderer renderer_;
  std::optional<LidarScanner> scanner_;
  SimulatorOptions options_;
};

}  // namespace lanemap::sim
