// Tests of sim::LidarScanner: ranges on flat ground equal h / sin(-elevation), a box ahead gives the
// slab range, motion during a sweep shows up, intensities per surface, noise statistics, and the
// packets decode (lidar::PacketDecoder) back to the simulated points with the right timestamps.
#include "core/sim/lidar_scanner.h"
#include "tests/render/test_worlds.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>

namespace lanemap::sim {
namespace {

using testing::StripedRoadWorld;
using testing::makeBox;

const std::string kVehicleYaml = std::string(LANEMAP_DATA_DIR) + "/../config/vehicle.yaml";
constexpr double kDeg = M_PI / 180.0;
constexpr double kMountHeight = 1.9;  // config/vehicle.yaml lidar.mount.z
constexpr double kSigma = 0.02;       // config/vehicle.yaml lidar.range_noise_m

Eigen::Isometry3d pose2d(double e, double n, double z, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(e, n, z);
  return p;
}

int laserWithElevation(double deg) {
  for (int j = 0; j < lidar::kVlp16Lasers; ++j)
    if (std::abs(lidar::vlp16ElevationDeg(j) - deg) < 1e-9) return j;
  ADD_FAILURE() << "no laser at " << deg;
  return 0;
}

TEST(LidarScanner, ShippedConfig) {
  const LidarScannerOptions o = LidarScannerOptions::fromYamlFile(kVehicleYaml);
  EXPECT_NEAR(o.mount.translation().x(), 1.2, 1e-12);
  EXPECT_NEAR(o.mount.translation().z(), kMountHeight, 1e-12);
  EXPECT_TRUE(o.mount.linear().isIdentity(1e-12));
  EXPECT_EQ(o.product_id, 0x22);
  EXPECT_EQ(o.rpm, 600.0);
  EXPECT_EQ(o.range_noise_m, kSigma);
  const LidarScanner scanner(o);
  EXPECT_EQ(scanner.sequencesPerSweep(), 1808);            // floor(0.1 s / 55.296 us)
  EXPECT_NEAR(scanner.azimuthStepDeg(), 0.199066, 1e-6);   // 3600 deg/s * 55.296 us
  EXPECT_THROW(LidarScannerOptions::fromYaml(YAML::Load("{rpm: 600}")), std::runtime_error);  // no mount
  EXPECT_THROW(LidarScannerOptions::fromYaml(YAML::Load("{rpm: 0, mount: {x: 0, y: 0, z: 1}}")),
               std::invalid_argument);
}

TEST(LidarScanner, FlatGroundRangeIsHeightOverSineOfElevation) {
  StripedRoadWorld world;
  world.base = 0.7;
  LidarScanner scanner(LidarScannerOptions::fromYamlFile(kVehicleYaml));
  const Eigen::Isometry3d pose = pose2d(3.0, -0.5, 0.7, 30 * kDeg);
  const LidarSweep sweep = scanner.scan(world, 7200.25, [&](double) { return pose; }, 1);

  std::map<int, int> count;
  std::map<int, double> sum_residual, sum_sq_noise;
  std::map<Surface, std::pair<double, int>> intensity;
  for (const LidarReturn& r : sweep.returns) {
    ASSERT_LT(r.elevation_deg, 0.0) << "an upward laser hit a flat world";
    const double expected = kMountHeight / std::sin(-r.elevation_deg * kDeg);
    EXPECT_NEAR(r.true_range_m, expected, 2e-3);        // ray cast: 0.1 mm vertical / sin(3 deg)
    EXPECT_NEAR(r.range_m, expected, 5.5 * kSigma);     // 5.5 sigma over 12.6k draws: p ~ 5e-4
    ++count[r.laser];
    sum_residual[r.laser] += r.range_m - expected;
    sum_sq_noise[r.laser] += std::pow(r.range_m - r.true_range_m, 2);
    const bool paint = r.ground.surface == Surface::kDashedPaint || r.ground.surface == Surface::kSolidPaint;
    auto& [s, n] = intensity[paint ? Surface::kSolidPaint : r.ground.surface];
    s += r.intensity;
    ++n;
  }
  // The seven lasers at -15..-3 deg reach the ground on every sequence; -1 deg lands at 108.9 m,
  // beyond the 100 m range.
  EXPECT_EQ(count.size(), 7u);
  for (const double e : {-15.0, -13.0, -11.0, -9.0, -7.0, -5.0, -3.0}) {
    const int j = laserWithElevation(e);
    ASSERT_EQ(count[j], scanner.sequencesPerSweep()) << e;
    EXPECT_NEAR(sum_residual[j] / count[j], 0.0, 4.0 * kSigma / std::sqrt(count[j]));  // unbiased
    EXPECT_NEAR(std::sqrt(sum_sq_noise[j] / count[j]), kSigma, 0.1 * kSigma);         // sigma
  }
  // Intensity: paint ~200, asphalt ~20 (noise sigma 8 -> a mean over >= 100 returns within 4 sigma
  // = 3.2 of the base).
  const auto& paint = intensity[Surface::kSolidPaint];
  std::printf("[ info ] %d paint returns, %d asphalt returns\n", paint.second, intensity[Surface::kAsphalt].second);
  ASSERT_GT(paint.second, 100);
  ASSERT_GT(intensity[Surface::kAsphalt].second, 1000);
  EXPECT_NEAR(paint.first / paint.second, 200.0, 3.2);
  EXPECT_NEAR(intensity[Surface::kAsphalt].first / intensity[Surface::kAsphalt].second, 20.0, 1.5);
}

TEST(LidarScanner, BoxAheadGivesTheSlabRangeAndMotionShowsWithinTheSweep) {
  StripedRoadWorld world;
  // A wall-like box whose rear face is 15 m ahead of the rear axle: 13.8 m ahead of the LIDAR.
  world.obstacles.push_back(makeBox({16.0, 0.0, 1.5}, {1.0, 6.0, 1.5}, 0.0));
  LidarScanner scanner(LidarScannerOptions::fromYamlFile(kVehicleYaml));

  // Standing still: a laser at elevation e, azimuth a hits the face at 13.8 / (cos e cos a) when
  // the hit height 1.9 + 13.8 tan e lies on the box (0..3 m): e in -7..+3 deg.
  LidarSweep still = scanner.scan(world, 0.0, [](double) { return pose2d(0, 0, 0, 0); }, 2);
  int on_box = 0;
  double intensity_sum = 0.0;
  for (const LidarReturn& r : still.returns) {
    const double a = r.azimuth_deg > 180 ? r.azimuth_deg - 360 : r.azimuth_deg;
    if (std::abs(a) > 10.0 || r.elevation_deg < -7.5 || r.elevation_deg > 3.5) continue;
    ASSERT_TRUE(r.is_obstacle) << r.elevation_deg << " " << a;
    EXPECT_NEAR(r.true_range_m, 13.8 / (std::cos(r.elevation_deg * kDeg) * std::cos(a * kDeg)), 1e-6);
    EXPECT_NEAR(r.range_m, r.true_range_m, 5.5 * kSigma);
    intensity_sum += r.intensity;
    ++on_box;
  }
  // 6 lasers x ~100 sequences within +-10 deg (step 0.199 deg; laser j fires 0.0083 j deg later).
  EXPECT_GE(on_box, 6 * 99);
  EXPECT_LE(on_box, 6 * 102);
  EXPECT_NEAR(intensity_sum / on_box, 60.0, 1.5);  // parked-car reflectivity, noise 8 / sqrt(606)

  // Driving at 10 m/s towards it: the last sequence (azimuth 359.8, 99.9 ms later) sees the
  // face 0.999 m closer than the first one (azimuth 0).
  const double speed = 10.0;
  LidarSweep moving = scanner.scan(world, 0.0, [&](double t) { return pose2d(speed * t, 0, 0, 0); }, 3);
  const int laser = laserWithElevation(1.0);
  const LidarReturn* first = nullptr;
  const LidarReturn* last = nullptr;
  for (const LidarReturn& r : moving.returns) {
    if (r.laser != laser) continue;
    if (r.sequence == 0) first = &r;
    if (r.sequence == scanner.sequencesPerSweep() - 1) last = &r;
  }
  ASSERT_TRUE(first && last);
  const double moved = speed * (last->time_s - first->time_s);
  EXPECT_NEAR(moved, speed * 1807 * lidar::kVlp16SequenceUs * 1e-6, 1e-9);  // 0.9992 m
  const double a_last = (360.0 - last->azimuth_deg) * kDeg, e = kDeg;
  EXPECT_NEAR(first->true_range_m, 13.8 / (std::cos(e) * std::cos(first->azimuth_deg * kDeg)), 1e-6);
  EXPECT_NEAR(last->true_range_m, (13.8 - moved) / (std::cos(e) * std::cos(a_last)), 1e-6);
}

TEST(LidarScanner, PacketsDecodeToTheSimulatedPoints) {
  StripedRoadWorld world;
  world.obstacles.push_back(makeBox({16.0, 0.0, 1.5}, {1.0, 6.0, 1.5}, 0.0));
  LidarScanner scanner(LidarScannerOptions::fromYamlFile(kVehicleYaml));
  const double t0 = 7200.25;  // 2 h + 0.25 s: 250000 us past the hour
  const auto still = [](double) { return pose2d(0, 0, 0, 0); };
  const auto start = std::chrono::steady_clock::now();
  const LidarSweep sweep = scanner.scan(world, t0, still, 4);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ info ] one VLP-16 sweep (%d sequences, %zu returns): %.1f ms\n",
              scanner.sequencesPerSweep(), sweep.returns.size(), 1e3 * seconds);

  // 1808 sequences = 75 full packets of 24; the 8 left wait for the next sweep.
  ASSERT_EQ(sweep.packets.size(), 75u);
  EXPECT_EQ(scanner.pendingSequences(), 8);
  for (size_t k = 0; k < sweep.packets.size(); ++k) {
    uint32_t stamp;
    std::memcpy(&stamp, sweep.packets[k].data() + lidar::kTimestampOffset, 4);  // little endian host
    EXPECT_EQ(stamp, usecPastHour(t0 + 24 * k * lidar::kVlp16SequenceUs * 1e-6)) << k;
  }
  EXPECT_EQ(usecPastHour(t0), 250000u);

  lidar::PacketDecoder decoder(lidar::Model::kVlp16);
  std::vector<lidar::LidarPoint> points;
  for (const auto& p : sweep.packets) ASSERT_EQ(decoder.decode(p, points), lidar::DecodeStatus::kOk);
  std::vector<const LidarReturn*> packed;
  for (const LidarReturn& r : sweep.returns)
    if (r.sequence < 75 * 24) packed.push_back(&r);
  ASSERT_EQ(points.size(), packed.size());
  double worst = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const lidar::LidarPoint& q = points[i];
    ASSERT_EQ(q.laser, packed[i]->laser);
    const Eigen::Vector3d decoded(q.x, q.y, q.z);
    worst = std::max(worst, (decoded - packed[i]->point_sensor).norm());
  }
  // Quantisation: distance 2 mm (1 mm rounding), azimuth 0.01 deg (5e-3 deg * 37 m = 3 mm).
  EXPECT_LT(worst, 0.006);

  // The next sweeps carry the rest: 8 + 1808 -> 75 packets (16 left), 16 + 1808 -> 76 (0 left).
  EXPECT_EQ(scanner.scan(world, t0 + 0.1, still, 5).packets.size(), 75u);
  EXPECT_EQ(scanner.pendingSequences(), 16);
  EXPECT_EQ(scanner.scan(world, t0 + 0.2, still, 6).packets.size(), 76u);
  EXPECT_EQ(scanner.pendingSequences(), 0);
}

TEST(LidarScanner, SeededNoise) {
  StripedRoadWorld world;
  const auto still = [](double) { return pose2d(0, 0, 0, 0); };
  LidarScanner a(LidarScannerOptions::fromYamlFile(kVehicleYaml));
  LidarScanner b(LidarScannerOptions::fromYamlFile(kVehicleYaml));
  const LidarSweep s1 = a.scan(world, 1.0, still, 9), s2 = b.scan(world, 1.0, still, 9);
  const LidarSweep s3 = a.scan(world, 1.0, still, 10);
  ASSERT_EQ(s1.returns.size(), s2.returns.size());
  ASSERT_EQ(s1.returns.size(), s3.returns.size());
  int same = 0;
  for (size_t i = 0; i < s1.returns.size(); ++i) {
    EXPECT_EQ(s1.returns[i].range_m, s2.returns[i].range_m);
    same += s1.returns[i].range_m == s3.returns[i].range_m;
  }
  EXPECT_EQ(s1.packets, s2.packets);
  EXPECT_LT(same, 10);  // another seed draws other noise
}

}  // namespace
}  // namespace lanemap::sim
