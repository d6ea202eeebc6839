// METHOD.md section 3's ablation on the simulator's crowned, hilly West Oakland: project the truth
// labels (the renderer's label image, as on SEMANTIC_FRONT_TRUTH) of frames along a drive once with
// the flat plane under the car and once with the Delaunay mesh of the simulated VLP-16 sweep taken
// just before the frame (ground extraction + triangulation of core/ground), both with the true pose.
// Scored against the world's truth: how far the projected lane-line cells are from the true line
// strings, and how many projected line / crosswalk cells lie on that paint in the world. Prints
// both; the mesh must win. A third projection without the LIDAR, on the driven road's crown
// (core/bev/road_crown.h), must beat the flat plane and lose to the mesh.
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

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace {

using namespace lanemap;

const std::string kSource = LANEMAP_SOURCE_DIR;

struct Segment {
  Eigen::Vector2d a, b;
};

double distanceToSegments(const Eigen::Vector2d& p, const std::vector<Segment>& segs) {
  double best = 1e9;
  for (const auto& s : segs) {
    const Eigen::Vector2d ab = s.b - s.a;
    const double t = std::clamp((p - s.a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
    best = std::min(best, (s.a + t * ab - p).norm());
  }
  return best;
}

// True painted lane lines (dashed, solid, double solid) within `radius` of p.
std::vector<Segment> lineSegmentsNear(const map::LaneMap& truth, const Eigen::Vector2d& p, double radius) {
  std::vector<Segment> out;
  for (const auto& l : truth.lines) {
    if (l.type != map::LineType::kDashed && l.type != map::LineType::kSolid && l.type != map::LineType::kSolidSolid) continue;
    for (size_t i = 0; i + 1 < l.points.size(); ++i) {
      const Segment s{l.points[i].head<2>(), l.points[i + 1].head<2>()};
      if ((s.a - p).norm() < radius || (s.b - p).norm() < radius) out.push_back(s);
    }
  }
  return out;
}

struct Score {
  double line_dist_sum = 0.0;  // distance of line cells from the true lines, capped at 2 m
  size_t line_cells = 0, line_on_paint = 0;
  size_t crosswalk_cells = 0, crosswalk_on_paint = 0;
  double meanDistance() const { return line_cells ? line_dist_sum / line_cells : 0.0; }
  double linePrecision() const { return line_cells ? double(line_on_paint) / line_cells : 0.0; }
  double crosswalkPrecision() const { return crosswalk_cells ? double(crosswalk_on_paint) / crosswalk_cells : 0.0; }
};

void score(const bev::FrameSplat& s, const sim::World& world, const std::vector<Segment>& lines, Score& out) {
  const uint8_t line_bits = bev::bit(bev::Layer::kDashedLine) | bev::bit(bev::Layer::kSolidLine);
  for (const auto& c : s.cells) {
    const Eigen::Vector2d p((c.x + 0.5) * s.resolution, (c.y + 0.5) * s.resolution);
    if (c.layers & line_bits) {
      ++out.line_cells;
      out.line_dist_sum += std::min(2.0, distanceToSegments(p, lines));
      const auto g = world.sample(p.x(), p.y()).surface;
      out.line_on_paint += g == sim::Surface::kDashedPaint || g == sim::Surface::kSolidPaint;
    }
    if (c.layers & bev::bit(bev::Layer::kCrosswalk)) {
      ++out.crosswalk_cells;
      out.crosswalk_on_paint += world.sample(p.x(), p.y()).surface == sim::Surface::kCrosswalkPaint;
    }
  }
}

TEST(MeshVsFlat, TheLidarMeshPutsLinesAndCrosswalksCloserToTheTruthOnHillyCrownedRoads) {
  const auto osm = osm::readOsm(kSource + "/data/osm/west-oakland.osm");
  const auto sk = skeleton::Skeleton::build(osm);
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(kSource + "/config/sim_world.yaml");
  wo.seed = 4;
  const auto world = sim::buildWorld(sk, wo);
  sim::DriveOptions drive;
  drive.seed = 4;
  drive.duration_s = 90.0;
  const auto plan = sim::planDrive(sk, world->truth(), drive);
  const sim::Trajectory traj(world->truth(), *world, plan, drive);
  ASSERT_GT(traj.duration(), 60.0);

  const YAML::Node vehicle = loadYamlFile(kSource + "/config/vehicle.yaml");
  const auto camera = camera::CameraModel::fromYaml(vehicle["camera"]);
  const auto lidar_options = sim::LidarScannerOptions::fromYaml(vehicle["lidar"]);
  sim::RenderOptions render;
  render.shadows = false;
  const sim::CameraRenderer renderer(camera, render);
  sim::LidarScanner scanner(lidar_options);
  const bev::Projector projector(camera);
  auto poseAt = [&](double t) { return traj.at(t).vehicle_to_enu; };

  Score flat, mesh, crowned;
  bev::CrownOptions crown_options;
  crown_options.slope = 0.02;
  int frames = 0;
  for (double t = 3.0; t < traj.duration() - 1.0; t += 4.0) {
    const sim::VehicleState st = traj.at(t);
    const auto frame = renderer.render(*world, st.vehicle_to_enu, st.lanelet, 7);
    // The sweep that ended at the frame's time, each return placed with the pose of its firing.
    const sim::LidarSweep sweep = scanner.scan(*world, t - scanner.sweepPeriodS(), poseAt, 11);
    ground::SweepPoints pts;
    for (const auto& r : sweep.returns) pts.enu.push_back(poseAt(r.time_s) * lidar_options.mount * r.point_sensor);
    pts.vehicle_to_enu_mid = poseAt(t - 0.5 * scanner.sweepPeriodS());
    const auto ground = ground::buildSweepGround(pts);
    ASSERT_TRUE(ground.mesh);
    const auto lines = lineSegmentsNear(world->truth(), st.vehicle_to_enu.translation().head<2>(), 45.0);
    const auto f = projector.project(frame.labels, st.vehicle_to_enu);
    const auto m = projector.project(frame.labels, st.vehicle_to_enu, ground.mesh.get());
    EXPECT_GT(m.mesh_hits, m.pixels / 2) << "t " << t;
    score(f, *world, lines, flat);
    score(m, *world, lines, mesh);
    // Without the LIDAR: the driven road's crown (core/bev/road_crown.h; 2 %, as the simulator's).
    const auto crown = bev::RoadCrown::around(sk, st.vehicle_to_enu, crown_options);
    score(projector.project(frame.labels, st.vehicle_to_enu, nullptr, crown ? &*crown : nullptr), *world, lines, crowned);
    ++frames;
  }
  std::printf("%d frames; lane-line cells: flat %zu cells, mean distance to the true lines %.3f m, on paint %.1f %%;"
              " mesh %zu cells, %.3f m, %.1f %%\n",
              frames, flat.line_cells, flat.meanDistance(), 100 * flat.linePrecision(), mesh.line_cells,
              mesh.meanDistance(), 100 * mesh.linePrecision());
  std::printf("crosswalk cells: flat %zu, on crosswalk paint %.1f %%; mesh %zu, %.1f %%\n", flat.crosswalk_cells,
              100 * flat.crosswalkPrecision(), mesh.crosswalk_cells, 100 * mesh.crosswalkPrecision());
  std::printf("crowned (no LIDAR): lane-line cells %zu, mean distance %.3f m, on paint %.1f %%\n", crowned.line_cells,
              crowned.meanDistance(), 100 * crowned.linePrecision());
  ASSERT_GT(frames, 10);
  // The crown model is closer than the flat plane, and the measured ground closer still.
  EXPECT_LT(crowned.meanDistance(), 0.95 * flat.meanDistance());
  EXPECT_GT(crowned.linePrecision(), flat.linePrecision());
  EXPECT_LT(mesh.meanDistance(), crowned.meanDistance());
  ASSERT_GT(flat.line_cells, 2000u);
  EXPECT_LT(mesh.meanDistance(), 0.8 * flat.meanDistance()) << "the mesh must be measurably closer";
  EXPECT_GT(mesh.linePrecision(), flat.linePrecision());
  if (flat.crosswalk_cells > 200 && mesh.crosswalk_cells > 200) {
    EXPECT_GT(mesh.crosswalkPrecision(), flat.crosswalkPrecision());
  }
}

}  // namespace
