// The BEV projection (core/bev/projector.h) against geometry computed by hand: a pinhole camera at a
// known height over a flat plane puts pixel row v at distance h * f / (v - cy); a labelled patch
// lands on exactly the cells those distances give; a raised mesh moves it to where the ray meets the
// mesh; lane-class transitions become lane separations; the shipped (distorted) camera's landed
// cells project back onto their pixels.
#include "core/bev/projector.h"
#include "core/camera/camera_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <utility>

namespace {

using lanemap::bev::BevGrid;
using lanemap::bev::FrameSplat;
using lanemap::bev::Layer;
using lanemap::bev::Projector;
using lanemap::bev::ProjectorOptions;
using lanemap::camera::CameraModel;
using Cells = std::set<std::pair<int, int>>;

constexpr double kF = 400.0, kH = 1.5;  // focal length (px), camera height (m)

// A distortion-free camera looking straight ahead (no pitch) from 1.5 m; pixel (320, 180) is the
// principal point, so pixel (320, v) looks down by atan((v - 180) / 400).
CameraModel levelCamera() {
  lanemap::camera::Intrinsics in;
  in.fx = in.fy = kF;
  in.cx = 320.0;
  in.cy = 180.0;
  in.width = 640;
  in.height = 360;
  Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
  body.translation() = Eigen::Vector3d(0.0, 0.0, kH);
  Eigen::Isometry3d optical = body;
  optical.linear() = lanemap::camera::bodyFromOptical();
  return CameraModel(in, {}, optical);
}

// Vehicle at ENU (100.03, 50.07, 10), facing north (yaw 90 deg).
Eigen::Isometry3d northPose() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(100.03, 50.07, 10.0);
  return t;
}

// Where pixel (u, v) of levelCamera meets the ground z = ground_z (vehicle frame), in ENU.
Eigen::Vector2d groundHit(double u, double v, double ground_z = 0.0) {
  const double t = (kH - ground_z) / ((v - 180.0) / kF);  // forward distance
  const Eigen::Vector3d vehicle(t, -t * (u - 320.0) / kF, ground_z);
  return (northPose() * vehicle).head<2>();
}

Cells cellsWith(const FrameSplat& s, Layer layer) {
  Cells out;
  for (const auto& c : s.cells) {
    if (c.layers & lanemap::bev::bit(layer)) out.insert({c.x, c.y});
  }
  return out;
}

ProjectorOptions everyPixel() {
  ProjectorOptions o;
  o.sample_spacing_m = 0.0;
  return o;
}

TEST(Projector, CandidatePixelsAreThoseWhoseGroundHitIsWithinRange) {
  const Projector p(levelCamera(), everyPixel());
  size_t expected = 0;
  for (int v = 181; v < 360; ++v) {
    for (int u = 0; u < 640; ++u) {
      const double x = kH * kF / (v - 180.0), y = x * (u - 320.0) / kF;
      if (std::hypot(x, y) <= 30.0) ++expected;
    }
  }
  EXPECT_EQ(p.candidatePixels(), expected);
  EXPECT_EQ(p.latticePixels(), expected) << "sample_spacing_m = 0 projects every candidate";
  // Row 200 looks down by 20/400: exactly 30 m ahead at the centre column.
  ProjectorOptions sparse;
  const Projector q(levelCamera(), sparse);
  EXPECT_LT(q.latticePixels(), expected / 2) << "the lattice thins out the near rows";
  EXPECT_GT(q.latticePixels(), 5000u);
}

TEST(Projector, ALabelledPatchLandsOnTheCellsGeometryGives) {
  const Projector p(levelCamera(), everyPixel());
  cv::Mat labels(360, 640, CV_8UC1, cv::Scalar(0));
  labels(cv::Rect(300, 250, 41, 51)).setTo(8);  // crosswalk: columns 300..340, rows 250..300
  ASSERT_EQ(p.check(labels), lanemap::bev::LabelCheck::kOk);
  const FrameSplat s = p.project(labels, northPose());
  BevGrid grid;
  Cells expected;
  for (int v = 250; v <= 300; ++v) {
    for (int u = 300; u <= 340; ++u) {
      const auto c = grid.cellOf(groundHit(u, v));
      expected.insert({c.x(), c.y()});
    }
  }
  // Row 300 is 1.5 * 400 / 120 = 5 m ahead, row 250 is 8.57 m ahead: north of the car.
  EXPECT_NEAR(groundHit(320, 300).y(), 50.07 + 5.0, 1e-9);
  EXPECT_EQ(cellsWith(s, Layer::kCrosswalk), expected);
  EXPECT_TRUE(cellsWith(s, Layer::kDrivable).empty());
  // Every cell seen counts as observed, once: the splat has no duplicate cells.
  EXPECT_EQ(cellsWith(s, Layer::kObserved).size(), s.cells.size());
  EXPECT_EQ(s.flat, s.pixels);
  EXPECT_EQ(s.mesh_hits, 0u);
}

lanemap::ground::TriangleMesh planeMesh(double x0, double x1, double z) {
  std::vector<Eigen::Vector3d> pts;
  for (double x = x0; x <= x1 + 1e-9; x += 1.0) {
    for (double y = -10.0; y <= 10.0; y += 1.0) pts.push_back(northPose() * Eigen::Vector3d(x, y, z));
  }
  return lanemap::ground::triangulateGround(pts, 0.0);
}

TEST(Projector, AMeshMovesPixelsToWhereTheRayMeetsItAndFallsBackToFlatOutsideIt) {
  const Projector p(levelCamera(), everyPixel());
  cv::Mat labels(360, 640, CV_8UC1, cv::Scalar(0));
  labels.at<uint8_t>(300, 320) = 7;  // 5 m ahead on the flat ground
  labels.at<uint8_t>(200, 320) = 6;  // 30 m ahead on the flat ground
  // The ground 0.5 m higher from 2 m to 12 m ahead: row 300 meets it at (1.5 - 0.5) * 400 / 120.
  const lanemap::ground::MeshGround raised(planeMesh(2.0, 12.0, 0.5));
  const FrameSplat s = p.project(labels, northPose(), &raised);
  BevGrid grid;
  const auto solid = grid.cellOf(groundHit(320, 300, 0.5));
  EXPECT_NEAR(groundHit(320, 300, 0.5).y() - 50.07, 10.0 / 3.0, 1e-9);
  EXPECT_EQ(cellsWith(s, Layer::kSolidLine), (Cells{{solid.x(), solid.y()}}));
  // Row 200 passes over the raised mesh (1.5 - 12 * 0.05 = 0.9 m high at its far end) and finds no
  // triangle under its flat hit (30 m): flat.
  const auto dashed = grid.cellOf(groundHit(320, 200));
  EXPECT_EQ(cellsWith(s, Layer::kDashedLine), (Cells{{dashed.x(), dashed.y()}}));
  EXPECT_GT(s.mesh_hits, 0u);
  EXPECT_GT(s.flat, 0u);

  // A mesh 3 m below, under the flat hits up to 12 m: those rays pass over it within range, so
  // they are dropped rather than put on the flat plane.
  const lanemap::ground::MeshGround sunk(planeMesh(0.0, 12.0, -3.0));
  const FrameSplat d = p.project(labels, northPose(), &sunk);
  EXPECT_TRUE(cellsWith(d, Layer::kSolidLine).empty());
  EXPECT_GT(d.dropped, 0u);
}

TEST(Projector, LaneClassTransitionsBecomeLaneSeparations) {
  const Projector p(levelCamera(), everyPixel());
  cv::Mat labels(360, 640, CV_8UC1, cv::Scalar(0));
  const int v = 300;  // 5 m ahead: a pixel is 5/400 = 1.25 cm wide
  labels.row(v).colRange(100, 300).setTo(2);  // left lane
  labels.row(v).colRange(300, 310).setTo(6);  // 12.5 cm of dashed paint
  labels.row(v).colRange(310, 400).setTo(1);  // ego lane, then right lane touching it (no paint)
  labels.row(v).colRange(400, 500).setTo(3);
  labels.row(v).colRange(500, 510).setTo(0);  // background between right and right-right: no separation
  labels.row(v).colRange(510, 600).setTo(5);
  const FrameSplat s = p.project(labels, northPose());
  BevGrid grid;
  Cells paint, touching;
  for (int u = 300; u < 310; ++u) {
    const auto c = grid.cellOf(groundHit(u, v));
    paint.insert({c.x(), c.y()});
  }
  for (int u : {399, 400}) {
    const auto c = grid.cellOf(groundHit(u, v));
    touching.insert({c.x(), c.y()});
  }
  Cells expected = paint;
  expected.insert(touching.begin(), touching.end());
  EXPECT_EQ(cellsWith(s, Layer::kLaneSeparation), expected);
  EXPECT_EQ(cellsWith(s, Layer::kDashedLine), paint);
  // Drivable covers the lane pixels.
  const auto ego = grid.cellOf(groundHit(350, v));
  EXPECT_TRUE(cellsWith(s, Layer::kDrivable).count({ego.x(), ego.y()}));
  const auto rr = grid.cellOf(groundHit(550, v));
  EXPECT_TRUE(cellsWith(s, Layer::kDrivable).count({rr.x(), rr.y()}));
}

TEST(Projector, TheShippedCameraWithDistortionLandsEachPixelInTheCellItSees) {
  const CameraModel cam = CameraModel::fromYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/vehicle.yaml");
  const Projector p(cam, everyPixel());
  cv::Mat labels(cam.height(), cam.width(), CV_8UC1, cv::Scalar(0));
  std::vector<cv::Point> px;
  for (int v = 220; v < cam.height(); v += 23) {
    for (int u = 5; u < cam.width(); u += 57) px.emplace_back(u, v);
  }
  const Eigen::Isometry3d pose = northPose();
  BevGrid grid;
  int checked = 0;
  for (const auto& q : px) {
    labels.setTo(0);
    labels.at<uint8_t>(q) = 9;
    const Cells curb = cellsWith(p.project(labels, pose), Layer::kCurb);
    if (curb.empty()) continue;  // beyond 30 m
    ASSERT_EQ(curb.size(), 1u);
    // The pixel lies inside the image of its cell: project the cell's corners with the forward
    // model (distortion applied, no Newton iteration), check the pixel is within their box.
    const auto [cx, cy] = *curb.begin();
    Eigen::AlignedBox2d box;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d corner = grid.cellCentre({cx, cy}) + 0.05 * Eigen::Vector2d(k & 1 ? 1 : -1, k & 2 ? 1 : -1);
      const Eigen::Vector3d vehicle = pose.inverse() * Eigen::Vector3d(corner.x(), corner.y(), 10.0);
      const auto pix = cam.projectVehicle(vehicle);
      ASSERT_TRUE(pix);
      box.extend(*pix);
    }
    EXPECT_TRUE(box.contains(Eigen::Vector2d(q.x, q.y))) << "pixel " << q.x << "," << q.y;
    ++checked;
  }
  EXPECT_GT(checked, 40);
}

TEST(Projector, RejectsLabelImagesOfTheWrongSizeTypeOrClasses) {
  const Projector p(levelCamera());
  EXPECT_EQ(p.check(cv::Mat(360, 640, CV_8UC1, cv::Scalar(10))), lanemap::bev::LabelCheck::kOk);
  EXPECT_EQ(p.check(cv::Mat(360, 639, CV_8UC1, cv::Scalar(0))), lanemap::bev::LabelCheck::kWrongSize);
  EXPECT_EQ(p.check(cv::Mat(360, 640, CV_16UC1, cv::Scalar(0))), lanemap::bev::LabelCheck::kWrongType);
  cv::Mat bad(360, 640, CV_8UC1, cv::Scalar(0));
  bad.at<uint8_t>(359, 639) = 11;
  EXPECT_EQ(p.check(bad), lanemap::bev::LabelCheck::kUnknownClass);
}

}  // namespace
