// Ground models (core/ground): the Delaunay mesh interpolates a plane exactly and rays meet it where
// the plane says; long triangles are dropped (no bridge across gaps); the flat plane under a tilted
// vehicle; ground extraction keeps the ground rings of a synthetic VLP-16-like sweep over a crowned,
// graded road and leaves out a parked car and a wall; a sweep of real VLP-16 packets taken while
// driving lands on the ground in ENU once each packet gets its own pose.
#include "core/ground/ground_extraction.h"
#include "core/ground/ground_mesh.h"
#include "core/ground/ground_model.h"
#include "core/ground/sweep_ground.h"
#include "core/lidar/velodyne.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace {

using namespace lanemap::ground;

double plane(double x, double y) { return 1.0 + 0.1 * x - 0.05 * y; }

TriangleMesh planeGrid(double step) {
  std::vector<Eigen::Vector3d> pts;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3 * step, 0.3 * step);
  for (double x = -20; x <= 20; x += step) {
    for (double y = -20; y <= 20; y += step) {
      const double px = x + jitter(rng), py = y + jitter(rng);
      pts.emplace_back(px, py, plane(px, py));
    }
  }
  return triangulateGround(pts, 0.0);
}

TEST(GroundMesh, InterpolatesAPlaneExactlyAndRaysMeetIt) {
  const MeshGround mesh(planeGrid(2.0), {1.0});
  ASSERT_GT(mesh.triangleCount(), 300u);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-18.0, 18.0);
  for (int i = 0; i < 200; ++i) {
    const double x = u(rng), y = u(rng);
    const auto z = mesh.heightAt(x, y);
    ASSERT_TRUE(z) << x << "," << y;
    EXPECT_NEAR(*z, plane(x, y), 1e-9);
    // A ray from 3 m above the plane at a random point, downwards at a grazing angle.
    const Eigen::Vector3d o(u(rng) * 0.3, u(rng) * 0.3, 0.0);
    const Eigen::Vector3d origin(o.x(), o.y(), plane(o.x(), o.y()) + 3.0);
    const double a = u(rng);
    const Eigen::Vector3d d(std::cos(a), std::sin(a), -0.3);
    const auto t = mesh.intersect(origin, d, 100.0);
    ASSERT_TRUE(t);
    const Eigen::Vector3d p = origin + *t * d;
    EXPECT_NEAR(p.z(), plane(p.x(), p.y()), 1e-9);
    // Analytic: origin.z + t d.z = 1 + 0.1 x - 0.05 y along the ray.
    const double t_exact = (origin.z() - plane(origin.x(), origin.y())) / (0.1 * d.x() - 0.05 * d.y() - d.z());
    EXPECT_NEAR(*t, t_exact, 1e-9);
  }
  EXPECT_FALSE(mesh.heightAt(30.0, 0.0));
  EXPECT_FALSE(mesh.intersect(Eigen::Vector3d(0, 0, 10), Eigen::Vector3d(1, 0, 0.5), 100.0)) << "upwards";
  EXPECT_FALSE(mesh.intersect(Eigen::Vector3d(0, 0, 10), Eigen::Vector3d(1, 0, -0.1), 5.0)) << "max_t";
}

TEST(GroundMesh, LongTrianglesAreDroppedSoGapsStayOpen) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      pts.emplace_back(i, j, 0.0);
      pts.emplace_back(40.0 + i, j, 2.0);
    }
  }
  const MeshGround bridged(triangulateGround(pts, 0.0));
  const MeshGround gapped(triangulateGround(pts, 3.0));
  ASSERT_TRUE(bridged.heightAt(20.0, 2.0)) << "Delaunay alone bridges the 35 m gap";
  EXPECT_GT(*bridged.heightAt(20.0, 2.0), 0.5);
  EXPECT_LT(*bridged.heightAt(20.0, 2.0), 1.5);
  EXPECT_FALSE(gapped.heightAt(20.0, 2.0));
  EXPECT_NEAR(*gapped.heightAt(2.2, 2.7), 0.0, 1e-12);
  EXPECT_NEAR(*gapped.heightAt(42.2, 2.7), 2.0, 1e-12);
  EXPECT_EQ(gapped.triangleCount(), 2u * 2u * 16u);
}

TEST(FlatGround, IsThePlaneTheVehicleStandsOn) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();  // nose 0.05 rad down
  pose.translation() = Eigen::Vector3d(10, 20, 3);
  const FlatGround g = FlatGround::underVehicle(pose);
  EXPECT_NEAR(g.heightAt(10 + 10.0, 20), 3.0 - 10.0 * std::tan(0.05), 1e-12);
  const auto t = g.intersect(Eigen::Vector3d(20, 20, 10), Eigen::Vector3d(0, 0, -1), 100.0);
  ASSERT_TRUE(t);
  EXPECT_NEAR(10.0 - *t, g.heightAt(20, 20), 1e-12);
  EXPECT_FALSE(g.intersect(Eigen::Vector3d(20, 20, 10), Eigen::Vector3d(0, 0, 1), 100.0));
}

// A VLP-16-like sweep in the vehicle frame over a road crowned 2 % with a 5 % grade from 10 m on,
// a parked car (box 4.5 x 1.8 x 1.5 m at x 8..12.5, y -3.5..-5.3) and a wall at y = 9.
struct Scene {
  std::vector<Eigen::Vector3d> pts;
  std::vector<bool> ground;
};

double roadHeight(double x, double y) { return -0.02 * std::abs(y) + (x > 10.0 ? 0.05 * (x - 10.0) : 0.0); }

Scene syntheticSweep() {
  Scene s;
  const Eigen::Vector3d o(1.2, 0.0, 1.9);
  for (int laser = 0; laser < 16; ++laser) {
    const double el = lanemap::lidar::vlp16ElevationDeg(laser) * M_PI / 180.0;
    if (el >= 0) continue;
    for (double az = 0; az < 360; az += 0.4) {
      const double a = az * M_PI / 180.0;
      const Eigen::Vector3d d(std::cos(el) * std::cos(a), std::cos(el) * std::sin(a), std::sin(el));
      // March the ray; first of: wall, car box, ground.
      for (double t = 0.5; t < 80.0; t += 0.02) {
        const Eigen::Vector3d p = o + t * d;
        const bool wall = p.y() >= 9.0;
        const bool car = p.x() > 8 && p.x() < 12.5 && p.y() < -3.5 && p.y() > -5.3 && p.z() < roadHeight(p.x(), p.y()) + 1.5;
        const bool grd = p.z() <= roadHeight(p.x(), p.y());
        if (wall || car || grd) {
          s.pts.push_back(p);
          s.ground.push_back(grd && !wall && !car);
          break;
        }
      }
    }
  }
  return s;
}

TEST(GroundExtraction, KeepsTheCrownedGradedRoadAndDropsACarAndAWall) {
  const Scene s = syntheticSweep();
  const auto idx = extractGround(s.pts);
  const std::set<int> chosen(idx.begin(), idx.end());
  // Car and wall points within a few cm of the road (their feet) are ground as far as a mesh cares:
  // only those 0.15 m or more above it count as clutter. Scored within 40 m (the camera sees 30 m).
  size_t ground = 0, ground_kept = 0, other = 0, other_kept = 0;
  for (size_t i = 0; i < s.pts.size(); ++i) {
    const bool kept = chosen.count(static_cast<int>(i)) > 0;
    if (!s.ground[i] && s.pts[i].z() - roadHeight(s.pts[i].x(), s.pts[i].y()) < 0.15) continue;
    if (s.pts[i].head<2>().norm() > 40.0) continue;
    if (s.ground[i]) {
      ++ground;
      ground_kept += kept;
    } else {
      ++other;
      other_kept += kept;
    }
  }
  std::printf("ground %zu (kept %zu), other %zu (kept %zu)\n", ground, ground_kept, other, other_kept);
  ASSERT_GT(other, 300u);
  EXPECT_GT(static_cast<double>(ground_kept) / ground, 0.9);
  EXPECT_LT(static_cast<double>(other_kept) / other, 0.01);
}

TEST(SweepGround, PacketsTakenWhileDrivingLandOnTheGroundWithAPosePerPacket) {
  // The car drives north at 12 m/s up a 10 % slope (ground z = 0.1 * north), turning left at
  // 0.5 rad/s; real VLP-16 packets.
  const Eigen::Isometry3d mount(Eigen::Translation3d(1.2, 0.0, 1.9));
  auto poseAt = [](int64_t utime) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = (Eigen::AngleAxisd(M_PI / 2 + 0.5 * utime * 1e-6, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(-std::atan(0.1), Eigen::Vector3d::UnitY()))  // nose up the slope
                     .toRotationMatrix();
    const double north = 12.0 * utime * 1e-6;
    t.translation() = Eigen::Vector3d(5.0, north, 0.1 * north);
    return t;
  };
  lanemap::lidar::Vlp16PacketEncoder enc;
  const double rate = 360.0 / 0.1 * 1e-6;  // deg per microsecond
  for (int i = 0; i < 1800; ++i) {
    const double t_us = i * lanemap::lidar::kVlp16SequenceUs;
    lanemap::lidar::FiringSequence seq;
    seq.azimuth_deg = std::fmod(t_us * rate, 360.0);
    const Eigen::Isometry3d lidar_to_enu = poseAt(static_cast<int64_t>(t_us)) * mount;
    const Eigen::Vector3d o = lidar_to_enu.translation();
    for (int l = 0; l < 16; ++l) {
      const double el = lanemap::lidar::vlp16ElevationDeg(l) * M_PI / 180.0;
      const double az = (seq.azimuth_deg + rate * l * lanemap::lidar::kVlp16FiringUs) * M_PI / 180.0;
      const Eigen::Vector3d d = lidar_to_enu.linear() * Eigen::Vector3d(std::cos(el) * std::cos(az), -std::cos(el) * std::sin(az), std::sin(el));
      const double t = (0.1 * o.y() - o.z()) / (d.z() - 0.1 * d.y());
      seq.distance_m[l] = t > 0.0 && t < 100.0 ? static_cast<float>(t) : 0.0f;
    }
    enc.add(seq, static_cast<uint32_t>(t_us));
  }
  const auto packets = enc.takePackets();
  std::vector<SweepPacket> in;
  for (const auto& p : packets) {
    const uint32_t ts = p[1200] | p[1201] << 8 | p[1202] << 16 | static_cast<uint32_t>(p[1203]) << 24;
    in.push_back(SweepPacket{static_cast<int64_t>(ts), p.data(), p.size()});
  }
  auto worstResidual = [](const SweepPoints& s) {
    double worst = 0.0;
    for (const auto& p : s.enu) worst = std::max(worst, std::abs(p.z() - 0.1 * p.y()));
    return worst;
  };
  const auto pts = sweepToEnu(in, mount, [&](int64_t u) { return std::optional<Eigen::Isometry3d>(poseAt(u)); });
  ASSERT_TRUE(pts);
  ASSERT_GT(pts->enu.size(), 10000u);
  EXPECT_LT(worstResidual(*pts), 0.02) << "points off the ground: the pose per packet is not used";
  // One pose (the sweep's start) for every packet: the car's motion in the sweep (1.2 m, 2.9 deg)
  // moves far points by metres, across the slope: off the ground.
  const auto one = sweepToEnu(in, mount, [&](int64_t) { return std::optional<Eigen::Isometry3d>(poseAt(0)); });
  EXPECT_GT(worstResidual(*one), 0.08);
  const SweepGround g = buildSweepGround(*pts);
  // Everything is ground here; within the 60 m the mesh takes.
  size_t within = 0;
  for (const auto& p : pts->enu) within += (p - pts->vehicle_to_enu_mid.translation()).head<2>().norm() <= 60.0;
  EXPECT_GT(g.ground_points, within * 9 / 10);
  ASSERT_TRUE(g.mesh);
  EXPECT_NEAR(*g.mesh->heightAt(5.0, 20.0), 2.0, 0.02);
}

}  // namespace
