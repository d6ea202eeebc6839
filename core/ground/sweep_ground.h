// From one LIDAR sweep's raw packets to the topographic ground model (METHOD.md section 3):
// decode (core/lidar/velodyne.h), move every point to ENU with the LIDAR mount and the vehicle pose
// AT ITS PACKET'S TIME, extract the ground points (ground_extraction.h), triangulate them
// (ground_mesh.h).
//
// Why the pose per packet and not one pose per sweep: a sweep lasts 0.1 s, in which the car moves
// ~1.1 m at urban speed and turns up to several degrees. One pose for the whole sweep would shear
// the point cloud by up to that much (the last packets of the sweep land ~1 m off); interpolating
// the 100 Hz pose at each of the ~75 packets costs nothing and removes the skew (a packet spans
// 1.3 ms, ~1.5 cm of motion). Ground extraction runs in the vehicle frame at the sweep's middle
// pose, so "up" and "the ground under the car" are those of the car.
#pragma once

#include "core/ground/ground_extraction.h"
#include "core/ground/ground_mesh.h"
#include "core/lidar/velodyne.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace lanemap::ground {

struct SweepPacket {
  int64_t utime = 0;             // time of the packet's first firing
  const uint8_t* data = nullptr;
  size_t size = 0;
};

// Vehicle pose (vehicle -> ENU) at a utime, nullopt when unknown there.
using PoseLookup = std::function<std::optional<Eigen::Isometry3d>(int64_t utime)>;

struct SweepPoints {
  std::vector<Eigen::Vector3d> enu;        // every decoded point, ENU
  int64_t utime_mid = 0;                   // middle of the packets with a pose
  Eigen::Isometry3d vehicle_to_enu_mid = Eigen::Isometry3d::Identity();
  int packets = 0, packets_bad = 0, packets_without_pose = 0;
};

// Decodes the packets and moves their points to ENU. nullopt when no packet had a pose.
std::optional<SweepPoints> sweepToEnu(const std::vector<SweepPacket>& packets, const Eigen::Isometry3d& lidar_to_vehicle,
                                      const PoseLookup& pose, std::optional<lidar::Model> model = std::nullopt);

struct SweepGroundOptions {
  GroundExtractionOptions extraction;
  double max_edge_m = 16.0;     // triangles with a longer edge are dropped (ground_mesh.h)
  double max_range_m = 60.0;    // ground points farther from the car are not triangulated
  // Ground points are merged per decimate_m x decimate_m cell (east, north) into their mean before
  // Delaunay; 0: every point is a vertex. A VLP-16 ring has a point every 0.2 deg (3.5 cm at 10 m)
  // but the rings are metres apart, so the along-ring density buys nothing for the surface, while
  // it makes thousands of needle triangles (Delaunay, index and the projection's raster all scale
  // with them). The mean also averages the range noise (tests/ground/sweep_mesh_test.cc).
  double decimate_m = 0.3;
  MeshGroundOptions index;
};

// Means of the points per cell x cell square (east, north); cell <= 0: the points unchanged.
std::vector<Eigen::Vector3d> decimateGround(const std::vector<Eigen::Vector3d>& points, double cell_m);

struct SweepGround {
  std::shared_ptr<const MeshGround> mesh;
  int64_t utime = 0;                 // the sweep's middle
  size_t points = 0, ground_points = 0, mesh_points = 0;  // decoded, ground, mesh vertices
  double ms_extract = 0.0, ms_triangulate = 0.0, ms_index = 0.0;
};

// Ground extraction + Delaunay + index of one sweep in ENU.
SweepGround buildSweepGround(const SweepPoints& sweep, const SweepGroundOptions& options = {});

}  // namespace lanemap::ground
