// Pinhole + OpenCV distortion camera model: projection, exact undistortion, YAML loading.
#include "core/camera/camera_model.h"

#include "core/config/yaml_reader.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>

namespace lanemap::camera {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kMinDepth = 1e-9;

// Radial factor r(x) = 1 + k1 r^2 + k2 r^4 + k3 r^6 and d r(x) / d(r^2).
void radial(const Distortion& d, double r2, double* factor, double* dfactor_dr2) {
  *factor = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  *dfactor_dr2 = d.k1 + r2 * (2.0 * d.k2 + r2 * 3.0 * d.k3);
}

// Smallest r^2 where d(r * factor)/dr = 1 + 3 k1 r^2 + 5 k2 r^4 + 7 k3 r^6 reaches 0 (the radial
// distortion folds back there); infinity when it stays positive up to r = 10 (84 deg off-axis).
double monotonicLimitR2(const Distortion& d) {
  auto slope = [&](double r2) { return 1.0 + r2 * (3.0 * d.k1 + r2 * (5.0 * d.k2 + r2 * 7.0 * d.k3)); };
  constexpr double kMaxR2 = 100.0;
  constexpr int kSteps = 20000;
  double prev = 0.0;
  for (int i = 1; i <= kSteps; ++i) {
    const double r2 = kMaxR2 * i / kSteps;
    if (slope(r2) <= 0.0) {
      double lo = prev, hi = r2;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (slope(mid) > 0.0 ? lo : hi) = mid;
      }
      return lo;
    }
    prev = r2;
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

Eigen::Matrix3d bodyFromOptical() {
  Eigen::Matrix3d r;
  // Columns: the optical x (right), y (down), z (forward) axes in the body frame (x fwd, y left, z up).
  r << 0, 0, 1,
      -1, 0, 0,
       0, -1, 0;
  return r;
}

Eigen::Isometry3d mountFromYaml(const YAML::Node& node, const std::string& context) {
  try {
    const config::YamlReader r(node);
    const Eigen::Isometry3d pose = mountFromYaml(r);
    r.finish();
    return pose;
  } catch (const config::ConfigError& e) {
    throw CameraModelError(context + ": " + e.what());
  }
}

Eigen::Isometry3d mountFromYaml(const config::YamlReader& r) {
  if (!r.present()) r.failHere("a mount {x, y, z, roll_deg, pitch_deg, yaw_deg} is required");
  const double x = r.required<double>("x");
  const double y = r.required<double>("y");
  const double z = r.required<double>("z");
  const double roll = r.get<double>("roll_deg", 0.0) * kDegToRad;
  const double pitch = r.get<double>("pitch_deg", 0.0) * kDegToRad;
  const double yaw = r.get<double>("yaw_deg", 0.0) * kDegToRad;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

CameraModel::CameraModel(const Intrinsics& intrinsics, const Distortion& distortion,
                         const Eigen::Isometry3d& camera_to_vehicle)
    : intrinsics_(intrinsics),
      distortion_(distortion),
      camera_to_vehicle_(camera_to_vehicle),
      vehicle_to_camera_(camera_to_vehicle.inverse()),
      max_r2_(monotonicLimitR2(distortion)) {
  if (intrinsics.width <= 0 || intrinsics.height <= 0)
    throw CameraModelError("camera: image size must be positive, got " +
                           std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height));
  if (!(intrinsics.fx > 0.0) || !(intrinsics.fy > 0.0))
    throw CameraModelError("camera: focal lengths must be positive, got fx=" +
                           std::to_string(intrinsics.fx) + " fy=" + std::to_string(intrinsics.fy));
  if (!std::isfinite(intrinsics.cx) || !std::isfinite(intrinsics.cy))
    throw CameraModelError("camera: principal point is not finite");
}

CameraModel CameraModel::fromYaml(const YAML::Node& node) {
  try {
    const config::YamlReader r(node);
    CameraModel m = fromYaml(r);
    r.finishSections();  // the camera node also holds the simulator's keys (jpeg_quality, ...)
    return m;
  } catch (const config::ConfigError& e) {
    throw CameraModelError(e.what());
  }
}

CameraModel CameraModel::fromYaml(const config::YamlReader& r) {
  if (!r.present()) r.failHere("the camera {width, height, fx, fy, cx, cy, distortion, mount} is required");
  Intrinsics in;
  in.width = r.required<int>("width");
  in.height = r.required<int>("height");
  in.fx = r.required<double>("fx");
  in.fy = r.required<double>("fy");
  in.cx = r.required<double>("cx");
  in.cy = r.required<double>("cy");
  Distortion d;
  if (const YAML::Node dn = r.raw("distortion"); dn.IsDefined() && dn.IsSequence()) {
    // OpenCV's order [k1, k2, p1, p2(, k3)].
    if (dn.size() != 4 && dn.size() != 5) r.fail("distortion", "must have 4 or 5 coefficients, not " + std::to_string(dn.size()));
    double* coeffs[5] = {&d.k1, &d.k2, &d.p1, &d.p2, &d.k3};
    for (size_t i = 0; i < dn.size(); ++i) {
      try {
        *coeffs[i] = dn[i].as<double>();
      } catch (const YAML::Exception&) {
        r.fail("distortion", "entry " + std::to_string(i) + " is not a number");
      }
    }
  } else {
    const config::YamlReader dm = r.section("distortion");  // a map {k1, k2, p1, p2, k3}, or absent
    dm.read("k1", d.k1);
    dm.read("k2", d.k2);
    dm.read("p1", d.p1);
    dm.read("p2", d.p2);
    dm.read("k3", d.k3);
  }
  Eigen::Isometry3d camera_to_vehicle = mountFromYaml(r.section("mount"));
  camera_to_vehicle.linear() = camera_to_vehicle.linear() * bodyFromOptical();
  try {
    return CameraModel(in, d, camera_to_vehicle);
  } catch (const CameraModelError& e) {
    r.failHere(e.what());
  }
}

CameraModel CameraModel::fromYamlFile(const std::string& path, const std::string& key) {
  try {
    const auto root = config::YamlReader::loadFile(path);
    if (!root.has(key)) root.fail(key, "is required");
    const auto section = root.section(key);
    CameraModel m = fromYaml(section);
    section.finishSections();
    return m;
  } catch (const config::ConfigError& e) {
    throw CameraModelError(e.what());
  }
}

cv::Matx33d CameraModel::cameraMatrix() const {
  return {intrinsics_.fx, 0.0, intrinsics_.cx, 0.0, intrinsics_.fy, intrinsics_.cy, 0.0, 0.0, 1.0};
}

std::vector<double> CameraModel::distCoeffs() const {
  return {distortion_.k1, distortion_.k2, distortion_.p1, distortion_.p2, distortion_.k3};
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& ideal) const {
  const Distortion& d = distortion_;
  const double x = ideal.x(), y = ideal.y();
  const double r2 = x * x + y * y;
  double f, df;
  radial(d, r2, &f, &df);
  return {x * f + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x),
          y * f + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y};
}

Eigen::Vector2d CameraModel::undistort(const Eigen::Vector2d& distorted) const {
  if (distortion_.isZero()) return distorted;
  const Distortion& d = distortion_;
  Eigen::Vector2d u = distorted;
  for (int iter = 0; iter < 50; ++iter) {
    const double x = u.x(), y = u.y();
    const double r2 = x * x + y * y;
    double f, df;
    radial(d, r2, &f, &df);
    const Eigen::Vector2d residual = distort(u) - distorted;
    if (residual.squaredNorm() < 1e-30) break;
    // Jacobian of distort() at u.
    Eigen::Matrix2d j;
    j(0, 0) = f + 2.0 * x * x * df + 2.0 * d.p1 * y + 6.0 * d.p2 * x;
    j(0, 1) = 2.0 * x * y * df + 2.0 * d.p1 * x + 2.0 * d.p2 * y;
    j(1, 0) = 2.0 * x * y * df + 2.0 * d.p1 * x + 2.0 * d.p2 * y;
    j(1, 1) = f + 2.0 * y * y * df + 6.0 * d.p1 * y + 2.0 * d.p2 * x;
    const double det = j.determinant();
    if (std::abs(det) < 1e-12) break;  // fold of the polynomial: keep the best estimate
    const Eigen::Vector2d step = j.inverse() * residual;
    u -= step;
    if (step.squaredNorm() < 1e-28) break;
  }
  return u;
}

std::optional<Eigen::Vector2d> CameraModel::projectCamera(const Eigen::Vector3d& p) const {
  if (!(p.z() > kMinDepth)) return std::nullopt;
  const Eigen::Vector2d ideal(p.x() / p.z(), p.y() / p.z());
  if (ideal.squaredNorm() > max_r2_) return std::nullopt;
  const Eigen::Vector2d dist = distort(ideal);
  return Eigen::Vector2d(intrinsics_.fx * dist.x() + intrinsics_.cx,
                         intrinsics_.fy * dist.y() + intrinsics_.cy);
}

std::optional<Eigen::Vector2d> CameraModel::projectVehicle(const Eigen::Vector3d& p_vehicle) const {
  return projectCamera(vehicle_to_camera_ * p_vehicle);
}

std::optional<Eigen::Vector2d> CameraModel::projectCameraPinhole(const Eigen::Vector3d& p) const {
  if (!(p.z() > kMinDepth)) return std::nullopt;
  return Eigen::Vector2d(intrinsics_.fx * p.x() / p.z() + intrinsics_.cx,
                         intrinsics_.fy * p.y() / p.z() + intrinsics_.cy);
}

Eigen::Vector3d CameraModel::rayCamera(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d distorted((pixel.x() - intrinsics_.cx) / intrinsics_.fx,
                                  (pixel.y() - intrinsics_.cy) / intrinsics_.fy);
  const Eigen::Vector2d ideal = undistort(distorted);
  return Eigen::Vector3d(ideal.x(), ideal.y(), 1.0).normalized();
}

Eigen::Vector3d CameraModel::rayVehicle(const Eigen::Vector2d& pixel) const {
  return camera_to_vehicle_.linear() * rayCamera(pixel);
}

bool CameraModel::inImage(const Eigen::Vector2d& px) const {
  return px.x() >= -0.5 && px.y() >= -0.5 && px.x() < intrinsics_.width - 0.5 &&
         px.y() < intrinsics_.height - 0.5;
}

}  // namespace lanemap::camera
