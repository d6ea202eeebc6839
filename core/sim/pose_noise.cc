#include "core/sim/pose_noise.h"

#include "core/config/yaml_reader.h"

#include <cmath>

namespace lanemap::sim {

PoseNoiseOptions PoseNoiseOptions::fromYaml(const YAML::Node& n) {
  const config::YamlReader r(n);
  PoseNoiseOptions o = fromYaml(r);
  r.finish();
  return o;
}

PoseNoiseOptions PoseNoiseOptions::fromYaml(const config::YamlReader& r) {
  PoseNoiseOptions o;
  for (const auto& [key, v] : {std::pair<const char*, double*>{"position_sigma_m", &o.position_sigma_m},
                               {"altitude_sigma_m", &o.altitude_sigma_m},
                               {"bias_sigma_m", &o.bias_sigma_m},
                               {"bias_time_constant_s", &o.bias_time_constant_s},
                               {"yaw_sigma_deg", &o.yaw_sigma_deg},
                               {"attitude_sigma_deg", &o.attitude_sigma_deg},
                               {"campaign_offset_sigma_m", &o.drive_offset_sigma_m},
                               {"campaign_heading_sigma_deg", &o.drive_heading_sigma_deg}}) {
    if (r.read(key, *v) && !(*v >= 0.0)) r.fail(key, "must be >= 0");
  }
  return o;
}

DriveOffset driveOffset(const PoseNoiseOptions& o, uint64_t seed) {
  // Its own generator, so that drives without an offset keep every other draw as before.
  std::mt19937_64 rng(seed * 15485863 + 11);
  std::normal_distribution<double> unit(0.0, 1.0);
  DriveOffset d;
  const double e = unit(rng), n = unit(rng), h = unit(rng);
  d.position = Eigen::Vector2d(e, n) * o.drive_offset_sigma_m;
  d.yaw_rad = h * o.drive_heading_sigma_deg * M_PI / 180.0;
  return d;
}

PoseNoise::PoseNoise(const PoseNoiseOptions& options, uint64_t seed)
    : options_(options), rng_(seed * 104729 + 3), offset_(driveOffset(options, seed)) {
  bias_ = Eigen::Vector2d(unit_(rng_), unit_(rng_)) * options_.bias_sigma_m;
}

PoseError PoseNoise::next(double dt) {
  // Gauss-Markov: b <- a b + sqrt(1 - a^2) sigma w keeps the bias's std at bias_sigma_m.
  const double a = options_.bias_time_constant_s > 0 ? std::exp(-dt / options_.bias_time_constant_s) : 0.0;
  const double q = std::sqrt(std::max(0.0, 1.0 - a * a)) * options_.bias_sigma_m;
  bias_ = a * bias_ + q * Eigen::Vector2d(unit_(rng_), unit_(rng_));
  PoseError e;
  e.position.x() = offset_.position.x() + bias_.x() + options_.position_sigma_m * unit_(rng_);
  e.position.y() = offset_.position.y() + bias_.y() + options_.position_sigma_m * unit_(rng_);
  e.position.z() = options_.altitude_sigma_m * unit_(rng_);
  const double deg = M_PI / 180.0;
  e.rpy = Eigen::Vector3d(options_.attitude_sigma_deg * unit_(rng_), options_.attitude_sigma_deg * unit_(rng_),
                          options_.yaw_sigma_deg * unit_(rng_)) * deg;
  e.rpy.z() += offset_.yaw_rad;
  return e;
}

}  // namespace lanemap::sim
