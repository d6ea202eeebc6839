// The mesh raster of core/bev/projector.h (ProjectorOptions::mesh_raster) against the ray cast it
// replaces (mesh_raster = false): the same label image, pose and mesh must give the same cells, the
// same layers and the same hit / flat / dropped counts, up to a small stated fraction of pixels at
// triangle edges (float rounding there). Two meshes: a synthetic one built to be hard (a ridge that
// hides the ground behind it, thin irregular triangles, a hole under the car bridged by large
// triangles reaching behind the camera, the mesh ending before max range), and the real case, the
// LIDAR mesh of simulated VLP-16 sweeps along a drive through West Oakland.
#include "core/bev/projector.h"
#include "core/camera/camera_model.h"
#include "core/ground/sweep_ground.h"
#include "core/osm/osm_data.h"
#include "core/sim/camera_renderer.h"
#include "core/sim/drive.h"
#include "core/sim/lidar_scanner.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <utility>

namespace {

using namespace lanemap;

const std::string kSource = LANEMAP_SOURCE_DIR;

struct Diff {
  size_t cells_a = 0, cells_b = 0, differing = 0;  // differing: cells in one only, or with other layers
  double fraction() const { return double(differing) / double(std::max<size_t>(1, std::max(cells_a, cells_b))); }
};

Diff compare(const bev::FrameSplat& a, const bev::FrameSplat& b) {
  std::map<std::pair<int, int>, uint8_t> ma, mb;
  for (const auto& c : a.cells) ma[{c.x, c.y}] = c.layers;
  for (const auto& c : b.cells) mb[{c.x, c.y}] = c.layers;
  Diff d{a.cells.size(), b.cells.size(), 0};
  for (const auto& [k, l] : ma) {
    const auto it = mb.find(k);
    d.differing += it == mb.end() || it->second != l;
  }
  for (const auto& [k, l] : mb) d.differing += !ma.count(k);
  return d;
}

size_t absDiff(size_t a, size_t b) { return a > b ? a - b : b - a; }

bev::ProjectorOptions rayCast(bev::ProjectorOptions o) {
  o.mesh_raster = false;
  return o;
}

// Vehicle at ENU (100.03, 50.07, 10), facing north-east.
Eigen::Isometry3d pose() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(100.03, 50.07, 10.0);
  return t;
}

// Irregular points (jittered 0.7 m lattice, vehicle frame) from 20 m behind to 40 m ahead and 12 m
// to either side, none within 5 m of the car (Delaunay bridges the hole with large triangles
// reaching behind the camera): a rolling surface with a 0.9 m ridge 14 m ahead, about 10 m wide,
// which the rays that clear it pass until beyond max range (dropped: the mesh lies under their flat
// hit); rays past its ends to the sides land off the mesh (flat).
ground::TriangleMesh hardMesh() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<Eigen::Vector3d> pts;
  for (double x = -20.0; x <= 40.0; x += 0.7) {
    for (double y = -12.0; y <= 12.0; y += 0.7) {
      const double px = x + jitter(rng), py = y + jitter(rng);
      if (std::hypot(px, py) < 5.0) continue;
      const double ridge = 0.9 * std::exp(-std::pow((px - 14.0) / 1.2, 2) - std::pow(py / 5.0, 4));
      const double z = 0.15 * std::sin(0.3 * px) * std::cos(0.2 * py) + ridge - 0.01 * py * py * 0.1;
      pts.push_back(pose() * Eigen::Vector3d(px, py, z));
    }
  }
  return ground::triangulateGround(pts, 0.0);
}

// Every class, in stripes that change along rows and columns (lane separations included).
cv::Mat stripes(int w, int h) {
  cv::Mat labels(h, w, CV_8UC1);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) labels.at<uint8_t>(v, u) = static_cast<uint8_t>((u / 9 + v / 4) % bev::kNumClasses);
  }
  return labels;
}

TEST(MeshRaster, EqualsTheRayCastOnAMeshWithARidgeAHoleUnderTheCarAndEdgesInView) {
  const auto cam = camera::CameraModel::fromYamlFile(kSource + "/config/vehicle.yaml");
  const ground::MeshGround mesh(hardMesh());
  const cv::Mat labels = stripes(cam.width(), cam.height());
  for (const double spacing : {0.0, 0.1}) {
    bev::ProjectorOptions o;
    o.sample_spacing_m = spacing;
    const bev::Projector raster(cam, o), cast(cam, rayCast(o));
    ASSERT_TRUE(raster.rasterises());
    ASSERT_FALSE(cast.rasterises());
    const auto a = raster.project(labels, pose(), &mesh);
    const auto b = cast.project(labels, pose(), &mesh);
    const Diff d = compare(a, b);
    std::printf("spacing %.1f: %zu pixels; raster %zu hits %zu flat %zu dropped (%zu ray-cast); ray cast %zu / %zu / %zu;"
                " %zu vs %zu cells, %zu differ\n",
                spacing, a.pixels, a.mesh_hits, a.flat, a.dropped, a.raycast, b.mesh_hits, b.flat, b.dropped,
                a.cells.size(), b.cells.size(), d.differing);
    // The scene exercises every branch: hits, flat beyond the mesh's edge, rays dropped behind the ridge.
    EXPECT_GT(b.mesh_hits, b.pixels / 2);
    EXPECT_GT(b.flat, 100u);
    EXPECT_GT(b.dropped, 100u);
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_EQ(b.raycast, b.pixels) << "the reference ray-casts every pixel";
    EXPECT_LE(a.raycast, a.pixels / 100) << "the raster settles nearly every pixel itself";
    EXPECT_LE(absDiff(a.mesh_hits, b.mesh_hits), a.pixels / 1000);
    EXPECT_LE(absDiff(a.dropped, b.dropped), a.pixels / 1000);
    EXPECT_LE(absDiff(a.flat, b.flat), a.pixels / 1000);
    EXPECT_LE(d.fraction(), 0.002) << "cells differ beyond rounding at triangle edges";
  }
}

TEST(MeshRaster, EqualsTheRayCastOnTheLidarMeshAlongADrive) {
  const auto osm = osm::readOsm(kSource + "/data/osm/west-oakland.osm");
  const auto sk = skeleton::Skeleton::build(osm);
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(kSource + "/config/sim_world.yaml");
  wo.seed = 5;
  const auto world = sim::buildWorld(sk, wo);
  sim::DriveOptions drive;
  drive.seed = 5;
  drive.duration_s = 40.0;
  const auto plan = sim::planDrive(sk, world->truth(), drive);
  const sim::Trajectory traj(world->truth(), *world, plan, drive);
  ASSERT_GT(traj.duration(), 30.0);

  const YAML::Node vehicle = loadYamlFile(kSource + "/config/vehicle.yaml");
  const auto camera = camera::CameraModel::fromYaml(vehicle["camera"]);
  const auto lidar_options = sim::LidarScannerOptions::fromYaml(vehicle["lidar"]);
  sim::RenderOptions render;
  render.shadows = false;
  const sim::CameraRenderer renderer(camera, render);
  sim::LidarScanner scanner(lidar_options);
  const bev::Projector raster(camera), cast(camera, rayCast({}));
  auto poseAt = [&](double t) { return traj.at(t).vehicle_to_enu; };

  size_t pixels = 0, raycast = 0, hits_a = 0, hits_b = 0, cells = 0, differing = 0;
  int frames = 0;
  for (double t = 3.0; t < traj.duration() - 1.0; t += 6.0) {
    const sim::VehicleState st = traj.at(t);
    const auto frame = renderer.render(*world, st.vehicle_to_enu, st.lanelet, 7);
    const sim::LidarSweep sweep = scanner.scan(*world, t - scanner.sweepPeriodS(), poseAt, 11);
    ground::SweepPoints pts;
    for (const auto& r : sweep.returns) pts.enu.push_back(poseAt(r.time_s) * lidar_options.mount * r.point_sensor);
    pts.vehicle_to_enu_mid = poseAt(t - 0.5 * scanner.sweepPeriodS());
    const auto ground = ground::buildSweepGround(pts);
    ASSERT_TRUE(ground.mesh);
    const auto a = raster.project(frame.labels, st.vehicle_to_enu, ground.mesh.get());
    const auto b = cast.project(frame.labels, st.vehicle_to_enu, ground.mesh.get());
    const Diff d = compare(a, b);
    EXPECT_GT(b.mesh_hits, b.pixels / 2) << "t " << t;
    EXPECT_LE(d.fraction(), 0.002) << "t " << t;
    pixels += a.pixels;
    raycast += a.raycast;
    hits_a += a.mesh_hits;
    hits_b += b.mesh_hits;
    cells += b.cells.size();
    differing += d.differing;
    ++frames;
  }
  std::printf("%d frames, %zu pixels: raster %zu on the mesh (%zu ray-cast), ray cast %zu; %zu of %zu cells differ\n",
              frames, pixels, hits_a, raycast, hits_b, differing, cells);
  ASSERT_GE(frames, 5);
  EXPECT_LE(raycast, pixels / 100);
  EXPECT_LE(absDiff(hits_a, hits_b), pixels / 1000);
  EXPECT_LE(double(differing), 0.001 * double(cells));
}

}  // namespace
