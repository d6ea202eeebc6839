// VLP-16 simulation: per-sequence poses, ray casting, noise, intensities, packet encoding.
#include "core/sim/lidar_scanner.h"

#include "core/camera/camera_model.h"  // mountFromYaml
#include "core/config/yaml_reader.h"

#include <opencv2/core/utility.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace lanemap::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

uint64_t mix64(uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

const LidarScannerOptions& validate(const LidarScannerOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("LidarScannerOptions: " + what); };
  if (!(o.rpm >= 60.0 && o.rpm <= 1500.0)) fail("rpm must be in [60, 1500], got " + std::to_string(o.rpm));
  if (!(o.min_range_m >= 0.0 && o.min_range_m < o.max_range_m))
    fail("need 0 <= min_range_m < max_range_m");
  if (!(o.max_range_m <= 131.0)) fail("max_range_m beyond what a VLP-16 packet can encode (131 m)");
  if (!(o.range_noise_m >= 0.0) || !(o.intensity_noise >= 0.0)) fail("noise must be >= 0");
  return o;
}

double wrapDeg(double a) {
  a = std::fmod(a, 360.0);
  return a < 0.0 ? a + 360.0 : a;
}

// Unit direction of a laser in the LIDAR body frame (x forward, y left, z up), Velodyne azimuth.
Eigen::Vector3d laserDirection(double azimuth_deg, double elevation_deg) {
  const double a = azimuth_deg * kDegToRad, e = elevation_deg * kDegToRad;
  return {std::cos(e) * std::cos(a), -std::cos(e) * std::sin(a), std::sin(e)};
}

}  // namespace

namespace {

// The keys of a `lidar:` section, unchecked. The simulator (the YAML::Node form) simulates a VLP-16
// only; a vehicle file read whole (core/config/vehicle_config.h) may name another model.
LidarScannerOptions readLidarKeys(const config::YamlReader& r, bool vlp16_only) {
  if (!r.present()) r.failHere("the lidar {model, rpm, ..., mount} is required");
  LidarScannerOptions o;
  const std::string model = r.get<std::string>("model", "VLP-16");
  if (vlp16_only && model != "VLP-16") r.fail("model", "'" + model + "' is not simulated (only VLP-16)");
  r.read("rpm", o.rpm);
  r.read("max_range_m", o.max_range_m);
  r.read("min_range_m", o.min_range_m);
  r.read("range_noise_m", o.range_noise_m);
  r.read("intensity_noise", o.intensity_noise);
  int product = o.product_id;
  if (r.read("product_id", product) && (product < 0 || product > 255)) r.fail("product_id", "must be a byte (0-255)");
  o.product_id = static_cast<uint8_t>(product);
  o.mount = camera::mountFromYaml(r.section("mount"));
  return o;
}

}  // namespace

LidarScannerOptions LidarScannerOptions::fromYaml(const YAML::Node& node) {
  const config::YamlReader r(node);
  LidarScannerOptions o = readLidarKeys(r, true);
  r.finish();
  return validate(o);  // std::invalid_argument on a bad value
}

LidarScannerOptions LidarScannerOptions::fromYaml(const config::YamlReader& r) {
  LidarScannerOptions o = readLidarKeys(r, false);
  try {
    validate(o);
  } catch (const std::invalid_argument& e) {
    r.failHere(e.what());
  }
  return o;
}

LidarScannerOptions LidarScannerOptions::fromYamlFile(const std::string& path, const std::string& key) {
  const auto root = config::YamlReader::loadFile(path);
  if (!root.has(key)) root.fail(key, "is required");
  const auto section = root.section(key);
  LidarScannerOptions o = fromYaml(section);
  section.finish();
  return o;
}

double surfaceIntensity(Surface s) {
  switch (s) {
    case Surface::kDashedPaint:
    case Surface::kSolidPaint:
    case Surface::kCrosswalkPaint:
    case Surface::kStopLinePaint: return 200.0;  // retro-reflective paint
    case Surface::kCurb: return 45.0;
    case Surface::kSidewalk: return 35.0;
    case Surface::kOffRoad: return 28.0;
    case Surface::kBikeLane: return 24.0;
    case Surface::kAsphalt:
    case Surface::kIntersection:
    case Surface::kParking:
    default: return 20.0;
  }
}

double obstacleIntensity(Obstacle::Kind k) { return k == Obstacle::Kind::kParkedCar ? 60.0 : 40.0; }

uint32_t usecPastHour(double t) {
  constexpr int64_t kHourUs = 3600LL * 1000000LL;
  int64_t us = std::llround(t * 1e6) % kHourUs;
  if (us < 0) us += kHourUs;
  return static_cast<uint32_t>(us);
}

LidarScanner::LidarScanner(const LidarScannerOptions& options)
    : options_(validate(options)),
      sequences_per_sweep_(static_cast<int>(std::floor(60.0 / options.rpm / (lidar::kVlp16SequenceUs * 1e-6)))),
      encoder_(options.product_id) {}

double LidarScanner::azimuthStepDeg() const {
  return options_.rpm * 6.0 * lidar::kVlp16SequenceUs * 1e-6;
}

LidarSweep LidarScanner::scan(const World& world, double t0, const PoseAtTime& pose_at, uint64_t seed) {
  return encode(cast(world, t0, pose_at, seed));
}

LidarScanner::Cast LidarScanner::cast(const World& world, double t0, const PoseAtTime& pose_at, uint64_t seed) const {
  const int n = sequences_per_sweep_;
  const double seq_s = lidar::kVlp16SequenceUs * 1e-6, firing_s = lidar::kVlp16FiringUs * 1e-6;
  const double deg_per_s = options_.rpm * 6.0;

  // Sensor pose (LIDAR body -> ENU) for every sequence, asked serially (pose_at need not be
  // thread-safe).
  std::vector<Eigen::Isometry3d> sensor_to_enu(n);
  for (int i = 0; i < n; ++i) sensor_to_enu[i] = pose_at(t0 + i * seq_s) * options_.mount;

  // The obstacles around the sensor, binned by azimuth once for the sweep; the sensor moves by at
  // most `slack` metres from its first position during it.
  double slack = 0.0;
  for (const auto& p : sensor_to_enu) slack = std::max(slack, (p.translation() - sensor_to_enu[0].translation()).norm());
  const ObstacleFan fan(world, sensor_to_enu[0].translation(), options_.max_range_m, slack + 0.01);

  std::array<double, lidar::kVlp16Lasers> elevation{};
  for (int j = 0; j < lidar::kVlp16Lasers; ++j) elevation[j] = lidar::vlp16ElevationDeg(j);

  std::vector<lidar::FiringSequence> sequences(n);
  std::vector<std::array<LidarReturn, lidar::kVlp16Lasers>> rays(n);
  std::vector<std::array<bool, lidar::kVlp16Lasers>> valid(n);

  cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      std::mt19937_64 rng(mix64(seed ^ mix64(static_cast<uint64_t>(i) + 1)));
      std::normal_distribution<double> gauss(0.0, 1.0);
      const double seq_azimuth = options_.start_azimuth_deg + deg_per_s * i * seq_s;
      lidar::FiringSequence& seq = sequences[i];
      seq.azimuth_deg = wrapDeg(seq_azimuth);
      const Eigen::Isometry3d& pose = sensor_to_enu[i];
      const Eigen::Vector3d origin = pose.translation();
      for (int j = 0; j < lidar::kVlp16Lasers; ++j) {
        // Laser j fires j * 2.304 us after laser 0, the head having turned on by then.
        const double azimuth = wrapDeg(seq_azimuth + deg_per_s * j * firing_s);
        const Eigen::Vector3d dir_body = laserDirection(azimuth, elevation[j]);
        const RayHit hit = raycast(world, origin, pose.linear() * dir_body, options_.max_range_m, fan,
                                   options_.raycast);
        const double noise = options_.range_noise_m * gauss(rng);
        const double inten_noise = options_.intensity_noise * gauss(rng);
        valid[i][j] = false;
        seq.distance_m[j] = 0.0f;
        seq.intensity[j] = 0;
        if (!hit.hit) continue;
        const double measured = hit.range + noise;
        if (measured < options_.min_range_m || measured > options_.max_range_m) continue;
        const double base = hit.is_obstacle ? obstacleIntensity(hit.obstacle->kind)
                                            : surfaceIntensity(hit.ground.surface);
        const auto intensity = static_cast<uint8_t>(std::clamp(std::lround(base + inten_noise), 0L, 255L));
        seq.distance_m[j] = static_cast<float>(measured);
        seq.intensity[j] = intensity;

        LidarReturn& r = rays[i][j];
        r.time_s = t0 + i * seq_s + j * firing_s;
        r.sequence = i;
        r.laser = j;
        r.azimuth_deg = azimuth;
        r.elevation_deg = elevation[j];
        r.range_m = measured;
        r.true_range_m = hit.range;
        r.point_sensor = measured * dir_body;
        r.point_enu = hit.point;
        r.intensity = intensity;
        r.is_obstacle = hit.is_obstacle;
        r.obstacle = hit.obstacle;
        r.ground = hit.ground;
        valid[i][j] = true;
      }
    }
  });

  Cast out;
  out.t0 = t0;
  out.returns.reserve(static_cast<size_t>(n) * lidar::kVlp16Lasers);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < lidar::kVlp16Lasers; ++j)
      if (valid[i][j]) out.returns.push_back(rays[i][j]);
  }
  out.sequences = std::move(sequences);
  return out;
}

LidarSweep LidarScanner::encode(Cast&& cast) {
  const double seq_s = lidar::kVlp16SequenceUs * 1e-6;
  const int n = static_cast<int>(cast.sequences.size());
  LidarSweep sweep;
  sweep.t0 = cast.t0;
  sweep.t_end = cast.t0 + n * seq_s;
  for (int i = 0; i < n; ++i) encoder_.add(cast.sequences[i], usecPastHour(cast.t0 + i * seq_s));
  sweep.returns = std::move(cast.returns);
  sweep.packets = encoder_.takePackets();
  return sweep;
}

}  // namespace lanemap::sim
