// The ground mesh of simulated VLP-16 sweeps against the simulator's true terrain (crowned, graded,
// bumpy West Oakland): the decimated mesh (SweepGroundOptions::decimate_m, the default) must be as
// close to the true height as the mesh with every ground point a vertex, with far fewer triangles.
// Also decimateGround itself: one mean per cell.
#include "core/ground/sweep_ground.h"
#include "core/osm/osm_data.h"
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

TEST(DecimateGround, MergesThePointsOfEachCellIntoTheirMean) {
  const std::vector<Eigen::Vector3d> pts{{0.01, 0.02, 1.0}, {0.25, 0.1, 2.0}, {0.35, 0.1, 5.0}, {-0.05, 0.1, 7.0}};
  const auto out = ground::decimateGround(pts, 0.3);
  ASSERT_EQ(out.size(), 3u);  // cells (0, 0): two points; (1, 0); (-1, 0)
  bool merged = false;
  for (const auto& p : out) {
    if (std::abs(p.z() - 1.5) < 1e-12) {
      merged = true;
      EXPECT_NEAR(p.x(), 0.13, 1e-12);
      EXPECT_NEAR(p.y(), 0.06, 1e-12);
    }
  }
  EXPECT_TRUE(merged);
  EXPECT_EQ(ground::decimateGround(pts, 0.0).size(), pts.size());
}

struct HeightError {
  std::vector<double> err;
  double mean() const {
    double s = 0;
    for (double e : err) s += e;
    return err.empty() ? 0.0 : s / err.size();
  }
  double quantile(double q) const {
    std::vector<double> e = err;
    std::sort(e.begin(), e.end());
    return e.empty() ? 0.0 : e[static_cast<size_t>(q * (e.size() - 1))];
  }
};

TEST(SweepMesh, TheDecimatedMeshIsAsCloseToTheTrueTerrainWithAFifthOfTheTriangles) {
  const auto osm = osm::readOsm(kSource + "/data/osm/west-oakland.osm");
  const auto sk = skeleton::Skeleton::build(osm);
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(kSource + "/config/sim_world.yaml");
  wo.seed = 6;
  const auto world = sim::buildWorld(sk, wo);
  sim::DriveOptions drive;
  drive.seed = 6;
  drive.duration_s = 40.0;
  const auto plan = sim::planDrive(sk, world->truth(), drive);
  const sim::Trajectory traj(world->truth(), *world, plan, drive);
  ASSERT_GT(traj.duration(), 30.0);
  const YAML::Node vehicle = loadYamlFile(kSource + "/config/vehicle.yaml");
  const auto lidar_options = sim::LidarScannerOptions::fromYaml(vehicle["lidar"]);
  sim::LidarScanner scanner(lidar_options);
  auto poseAt = [&](double t) { return traj.at(t).vehicle_to_enu; };

  ground::SweepGroundOptions full;
  full.decimate_m = 0.0;
  const ground::SweepGroundOptions decimated;
  ASSERT_GT(decimated.decimate_m, 0.0);
  HeightError e_full, e_dec;
  size_t tris_full = 0, tris_dec = 0, both = 0, only_full = 0;
  for (double t = 3.0; t < traj.duration() - 1.0; t += 5.0) {
    const sim::LidarSweep sweep = scanner.scan(*world, t - scanner.sweepPeriodS(), poseAt, 13);
    ground::SweepPoints pts;
    for (const auto& r : sweep.returns) pts.enu.push_back(poseAt(r.time_s) * lidar_options.mount * r.point_sensor);
    pts.vehicle_to_enu_mid = poseAt(t - 0.5 * scanner.sweepPeriodS());
    const auto gf = ground::buildSweepGround(pts, full);
    const auto gd = ground::buildSweepGround(pts, decimated);
    ASSERT_TRUE(gf.mesh && gd.mesh);
    EXPECT_EQ(gf.mesh_points, gf.ground_points);
    EXPECT_LT(gd.mesh_points, gd.ground_points / 2);
    tris_full += gf.mesh->triangleCount();
    tris_dec += gd.mesh->triangleCount();
    // What the camera sees: 4..30 m ahead, 12 m to either side, every 0.5 m.
    const Eigen::Isometry3d pose = poseAt(t);
    for (double x = 4.0; x <= 30.0; x += 0.5) {
      for (double y = -12.0; y <= 12.0; y += 0.5) {
        const Eigen::Vector3d p = pose * Eigen::Vector3d(x, y, 0.0);
        const auto zf = gf.mesh->heightAt(p.x(), p.y());
        const auto zd = gd.mesh->heightAt(p.x(), p.y());
        if (zf && !zd) ++only_full;
        if (!zf || !zd) continue;
        ++both;
        const double truth = world->height(p.x(), p.y());
        e_full.err.push_back(std::abs(*zf - truth));
        e_dec.err.push_back(std::abs(*zd - truth));
      }
    }
  }
  std::printf("%zu points on both meshes (%zu on the full mesh only); |mesh - truth|: every point mean %.4f m, p95 %.4f m;"
              " decimated %.2f m mean %.4f m, p95 %.4f m; triangles %zu vs %zu\n",
              both, only_full, e_full.mean(), e_full.quantile(0.95), decimated.decimate_m, e_dec.mean(),
              e_dec.quantile(0.95), tris_full, tris_dec);
  ASSERT_GT(both, 10000u);
  EXPECT_LT(only_full, both / 50) << "decimation must not open holes in the mesh";
  EXPECT_LE(e_dec.mean(), e_full.mean() * 1.05 + 0.001);
  EXPECT_LE(e_dec.quantile(0.95), e_full.quantile(0.95) * 1.05 + 0.002);
  EXPECT_LT(tris_dec, tris_full / 4);
}

}  // namespace
