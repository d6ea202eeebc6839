// Tests of sim::CameraRenderer: labels agree with where the world's geometry projects (paint
// corners, lanes, a parked car, the sky), every ground pixel's label and range agree with an
// analytic ray/plane intersection, yellow centre lines, shadows, light level, deterministic noise.
// Prints the render time per 640x360 frame.
#include "core/sim/camera_renderer.h"
#include "tests/render/test_worlds.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace lanemap::sim {
namespace {

using testing::StripedRoadWorld;
using testing::makeBox;

const std::string kVehicleYaml = std::string(LANEMAP_DATA_DIR) + "/../config/vehicle.yaml";

camera::CameraModel shippedCamera() { return camera::CameraModel::fromYamlFile(kVehicleYaml); }

// Vehicle at (east, 0) on the ground, heading east, pitched with the road grade (nose up on a climb).
Eigen::Isometry3d vehicleOnRoad(const StripedRoadWorld& world, double east) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(-std::atan(world.grade_e), Eigen::Vector3d::UnitY()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(east, 0.0, world.height(east, 0.0));
  return pose;
}

struct Pixel {
  int u, v;
};

// The pixel whose centre is nearest to the projection of an ENU ground point (must be in the image).
Pixel projectGround(const camera::CameraModel& cam, const Eigen::Isometry3d& vehicle_to_enu,
                    const StripedRoadWorld& world, double e, double n) {
  const Eigen::Vector3d p_enu(e, n, world.height(e, n));
  const auto px = cam.projectVehicle(vehicle_to_enu.inverse() * p_enu);
  EXPECT_TRUE(px && cam.inImage(*px)) << e << "," << n;
  if (!px) return {0, 0};
  return {static_cast<int>(std::lround(px->x())), static_cast<int>(std::lround(px->y()))};
}

LabelClass labelAt(const RenderedFrame& f, Pixel p) { return static_cast<LabelClass>(f.labels.at<uint8_t>(p.v, p.u)); }

double greyMean(const cv::Mat& bgr, Pixel p, int r = 2) {
  const cv::Rect box(p.u - r, p.v - r, 2 * r + 1, 2 * r + 1);
  const cv::Scalar m = cv::mean(bgr(box & cv::Rect(0, 0, bgr.cols, bgr.rows)));
  return (m[0] + m[1] + m[2]) / 3.0;
}

// Point margins below: at ~8 m from the camera a pixel covers ~2 cm across and ~10 cm along the
// road, so the nearest pixel centre lies within 1 cm / 5 cm of the projected point; the points sit
// 5 cm (across) and 10 cm (along) from every paint edge.
void expectDashCornerLabels(const StripedRoadWorld& world, const Eigen::Isometry3d& pose, double dash_start) {
  const camera::CameraModel cam = shippedCamera();
  const CameraRenderer renderer(cam);
  const RenderedFrame f = renderer.render(world, pose, /*ego_lanelet=*/1, /*seed=*/1);
  // Near corner of the dash on the left lane line: the dash covers east >= dash_start,
  // north in [1.675, 1.825]; the ego lane is north < 1.75, the left lane north >= 1.75.
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 0.1, 1.725)), LabelClass::kDashedLine);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 0.1, 1.800)), LabelClass::kDashedLine);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start - 0.1, 1.725)), LabelClass::kLaneEgo);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start - 0.1, 1.800)), LabelClass::kLaneLeft);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 0.1, 1.625)), LabelClass::kLaneEgo);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 0.1, 1.875)), LabelClass::kLaneLeft);
  // Right lane, right dash, curb and sidewalk on the right.
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 1.5, -3.5)), LabelClass::kLaneRight);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 1.5, -1.75)), LabelClass::kDashedLine);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 1.5, -5.35)), LabelClass::kCurb);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 1.5, -5.15)), LabelClass::kSolidLine);
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, dash_start + 1.5, -6.5)), LabelClass::kBackground);
}

TEST(CameraRenderer, DashCornerLabelsOnFlatGround) {
  StripedRoadWorld world;
  expectDashCornerLabels(world, vehicleOnRoad(world, 0.0), 9.0);
}

TEST(CameraRenderer, DashCornerLabelsOnAClimbWithBumps) {
  StripedRoadWorld world;
  world.base = 12.0;
  world.grade_e = 0.08;
  world.bump = 0.02;
  expectDashCornerLabels(world, vehicleOnRoad(world, 5.0), 18.0);
}

TEST(CameraRenderer, EveryGroundPixelAgreesWithTheAnalyticPlane) {
  StripedRoadWorld world;  // flat z = 0: the ray of pixel p meets it at t = -o.z / d.z
  const camera::CameraModel cam = shippedCamera();
  const CameraRenderer renderer(cam);
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 0.0);
  const RenderedFrame f = renderer.render(world, pose, 1, 2);
  const Eigen::Vector3d o = pose * cam.opticalCentreVehicle();
  int ground = 0, unexplained = 0, near_edge = 0;
  double worst_range = 0.0;
  for (int v = 0; v < cam.height(); ++v) {
    for (int u = 0; u < cam.width(); ++u) {
      const Eigen::Vector3d d = pose.linear() * cam.rayVehicle({u, v});
      const float range = f.range.at<float>(v, u);
      const double t = d.z() < 0 ? -o.z() / d.z() : INFINITY;
      if (!(t <= renderer.options().max_range_m)) {
        EXPECT_TRUE(std::isinf(range)) << u << "," << v;
        EXPECT_EQ(f.labels.at<uint8_t>(v, u), 0);
        continue;
      }
      ++ground;
      // Vertical hit tolerance 0.1 mm -> range error 0.1 mm / sin(depression); float storage.
      worst_range = std::max(worst_range, std::abs(range - t) / (1e-3 + 1e-4 / -d.z() + 1e-6 * t));
      const Eigen::Vector3d p = o + t * d;
      const auto expected = static_cast<uint8_t>(world.expectedLabel(p.x(), p.y()));
      if (f.labels.at<uint8_t>(v, u) == expected) continue;
      // A disagreement is only allowed where the surface changes within 1 cm of the true point.
      const Eigen::Vector3d a = o + (t - 0.01) * d, b = o + (t + 0.01) * d;
      if (world.expectedLabel(a.x(), a.y()) != world.expectedLabel(b.x(), b.y())) ++near_edge;
      else ++unexplained;
    }
  }
  EXPECT_GT(ground, 100000);  // ground fills a bit over half of the image
  EXPECT_EQ(unexplained, 0);
  EXPECT_LT(near_edge, 20);
  EXPECT_LE(worst_range, 1.0);
}

TEST(CameraRenderer, ParkedCarIsBackgroundAtTheRightRangeAndSkyIsBlue) {
  StripedRoadWorld world;
  // A red car 12 m ahead of the rear axle in the ego lane: its rear face is at east 12.
  world.obstacles.push_back(makeBox({14.2, 0.0, 0.75}, {2.2, 0.9, 0.75}, 0.0));
  const camera::CameraModel cam = shippedCamera();
  const CameraRenderer renderer(cam);
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 0.0);
  const RenderedFrame f = renderer.render(world, pose, 1, 3);
  const Pixel car = projectGround(cam, pose, world, 12.0, 0.0);  // bottom edge of the rear face...
  const Pixel face{car.u, car.v - 10};                           // ...and 10 px up the face
  EXPECT_EQ(labelAt(f, face), LabelClass::kBackground);
  const Eigen::Vector3d d = cam.rayVehicle({face.u, face.v});
  EXPECT_NEAR(f.range.at<float>(face.v, face.u), (12.0 - 1.6) / d.x(), 1e-4);  // slab distance
  const cv::Vec3b bgr = f.rgb.at<cv::Vec3b>(face.v, face.u);
  EXPECT_GT(bgr[2], bgr[1] + 30);  // red paint
  // The road just before the car is still the ego lane.
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, 11.5, 0.0)), LabelClass::kLaneEgo);
  // Top row: sky, background, infinite range, blue-ish.
  EXPECT_EQ(f.labels.at<uint8_t>(0, 320), 0);
  EXPECT_TRUE(std::isinf(f.range.at<float>(0, 320)));
  const cv::Vec3b sky = f.rgb.at<cv::Vec3b>(0, 320);
  EXPECT_GT(sky[0], sky[2] + 20);
}

TEST(CameraRenderer, CentreLineBetweenOppositeDirectionsIsYellow) {
  StripedRoadWorld world;
  world.left_is_opposite = true;
  const camera::CameraModel cam = shippedCamera();
  const CameraRenderer renderer(cam);
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 0.0);
  const RenderedFrame f = renderer.render(world, pose, 1, 4);
  const Pixel centre_line = projectGround(cam, pose, world, 10.0, 1.75);
  const Pixel lane_line = projectGround(cam, pose, world, 10.0, -1.75);  // white dash (9..12)
  EXPECT_EQ(labelAt(f, centre_line), LabelClass::kSolidLine);
  const cv::Vec3b y = f.rgb.at<cv::Vec3b>(centre_line.v, centre_line.u);
  const cv::Vec3b w = f.rgb.at<cv::Vec3b>(lane_line.v, lane_line.u);
  EXPECT_GT(y[2], y[0] + 80);                  // yellow: red well above blue
  EXPECT_LT(std::abs(w[2] - w[0]), 25);        // white: balanced
  EXPECT_GT(w[1], 150);
  // The opposite lane has no lane offset to the ego lane: background.
  EXPECT_EQ(labelAt(f, projectGround(cam, pose, world, 10.0, 3.5)), LabelClass::kBackground);

  // A World whose lane offsets span both directions (like SimWorld) says which lanelets are
  // opposite through the hook: the same solid line is white without it, yellow with it.
  StripedRoadWorld spanning;
  spanning.solid_left_line = true;
  ASSERT_TRUE(spanning.laneOffset(1, 2));
  const cv::Vec3b plain = renderer.render(spanning, pose, 1, 4).rgb.at<cv::Vec3b>(centre_line.v, centre_line.u);
  EXPECT_LT(std::abs(plain[2] - plain[0]), 25);
  RenderOptions hook;
  hook.opposite_directions = [](int64_t a, int64_t b) { return (a == 2) != (b == 2); };
  const cv::Vec3b hooked =
      CameraRenderer(cam, hook).render(spanning, pose, 1, 4).rgb.at<cv::Vec3b>(centre_line.v, centre_line.u);
  EXPECT_GT(hooked[2], hooked[0] + 80);
  // Edge lines have a lanelet on one side only: white even with the hook.
  const Pixel edge = projectGround(cam, pose, spanning, 10.0, 5.175);
  const cv::Vec3b e = CameraRenderer(cam, hook).render(spanning, pose, 1, 4).rgb.at<cv::Vec3b>(edge.v, edge.u);
  EXPECT_LT(std::abs(e[2] - e[0]), 25);
}

TEST(CameraRenderer, ObstacleShadowsDarkenTheGroundBehindThem) {
  StripedRoadWorld world;
  // A 3 m high box at the right edge; the sun in the south at 30 deg casts its shadow 5.2 m north.
  world.obstacles.push_back(makeBox({15.0, -4.5, 1.5}, {2.0, 0.5, 1.5}, 0.0, Obstacle::Kind::kBuilding));
  RenderOptions opt;
  opt.sun_azimuth_deg = 180.0;
  opt.sun_elevation_deg = 30.0;
  opt.sensor_noise = 0.0;
  opt.haze_distance_m = 1e9;  // no haze: the ratio below is then the lighting alone
  const camera::CameraModel cam = shippedCamera();
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 0.0);
  const RenderedFrame with = CameraRenderer(cam, opt).render(world, pose, 1, 5);
  opt.shadows = false;
  const RenderedFrame without = CameraRenderer(cam, opt).render(world, pose, 1, 5);
  const Pixel shaded = projectGround(cam, pose, world, 15.0, 0.0);
  const Pixel open = projectGround(cam, pose, world, 22.0, 0.0);
  // Lit asphalt: ambient 0.45 + 0.55 * 1.6 * sin 30 = 0.89; in shadow 0.45: ratio 0.51.
  EXPECT_NEAR(greyMean(with.rgb, shaded) / greyMean(without.rgb, shaded), 0.45 / 0.89, 0.08);
  EXPECT_NEAR(greyMean(with.rgb, open) / greyMean(without.rgb, open), 1.0, 0.02);
  EXPECT_EQ(cv::countNonZero(with.labels != without.labels), 0);  // shadows do not touch labels
}

TEST(CameraRenderer, NoiseIsSeededAndLightScales) {
  StripedRoadWorld world;
  const camera::CameraModel cam = shippedCamera();
  const CameraRenderer renderer(cam);
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 0.0);
  const RenderedFrame a = renderer.render(world, pose, 1, 42);
  const RenderedFrame b = renderer.render(world, pose, 1, 42);
  const RenderedFrame c = renderer.render(world, pose, 1, 43);
  EXPECT_EQ(cv::norm(a.rgb, b.rgb, cv::NORM_INF), 0.0);
  // Two independent N(0, 2.5) noises: E|x - y| = 2 * 2.5 / sqrt(pi) = 2.8 (rounding, clipping).
  const double mad = cv::norm(a.rgb, c.rgb, cv::NORM_L1) / (a.rgb.total() * 3.0);
  EXPECT_GT(mad, 2.0);
  EXPECT_LT(mad, 3.6);
  RenderOptions dim;
  dim.light = 0.5;
  const RenderedFrame d = CameraRenderer(cam, dim).render(world, pose, 1, 42);
  const cv::Scalar bright_mean = cv::mean(a.rgb), dim_mean = cv::mean(d.rgb);
  EXPECT_NEAR(dim_mean[1] / bright_mean[1], 0.5, 0.03);  // no channel saturates at light 1
}

TEST(CameraRenderer, RenderTimePerFrame) {
  StripedRoadWorld world;
  world.grade_e = 0.03;
  world.bump = 0.02;
  for (int i = 0; i < 12; ++i)  // parked cars on both sides
    world.obstacles.push_back(makeBox({8.0 + 6.0 * i, (i % 2 ? 4.4 : -4.4), 0.75}, {2.2, 0.9, 0.75}, 0.02 * i));
  world.obstacles.push_back(makeBox({40, 16, 6}, {20, 6, 6}, 0.0, Obstacle::Kind::kBuilding));
  const camera::CameraModel cam = shippedCamera();
  const CameraRenderer renderer(cam);
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 0.0);
  const RenderedFrame first = renderer.render(world, pose, 1, 0);  // also warms up the thread pool
  const int frames = 3;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) {
    const RenderedFrame f = renderer.render(world, pose, 1, i + 1);
    EXPECT_EQ(cv::countNonZero(f.labels != first.labels), 0);  // labels do not depend on the seed
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / frames;
  std::printf("[ info ] render 640x360: %.1f ms per frame (%d OpenCV threads)\n", 1e3 * s, cv::getNumThreads());
  if (const char* dir = std::getenv("LANEMAP_RENDER_DUMP")) {  // for looking at the images
    cv::imwrite(std::string(dir) + "/render_rgb.png", first.rgb);
    cv::imwrite(std::string(dir) + "/render_labels.png", first.labels * 25);
  }
  // The cars hide part of the side lanes but the ego lane ahead stays clear: > 5 % of the image.
  EXPECT_GT(cv::countNonZero(first.labels == static_cast<int>(LabelClass::kLaneEgo)), 640 * 360 / 20);
  EXPECT_GT(cv::countNonZero(first.labels == static_cast<int>(LabelClass::kLaneRight)), 1000);
}

}  // namespace
}  // namespace lanemap::sim

namespace lanemap::sim {
namespace {

// A bumpy climb with raised curbs (a 15 cm step: steeper than the march's slope bound, so the hint
// from the pixel below can fail there and the march must start again from the camera), parked cars
// and a building; counts its height calls.
struct CurbedCountingWorld : StripedRoadWorld {
  mutable std::atomic<long> height_calls{0};
  double height(double e, double n) const override {
    ++height_calls;
    return StripedRoadWorld::height(e, n) + (std::abs(n) >= 5.25 ? 0.15 : 0.0);
  }
};

TEST(CameraRenderer, MarchFromThePixelBelowHitsTheSameSurfaceWithFewerHeightCalls) {
  CurbedCountingWorld world;
  world.base = 3.0;
  world.grade_e = 0.05;
  world.bump = 0.03;
  for (int i = 0; i < 12; ++i)
    world.obstacles.push_back(makeBox({8.0 + 6.0 * i, (i % 2 ? 4.4 : -4.4), 3.0 + 0.05 * (8.0 + 6.0 * i) + 0.75},
                                      {2.2, 0.9, 0.75}, 0.02 * i));
  world.obstacles.push_back(makeBox({40, 16, 9}, {20, 6, 6}, 0.0, Obstacle::Kind::kBuilding));
  const camera::CameraModel cam = shippedCamera();
  RenderOptions from_origin;
  from_origin.march_from_pixel_below = false;
  const Eigen::Isometry3d pose = vehicleOnRoad(world, 2.0);
  world.height_calls = 0;
  const RenderedFrame a = CameraRenderer(cam, from_origin).render(world, pose, 1, 5);
  const long calls_origin = world.height_calls.exchange(0);
  const RenderedFrame b = CameraRenderer(cam).render(world, pose, 1, 5);
  const long calls_below = world.height_calls.load();
  std::printf("[ info ] height calls per frame: %ld from the camera, %ld from the pixel below\n", calls_origin, calls_below);
  EXPECT_LT(calls_below, 0.7 * calls_origin);

  // Where the two hits are not the same point within the march's tolerance, the ray only grazes the
  // ground between them: a crest poking above the ray by less than the march resolves (under
  // 1 mm at the min step, raycast.h), which one march's samples happened to catch and the other's
  // stepped over. Elsewhere the labels differ only at paint edges.
  const Eigen::Vector3d o = pose * cam.opticalCentreVehicle();
  int ground = 0, grazing = 0, label_differs = 0, unexplained = 0, hit_differs = 0;
  double deepest = 0.0;
  for (int v = 0; v < cam.height(); ++v) {
    for (int u = 0; u < cam.width(); ++u) {
      const float ra = a.range.at<float>(v, u), rb = b.range.at<float>(v, u);
      if (std::isinf(ra) != std::isinf(rb)) ++hit_differs;
      const bool same_label = a.labels.at<uint8_t>(v, u) == b.labels.at<uint8_t>(v, u);
      if (std::isinf(ra) || std::isinf(rb)) {
        if (!same_label) ++label_differs;
        continue;
      }
      const Eigen::Vector3d d = pose.linear() * cam.rayVehicle({u, v});
      ++ground;
      // Each hit is within the march's tolerance of the surface: 1 mm along the ray, or 0.1 mm
      // vertically (more along a grazing ray); two such hits differ by at most twice that.
      const double apart = std::abs(ra - rb) / (1e-3 + 1e-4 / std::max(1e-3, -d.z()) + 1e-6 * ra);
      if (apart <= 2.0) {
        // A label may differ only where the surface changes within 1 cm of the hit.
        const Eigen::Vector3d p0 = o + (ra - 0.01) * d, p1 = o + (ra + 0.01) * d;
        if (!same_label) ++label_differs;
        if (!same_label && world.expectedLabel(p0.x(), p0.y()) == world.expectedLabel(p1.x(), p1.y())) ++unexplained;
        continue;
      }
      ++grazing;
      for (double t = std::min(ra, rb); t <= std::max(ra, rb); t += 0.005) {
        const Eigen::Vector3d p = o + t * d;
        deepest = std::max(deepest, world.StripedRoadWorld::height(p.x(), p.y()) + (std::abs(p.y()) >= 5.25 ? 0.15 : 0.0) - p.z());
      }
    }
  }
  std::printf("[ info ] %d ground pixels: %d hit another crest of a grazing ray (the ray at most %.2f mm under the ground"
              " between the two), %d labels differ elsewhere\n", ground, grazing, 1e3 * deepest, label_differs);
  EXPECT_GT(ground, 100000);
  EXPECT_EQ(hit_differs, 0);
  EXPECT_LE(deepest, 2e-3);
  EXPECT_LT(grazing, ground / 1000);
  EXPECT_EQ(unexplained, 0) << "labels differ away from a surface edge";
  EXPECT_LE(label_differs, ground / 200) << "more than 0.5 % of the labels differ";
  // The colours: the same but where the hit moved across a paint or texture-cell edge.
  cv::Mat diff, channels[3];
  cv::absdiff(a.rgb, b.rgb, diff);
  cv::split(diff, channels);
  const int colour_differs = cv::countNonZero(channels[0] | channels[1] | channels[2]);
  std::printf("[ info ] %d pixels differ in colour\n", colour_differs);
  EXPECT_LE(colour_differs, ground / 100);
}

}  // namespace
}  // namespace lanemap::sim
