// The simulator's roof LIDAR: a Velodyne VLP-16 spinning at `rpm` (600 = 10 Hz), ray-cast against a
// World with the vehicle moving during the sweep, encoded as real VLP-16 data packets.
//
// Timing: sequence i of a sweep starting at t0 fires at t0 + i * 55.296 us, laser j of it
// 2.304 us later; the azimuth advances at rpm * 6 deg/s, i.e. 0.19907 deg per sequence at 600 rpm
// (the "0.2 deg" of the datasheet), and a sweep holds floor(60 / rpm / 55.296 us) = 1808 sequences
// so consecutive sweeps (t0 += 60 / rpm) never overlap in time.
//
// Azimuth convention (as lidar/velodyne.h): Velodyne azimuth a is 0 straight ahead and grows
// CLOCKWISE seen from above. In the LIDAR body frame (x forward = azimuth 0, y left, z up) a laser
// at elevation e fires along (cos e cos a, -cos e sin a, sin e): azimuth 90 deg looks RIGHT (-y).
// The body frame sits in the vehicle frame at LidarScannerOptions::mount (config/vehicle.yaml
// lidar.mount); the vehicle pose for each firing sequence comes from the caller, so motion during a
// sweep is real (rolling-shutter-like skew, as on the car).
#pragma once

#include "core/lidar/velodyne.h"
#include "core/sim/raycast.h"
#include "core/sim/world.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace YAML { class Node; }
namespace lanemap::config { class YamlReader; }

namespace lanemap::sim {

struct LidarScannerOptions {
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();  // LIDAR body frame in the vehicle frame
  double rpm = 600.0;               // rotation speed
  double max_range_m = 100.0;       // no return beyond
  double min_range_m = 0.5;         // no return closer (blind zone)
  double range_noise_m = 0.02;      // standard deviation of Gaussian range noise
  double intensity_noise = 8.0;     // standard deviation of reflectivity noise, 0-255 units
  double start_azimuth_deg = 0.0;   // azimuth of a sweep's first sequence
  uint8_t product_id = 0x22;        // packet factory byte (VLP-16)
  RaycastOptions raycast;

  // From the `lidar` node of config/vehicle.yaml (keys model (VLP-16), rpm, max_range_m,
  // min_range_m, range_noise_m, intensity_noise, product_id optional; mount required). Throws
  // config::ConfigError (a std::runtime_error) naming the key, std::invalid_argument on a value
  // out of range.
  static LidarScannerOptions fromYaml(const YAML::Node& lidar_node);
  // The same from a config section, any `model` accepted (a vehicle file read whole); every error
  // is a config::ConfigError naming file and key.
  static LidarScannerOptions fromYaml(const config::YamlReader& r);
  static LidarScannerOptions fromYamlFile(const std::string& path, const std::string& key = "lidar");
};

// One simulated return (only lasers that hit something within range give one).
struct LidarReturn {
  double time_s = 0.0;          // firing time of this laser
  int sequence = 0;             // firing sequence index within the sweep
  int laser = 0;                // laser id in firing order (lidar::vlp16ElevationDeg)
  double azimuth_deg = 0.0;     // Velodyne azimuth of this laser's firing, [0, 360)
  double elevation_deg = 0.0;
  double range_m = 0.0;         // measured (noisy) range
  double true_range_m = 0.0;    // noise-free range of the ray-cast hit
  Eigen::Vector3d point_sensor = Eigen::Vector3d::Zero();  // measured point, LIDAR body frame
  Eigen::Vector3d point_enu = Eigen::Vector3d::Zero();     // noise-free hit, ENU
  uint8_t intensity = 0;
  bool is_obstacle = false;
  const Obstacle* obstacle = nullptr;
  GroundSample ground;          // when !is_obstacle
};

struct LidarSweep {
  double t0 = 0.0;                        // first firing
  double t_end = 0.0;                     // t0 + sequences * 55.296 us
  std::vector<lidar::Packet> packets;     // packets completed during this sweep
  std::vector<LidarReturn> returns;       // for tests and ground truth
};

// Vehicle pose (vehicle_to_enu) at time t (seconds, same clock as t0).
using PoseAtTime = std::function<Eigen::Isometry3d(double t)>;

class LidarScanner {
 public:
  // Throws std::invalid_argument on bad options (rpm <= 0, ranges not 0 < min < max, ...).
  explicit LidarScanner(const LidarScannerOptions& options);

  // Simulates one sweep starting at t0. `pose_at` is called once per firing sequence, from the
  // calling thread, in time order. The ray casting runs in parallel (cv::parallel_for_); the result
  // depends only on the inputs and `seed`. Packet timestamps are the microseconds past the hour of
  // t0-relative clock t (t mod 3600 s). The packet encoder persists across sweeps: a packet that is
  // not full at the end of a sweep is completed by the next one (24 sequences per packet, as on the
  // sensor), so a sweep returns 75 or 76 packets at 600 rpm.
  LidarSweep scan(const World& world, double t0, const PoseAtTime& pose_at, uint64_t seed);

  // scan() in two halves, for sweeps cast on several threads at once: cast() is the ray casting
  // (const: any number may run at a time; `pose_at` is called from the calling thread only),
  // encode() the packet encoder, which must see the sweeps in time order.
  // scan(w, t0, p, s) == encode(cast(w, t0, p, s)).
  struct Cast {
    double t0 = 0.0;
    std::vector<lidar::FiringSequence> sequences;
    std::vector<LidarReturn> returns;
  };
  Cast cast(const World& world, double t0, const PoseAtTime& pose_at, uint64_t seed) const;
  LidarSweep encode(Cast&& cast);

  int sequencesPerSweep() const { return sequences_per_sweep_; }
  double sweepPeriodS() const { return 60.0 / options_.rpm; }
  double azimuthStepDeg() const;    // azimuth advance per firing sequence
  int pendingSequences() const { return encoder_.pendingSequences(); }
  const LidarScannerOptions& options() const { return options_; }

 private:
  LidarScannerOptions options_;
  int sequences_per_sweep_;
  lidar::Vlp16PacketEncoder encoder_;
};

// Reflectivity (0-255, before noise) the simulated sensor reports for a surface / obstacle.
double surfaceIntensity(Surface s);
double obstacleIntensity(Obstacle::Kind k);

// Microseconds past the hour of time t (seconds), wrapped into [0, 3.6e9).
uint32_t usecPastHour(double t);

}  // namespace lanemap::sim
