// config/vehicle.yaml read whole and strictly: the camera (intrinsics, distortion, mount; the
// simulator's frame rate and JPEG quality) and the LIDAR (mount; the simulated sensor's keys).
// The BEV builder and lanemap-offline take the camera model and the LIDAR mount from here, so a
// typo anywhere in the file is an error naming the file and the key.
#pragma once

#include "core/camera/camera_model.h"
#include "core/config/yaml_reader.h"
#include "core/sim/lidar_scanner.h"

#include <string>

namespace lanemap::config {

struct VehicleConfig {
  explicit VehicleConfig(camera::CameraModel c) : camera(std::move(c)) {}
  camera::CameraModel camera;
  double camera_frame_rate_hz = 10.0;  // camera.frame_rate_hz (what the simulator's camera runs at)
  int camera_jpeg_quality = 90;        // camera.jpeg_quality (the simulator's CAMERA_FRONT images)
  sim::LidarScannerOptions lidar;      // lidar: its mount, and the simulated sensor's keys
  Eigen::Isometry3d lidarToVehicle() const { return lidar.mount; }

  static VehicleConfig fromYaml(const YamlReader& r);  // the caller's finish() refuses other keys
  static VehicleConfig fromYamlFile(const std::string& path);
};

}  // namespace lanemap::config
