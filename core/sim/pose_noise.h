// GNSS/INS-like pose errors for the simulator: white noise plus a slowly wandering bias
// (a first-order Gauss-Markov process), seeded and deterministic.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <cstdint>
#include <random>

namespace lanemap::config { class YamlReader; }

namespace lanemap::sim {

struct PoseNoiseOptions {
  double position_sigma_m = 0.03;     // white noise per axis, horizontal
  double altitude_sigma_m = 0.05;
  double bias_sigma_m = 0.10;         // steady-state std of the wandering horizontal bias
  double bias_time_constant_s = 30.0;
  double yaw_sigma_deg = 0.1;
  double attitude_sigma_deg = 0.05;   // roll and pitch
  // A drive's own constant error (its GNSS/INS solution's offset, the same for the whole drive,
  // different between drives), drawn once per seed: horizontal sigma per axis and heading sigma.
  // The yaml keys are campaign_offset_sigma_m / campaign_heading_sigma_deg; lanemap-sim applies
  // them to the drives of a campaign (--world-seed) only, so a single drive defines its own frame.
  double drive_offset_sigma_m = 0.0;
  double drive_heading_sigma_deg = 0.0;
  static PoseNoiseOptions fromYaml(const YAML::Node& node);  // missing keys keep defaults
  // The same from a config section (config/sim_drive.yaml `pose_noise:`); the caller's finish()
  // refuses unknown keys. Errors are config::ConfigError naming the file and key.
  static PoseNoiseOptions fromYaml(const config::YamlReader& r);
};

// A drive's constant error: east, north (m) and heading (rad), a function of the options and seed.
struct DriveOffset {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
};
DriveOffset driveOffset(const PoseNoiseOptions& options, uint64_t seed);

struct PoseError {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // ENU metres
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();       // radians
};

class PoseNoise {
 public:
  PoseNoise(const PoseNoiseOptions& options, uint64_t seed);
  // The error of the next pose, dt seconds after the previous one.
  PoseError next(double dt);
  const PoseNoiseOptions& options() const { return options_; }

 private:
  PoseNoiseOptions options_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> unit_{0.0, 1.0};
  Eigen::Vector2d bias_ = Eigen::Vector2d::Zero();
  DriveOffset offset_;
};

}  // namespace lanemap::sim
