// The road's crown (core/bev/road_crown.h) against geometry worked out by hand: a straight two-way
// road along ENU x crowned at its OSM line (y = 0) with k = 0.02, the car in the right lane resting
// on the slope; the ground's height, a pixel ray's hit across the crown and on the car's side, the
// crown fading out towards a junction, and the projector placing a labelled pixel on the crowned
// ground where the flat plane misses it by a cell or more.
#include "core/bev/projector.h"
#include "core/bev/road_crown.h"
#include "tests/intersections/fixture.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using lanemap::bev::CrownOptions;
using lanemap::bev::RoadCrown;

constexpr double kK = 0.02;
CrownOptions twoPercent() {
  CrownOptions o;
  o.slope = kK;
  return o;
}
// The hand-made network's nodes go through latitude and longitude: its line lies within millimetres
// of y = 0, so heights agree to a few 1e-5 m.
constexpr double kTolZ = 2e-4;

// A two-way road along x from -200 to 100 m, crossed at x = 100 by a north-south road.
lanemap::skeleton::Skeleton crossroads() {
  lanemap::testing::Net n;
  n.node(1, -200.0, 0.0);
  n.node(2, 100.0, 0.0);
  n.node(3, 100.0, -100.0);
  n.node(4, 100.0, 100.0);
  n.way(10, {1, 2});
  n.way(11, {3, 2, 4});
  return n.build();
}

// The true ground: the crown's profile about y = 0 (the line at height 0), full strength.
double trueZ(double y) { return -kK * std::abs(y); }

// The car heading east at x, in the lane centred y = -1.75: it rests on the slope between its wheels
// (both right of the crown), rolled left side up by atan(k).
Eigen::Isometry3d carAt(double x, double y = -1.75) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double roll = std::atan((trueZ(y + 0.8) - trueZ(y - 0.8)) / 1.6);
  t.linear() = Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, trueZ(y));
  return t;
}

const lanemap::skeleton::AtomicRoad& eastbound(const lanemap::skeleton::Skeleton& sk) {
  for (const auto& r : sk.roads()) {
    if (r.way_id == 10 && r.polyline.back().x() > r.polyline.front().x()) return r;
  }
  throw std::runtime_error("no eastbound road");
}

TEST(RoadCrown, TheGroundFallsFromTheLineToTheKerbsAndTheCarsSideIsItsPlane) {
  const auto sk = crossroads();
  const auto crown = RoadCrown::around(sk, carAt(-100.0), twoPercent());
  ASSERT_TRUE(crown);
  EXPECT_EQ(crown->roadId(), eastbound(sk).id);
  for (const double y : {-5.0, -3.5, -1.75, 0.0, 1.75, 3.5, 5.25}) {
    EXPECT_NEAR(crown->groundZ({-90.0, y}), trueZ(y), kTolZ) << "y " << y;
  }
  // The plane under the car (the flat model) is the ground on the car's side only: across the
  // crown it lies 2 k per metre above it.
  const Eigen::Isometry3d car = carAt(-100.0);
  const Eigen::Vector3d up = car.linear().col(2);
  const auto planeZ = [&](double x, double y) {
    const Eigen::Vector3d o = car.translation();
    return o.z() - (up.x() * (x - o.x()) + up.y() * (y - o.y())) / up.z();
  };
  EXPECT_NEAR(planeZ(-90.0, -5.0), trueZ(-5.0), 1e-9);
  EXPECT_NEAR(planeZ(-90.0, 5.25) - trueZ(5.25), 2 * kK * 5.25, 1e-9);
}

TEST(RoadCrown, ARayMeetsTheCrownedGroundWhereTheFlatPlaneFallsShort) {
  const auto sk = crossroads();
  const Eigen::Isometry3d car = carAt(-100.0);
  const auto crown = RoadCrown::around(sk, car, twoPercent());
  ASSERT_TRUE(crown);
  const Eigen::Vector3d c = car * Eigen::Vector3d(1.5, 0.0, 1.5);  // a camera 1.5 m up
  const Eigen::Vector3d up = car.linear().col(2);
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(-88.0, 5.25), Eigen::Vector2d(-80.0, 1.75), Eigen::Vector2d(-85.0, -5.0),
                                  Eigen::Vector2d(-75.0, 8.0)}) {
    const Eigen::Vector3d target(q.x(), q.y(), trueZ(q.y()));
    const Eigen::Vector3d dir = (target - c).normalized();
    const double t_flat = up.dot(car.translation() - c) / up.dot(dir);  // the ray on the car's plane
    const Eigen::Vector2d flat = (c + t_flat * dir).head<2>();
    size_t hint = 0;
    const auto h = crown->hit(c, dir, t_flat, 100.0, hint);
    ASSERT_TRUE(h) << q.transpose();
    EXPECT_LT((*h - q).norm(), 0.002) << q.transpose();
    if (q.y() > 0.0) {
      // Across the crown the flat plane pulls the point towards the car by decimetres to metres.
      EXPECT_GT(q.y() - flat.y(), 0.1) << q.transpose();
    } else {
      EXPECT_LT((flat - q).norm(), 1e-6) << "the car's side is its plane: " << q.transpose();
    }
  }
}

TEST(RoadCrown, TheCrownFadesOutTowardsTheJunctionAndIsOffWithNoRoadOrSlope) {
  const auto sk = crossroads();
  const auto& road = eastbound(sk);
  ASSERT_LT(road.s_end, road.length - 1.0) << "the crossroads' ROI";
  const auto crown = RoadCrown::around(sk, carAt(-100.0), twoPercent());
  ASSERT_TRUE(crown);
  const double x0 = road.polyline.front().x();
  const double half = road.s_end - 4.0;  // fade_m 8: half strength
  EXPECT_NEAR(crown->groundZ({x0 + half, -5.0}), -kK * 5.0 * 0.5, kTolZ);
  EXPECT_NEAR(crown->groundZ({x0 + half, 5.0}), -kK * 5.0 * 0.5, kTolZ);
  EXPECT_NEAR(crown->groundZ({x0 + road.s_end + 2.0, -5.0}), 0.0, kTolZ) << "inside the junction's ROI: flat at the line's height";
  EXPECT_NEAR(crown->groundZ({x0 + 150.0, 30.0}), -kK * twoPercent().max_offset_m, kTolZ) << "capped past the kerbs";

  EXPECT_FALSE(RoadCrown::around(sk, carAt(-100.0), CrownOptions{})) << "off by default (slope 0)";
  EXPECT_FALSE(RoadCrown::around(sk, carAt(-100.0, 40.0), twoPercent())) << "no road within 8 m";
}

TEST(RoadCrown, TheProjectorPutsAPixelAcrossTheCrownOnItsCell) {
  const auto sk = crossroads();
  // A distortion-free camera 1.5 m up looking ahead and 10 degrees down.
  lanemap::camera::Intrinsics in;
  in.fx = in.fy = 400.0;
  in.cx = 320.0;
  in.cy = 180.0;
  in.width = 640;
  in.height = 360;
  Eigen::Isometry3d optical = Eigen::Isometry3d::Identity();
  optical.translation() = Eigen::Vector3d(1.5, 0.0, 1.5);
  optical.linear() = Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                     lanemap::camera::bodyFromOptical();
  const lanemap::camera::CameraModel camera(in, {}, optical);
  lanemap::bev::ProjectorOptions po;
  po.sample_spacing_m = 0.0;
  const lanemap::bev::Projector projector(camera, po);
  const Eigen::Isometry3d car = carAt(-100.0);
  // The pixel that sees the ground at (-86, 5.25) (across the crown, 14 m ahead).
  const Eigen::Vector3d target(-86.0, 5.25, trueZ(5.25));
  const Eigen::Vector3d in_cam = (car * optical).inverse() * target;
  const int u = static_cast<int>(std::lround(320.0 + 400.0 * in_cam.x() / in_cam.z()));
  const int v = static_cast<int>(std::lround(180.0 + 400.0 * in_cam.y() / in_cam.z()));
  cv::Mat labels(360, 640, CV_8UC1, cv::Scalar(0));
  labels.at<uint8_t>(v, u) = 8;  // crosswalk paint
  const auto crown = RoadCrown::around(sk, car, twoPercent());
  ASSERT_TRUE(crown);
  const auto cellOf = [](const lanemap::bev::FrameSplat& s) {
    for (const auto& c : s.cells) {
      if (c.layers & lanemap::bev::bit(lanemap::bev::Layer::kCrosswalk)) return Eigen::Vector2d((c.x + 0.5) * 0.1, (c.y + 0.5) * 0.1);
    }
    return Eigen::Vector2d(1e9, 1e9);
  };
  const auto crowned = projector.project(labels, car, nullptr, &*crown);
  const auto flat = projector.project(labels, car);
  EXPECT_GT(crowned.crowned, crowned.pixels / 4);
  EXPECT_EQ(flat.crowned, 0u);
  // Within the pixel's footprint (about 0.15 m there) of the true point; the flat plane 0.3 m or more short.
  EXPECT_LT((cellOf(crowned) - target.head<2>()).norm(), 0.25);
  EXPECT_GT((cellOf(flat) - target.head<2>()).norm(), 0.3);
  EXPECT_LT(cellOf(flat).y(), target.y() - 0.1) << "pulled towards the car";
}

}  // namespace
