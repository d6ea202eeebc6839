// Tests of camera::CameraModel: the shipped config, projection/unprojection round trips, the
// distortion model against OpenCV, the validity limits and the YAML errors.
#include "core/camera/camera_model.h"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <random>
#include <string>

namespace lanemap::camera {
namespace {

const std::string kVehicleYaml = std::string(LANEMAP_DATA_DIR) + "/../config/vehicle.yaml";
constexpr double kDeg = M_PI / 180.0;

CameraModel shippedCamera() { return CameraModel::fromYamlFile(kVehicleYaml); }

CameraModel strongDistortionCamera() {
  Intrinsics in{500.0, 480.0, 330.0, 170.0, 640, 360};
  Distortion d{-0.28, 0.09, 0.0012, -0.0008, -0.01};
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix() * bodyFromOptical();
  pose.translation() = Eigen::Vector3d(1.0, 0.2, 1.3);
  return CameraModel(in, d, pose);
}

TEST(CameraModel, ShippedConfigMatchesTheBrief) {
  const CameraModel cam = shippedCamera();
  EXPECT_EQ(cam.width(), 640);
  EXPECT_EQ(cam.height(), 360);
  // Horizontal FOV of the pinhole part: 2 atan(320 / fx) ~ 75 deg (fx rounded to 0.01 px).
  EXPECT_NEAR(2.0 * std::atan(320.0 / cam.intrinsics().fx) / kDeg, 75.0, 0.01);
  EXPECT_NEAR(cam.distortion().k1, -0.05, 1e-12);
  const Eigen::Vector3d c = cam.opticalCentreVehicle();
  EXPECT_NEAR(c.x(), 1.6, 1e-12);
  EXPECT_NEAR(c.y(), 0.0, 1e-12);
  EXPECT_NEAR(c.z(), 1.45, 1e-12);
  // The principal ray looks forward and 4 deg down (exact up to floating point).
  const Eigen::Vector3d axis = cam.rayVehicle({cam.intrinsics().cx, cam.intrinsics().cy});
  EXPECT_NEAR(axis.x(), std::cos(4 * kDeg), 1e-12);
  EXPECT_NEAR(axis.y(), 0.0, 1e-12);
  EXPECT_NEAR(axis.z(), -std::sin(4 * kDeg), 1e-12);
  // Image right is vehicle right (-y), image down is vehicle down.
  EXPECT_LT(cam.rayVehicle({600, 180}).y(), -0.5);
  EXPECT_LT(cam.rayVehicle({320, 350}).z(), -0.3);
  // The ground 10 m ahead on the centre line lies below the image centre, on the middle column.
  const auto px = cam.projectVehicle({10.0, 0.0, 0.0});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x(), 319.5, 1e-9);
  EXPECT_GT(px->y(), 179.5);
  EXPECT_TRUE(cam.inImage(*px));
}

TEST(CameraModel, ProjectUnprojectRoundTripBelowMicroPixel) {
  for (const CameraModel& cam : {shippedCamera(), strongDistortionCamera()}) {
    double worst = 0.0;
    for (int v = 0; v < cam.height(); v += 7) {
      for (int u = 0; u < cam.width(); u += 7) {
        const Eigen::Vector2d px(u + 0.25, v - 0.3);
        for (const double depth : {0.5, 7.0, 120.0}) {
          const Eigen::Vector3d p_vehicle = cam.opticalCentreVehicle() + depth * cam.rayVehicle(px);
          const auto back = cam.projectVehicle(p_vehicle);
          ASSERT_TRUE(back) << u << "," << v;
          worst = std::max(worst, (*back - px).norm());
        }
      }
    }
    // The brief's bound: 1e-6 px (Newton converges to ~1e-12 in normalized units).
    EXPECT_LT(worst, 1e-6);
  }
}

TEST(CameraModel, DistortionRoundTripAndAgreesWithOpenCv) {
  const CameraModel cam = strongDistortionCamera();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-0.75, 0.75);
  std::vector<cv::Point3d> object;
  std::vector<Eigen::Vector2d> ideal;
  double worst_px = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d x(uni(rng), 0.6 * uni(rng));
    const Eigen::Vector2d back = cam.undistort(cam.distort(x));
    worst_px = std::max(worst_px, ((back - x).array() * Eigen::Array2d(cam.intrinsics().fx, cam.intrinsics().fy)).matrix().norm());
    object.emplace_back(x.x(), x.y(), 1.0);
    ideal.push_back(x);
  }
  EXPECT_LT(worst_px, 0.01);  // the brief's bound; measured ~1e-10 px
  EXPECT_LT(worst_px, 1e-6);

  // Same pixels as cv::projectPoints (points given in the camera frame: zero rvec/tvec).
  std::vector<cv::Point2d> cv_px;
  cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cam.cameraMatrix(), cam.distCoeffs(), cv_px);
  double worst_cv = 0.0;
  for (size_t i = 0; i < object.size(); ++i) {
    const auto ours = cam.projectCamera({object[i].x, object[i].y, object[i].z});
    ASSERT_TRUE(ours);
    worst_cv = std::max(worst_cv, std::hypot(ours->x() - cv_px[i].x, ours->y() - cv_px[i].y));
  }
  EXPECT_LT(worst_cv, 1e-9);
}

TEST(CameraModel, RejectsPointsBehindOrBeyondTheFold) {
  const CameraModel cam = shippedCamera();
  EXPECT_FALSE(cam.projectVehicle({-5.0, 0.0, 1.0}));   // behind the vehicle
  EXPECT_FALSE(cam.projectCamera({0.0, 0.0, 0.0}));
  EXPECT_FALSE(cam.projectCamera({1.0, 0.0, -1.0}));
  // The shipped distortion is monotonic everywhere: no fold.
  EXPECT_TRUE(std::isinf(cam.maxValidRadius2()));
  // k1 = -0.3 alone: d(r (1 + k1 r^2))/dr = 1 + 3 k1 r^2 = 0 at r^2 = 1/0.9.
  const CameraModel folded({400, 400, 320, 180, 640, 360}, {-0.3, 0, 0, 0, 0}, Eigen::Isometry3d::Identity());
  EXPECT_NEAR(folded.maxValidRadius2(), 1.0 / 0.9, 1e-9);
  EXPECT_TRUE(folded.projectCamera({1.0, 0.0, 1.0}));    // r^2 = 1
  EXPECT_FALSE(folded.projectCamera({1.1, 0.0, 1.0}));   // r^2 = 1.21 > 1.11
}

TEST(CameraModel, YamlErrorsNameTheKey) {
  YAML::Node node = YAML::Load(
      "{width: 640, height: 360, fx: 400, fy: 400, cx: 320, cy: 180, mount: {x: 1, y: 0, z: 1}}");
  EXPECT_NO_THROW(CameraModel::fromYaml(node));
  YAML::Node no_fx = YAML::Clone(node);
  no_fx.remove("fx");
  try {
    CameraModel::fromYaml(no_fx);
    FAIL() << "missing fx accepted";
  } catch (const CameraModelError& e) {
    EXPECT_NE(std::string(e.what()).find("'fx'"), std::string::npos) << e.what();
  }
  YAML::Node no_mount_z = YAML::Clone(node);
  no_mount_z["mount"].remove("z");
  EXPECT_THROW(CameraModel::fromYaml(no_mount_z), CameraModelError);
  YAML::Node bad_width = YAML::Clone(node);
  bad_width["width"] = "wide";
  EXPECT_THROW(CameraModel::fromYaml(bad_width), CameraModelError);
  YAML::Node zero_fx = YAML::Clone(node);
  zero_fx["fx"] = 0.0;
  EXPECT_THROW(CameraModel::fromYaml(zero_fx), CameraModelError);
  // Distortion as OpenCV's list, or a map; anything else is an error.
  YAML::Node listed = YAML::Clone(node);
  listed["distortion"] = YAML::Load("[-0.1, 0.02, 0.001, 0.002, 0.003]");
  const Distortion d = CameraModel::fromYaml(listed).distortion();
  EXPECT_EQ(d.k1, -0.1);
  EXPECT_EQ(d.p2, 0.002);
  EXPECT_EQ(d.k3, 0.003);
  listed["distortion"] = YAML::Load("[-0.1, 0.02]");
  EXPECT_THROW(CameraModel::fromYaml(listed), CameraModelError);
  listed["distortion"] = "strong";
  EXPECT_THROW(CameraModel::fromYaml(listed), CameraModelError);
  try {
    CameraModel::fromYamlFile("/nonexistent/vehicle.yaml");
    FAIL();
  } catch (const CameraModelError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/vehicle.yaml"), std::string::npos);
  }
}

TEST(CameraModel, MountAnglesFollowTheDocumentedConvention) {
  // pitch +10 deg: nose down; yaw +90 deg: looking left (+y).
  const Eigen::Isometry3d pitched = mountFromYaml(YAML::Load("{x: 0, y: 0, z: 0, pitch_deg: 10}"), "t");
  EXPECT_NEAR((pitched.linear() * Eigen::Vector3d::UnitX()).z(), -std::sin(10 * kDeg), 1e-12);
  const Eigen::Isometry3d yawed = mountFromYaml(YAML::Load("{x: 0, y: 0, z: 0, yaw_deg: 90}"), "t");
  EXPECT_NEAR((yawed.linear() * Eigen::Vector3d::UnitX()).y(), 1.0, 1e-12);
}

}  // namespace
}  // namespace lanemap::camera
