// The camera model of lanemap: a pinhole camera with OpenCV's 5-parameter distortion
// (k1, k2, p1, p2, k3) and its mount on the vehicle. Projects vehicle-frame or camera-frame points
// to pixels and turns pixels back into unit rays. Used by the simulator's renderer and by the BEV
// projection, so every operation is exact (undistortion by Newton iteration to ~1e-12).
//
// Frames: vehicle x forward, y left, z up (origin: rear axle centre on the ground); camera frame
// OpenCV: x right, y down, z forward (along the optical axis). Pixel coordinates are OpenCV's:
// the centre of pixel (u, v) is at (u, v), the image spans [-0.5, width - 0.5] x [-0.5, height - 0.5].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace YAML { class Node; }
namespace lanemap::config { class YamlReader; }

namespace lanemap::camera {

// Bad camera configuration or arguments (the message names the key / file / value).
class CameraModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Intrinsics {
  double fx = 0.0, fy = 0.0;  // focal lengths, pixels
  double cx = 0.0, cy = 0.0;  // principal point, pixels
  int width = 0, height = 0;  // image size, pixels
};

// OpenCV's model: x_d = x r(x) + 2 p1 x y + p2 (r^2 + 2 x^2), y_d = y r(x) + p1 (r^2 + 2 y^2) + 2 p2 x y,
// r(x) = 1 + k1 r^2 + k2 r^4 + k3 r^6, on normalized coordinates (x, y) = (X/Z, Y/Z).
struct Distortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  bool isZero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
};

// A sensor mount (position and roll/pitch/yaw of a sensor's x-forward/y-left/z-up body frame in the
// vehicle frame) from YAML keys x, y, z (metres), roll_deg, pitch_deg, yaw_deg (degrees;
// R = Rz(yaw) Ry(pitch) Rx(roll); positive pitch turns the nose DOWN). Missing angles default to 0;
// missing x/y/z throw CameraModelError naming `context`.
Eigen::Isometry3d mountFromYaml(const YAML::Node& node, const std::string& context);
// The same from a config section (strict: x, y, z required, no other keys but the angles, once the
// caller's finish() runs); errors are config::ConfigError naming the file and key.
Eigen::Isometry3d mountFromYaml(const config::YamlReader& r);

// Rotation from OpenCV's camera frame to a camera body frame (x forward, y left, z up):
// body = kBodyFromOptical * optical.
Eigen::Matrix3d bodyFromOptical();

class CameraModel {
 public:
  // camera_to_vehicle: the pose of the OpenCV camera frame in the vehicle frame
  // (p_vehicle = camera_to_vehicle * p_camera). Throws CameraModelError on non-positive size/focal.
  CameraModel(const Intrinsics& intrinsics, const Distortion& distortion,
              const Eigen::Isometry3d& camera_to_vehicle);

  // From the `camera` node of config/vehicle.yaml: width, height, fx, fy, cx, cy,
  // distortion {k1, k2, p1, p2, k3} or [k1, k2, p1, p2(, k3)] (optional, zeros), mount {x, y, z, roll_deg, pitch_deg, yaw_deg}
  // (the camera body frame x forward/y left/z up; the optical frame follows by bodyFromOptical()).
  static CameraModel fromYaml(const YAML::Node& camera_node);
  // The same from a config section (config/vehicle.yaml `camera:`); the keys other than the ones
  // above are the caller's (core/config/vehicle_config.h reads the whole file strictly). Throws
  // config::ConfigError naming the file and key.
  static CameraModel fromYaml(const config::YamlReader& r);
  // Loads `path` (a vehicle YAML) and reads its `key` node; errors name the file.
  static CameraModel fromYamlFile(const std::string& path, const std::string& key = "camera");

  const Intrinsics& intrinsics() const { return intrinsics_; }
  const Distortion& distortion() const { return distortion_; }
  int width() const { return intrinsics_.width; }
  int height() const { return intrinsics_.height; }
  cv::Size imageSize() const { return {intrinsics_.width, intrinsics_.height}; }
  cv::Matx33d cameraMatrix() const;         // OpenCV K
  std::vector<double> distCoeffs() const;   // OpenCV order k1, k2, p1, p2, k3

  const Eigen::Isometry3d& cameraToVehicle() const { return camera_to_vehicle_; }
  const Eigen::Isometry3d& vehicleToCamera() const { return vehicle_to_camera_; }
  Eigen::Vector3d opticalCentreVehicle() const { return camera_to_vehicle_.translation(); }

  // Normalized image coordinates: ideal (undistorted) <-> distorted.
  Eigen::Vector2d distort(const Eigen::Vector2d& ideal) const;
  // Inverse of distort() by Newton iteration (exact to ~1e-12 inside the valid radius).
  Eigen::Vector2d undistort(const Eigen::Vector2d& distorted) const;

  // Pixel of a point; nullopt when it is behind the camera (Z <= 1e-9) or beyond the radius where the
  // radial distortion stops being monotonic (the polynomial folds back there, so the pixel would
  // be wrong). The pixel may lie outside the image: check with inImage().
  std::optional<Eigen::Vector2d> projectCamera(const Eigen::Vector3d& p_camera) const;
  std::optional<Eigen::Vector2d> projectVehicle(const Eigen::Vector3d& p_vehicle) const;
  // Pixel without distortion (pinhole only), for comparison; same nullopt rule for Z.
  std::optional<Eigen::Vector2d> projectCameraPinhole(const Eigen::Vector3d& p_camera) const;

  // Unit viewing ray through a pixel (undistorted), in the camera frame (z > 0) or rotated into the
  // vehicle frame (a direction; the ray starts at opticalCentreVehicle()).
  Eigen::Vector3d rayCamera(const Eigen::Vector2d& pixel) const;
  Eigen::Vector3d rayVehicle(const Eigen::Vector2d& pixel) const;

  bool inImage(const Eigen::Vector2d& pixel) const;
  // Normalized radius^2 up to which projection is valid (infinity when distortion is monotonic).
  double maxValidRadius2() const { return max_r2_; }

 private:
  Intrinsics intrinsics_;
  Distortion distortion_;
  Eigen::Isometry3d camera_to_vehicle_;
  Eigen::Isometry3d vehicle_to_camera_;
  double max_r2_;
};

}  // namespace lanemap::camera
