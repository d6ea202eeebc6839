// BEV projection (METHOD.md section 3) figures, on the simulator's West Oakland (in-process: truth
// labels of the shipped 640x360 camera, VLP-16 sweeps ray-cast at 10 Hz, true poses). Prints, asserts
// nothing. Per-frame and per-sweep figures are CPU time of the measuring thread (one thread), so a
// loaded machine inflates them less than wall time; each row is printed beside its baseline from
// the same run.
//   lanemap-bench-bev                  per-frame projection: flat vs mesh (raster, and the ray cast it
//                                      replaced) vs cv::warpPerspective (flat IPM of the same label
//                                      image), mesh build per sweep
//   lanemap-bench-bev --memory S       accumulate an S-second drive through BevBuilder + road tracker
//                                      (camera 5 Hz, LIDAR 10 Hz); peak RSS and peak grid memory
#include "core/bev/bev_builder.h"
#include "core/camera/camera_model.h"
#include "core/ground/sweep_ground.h"
#include "core/osm/osm_data.h"
#include "core/sim/camera_renderer.h"
#include "core/sim/drive.h"
#include "core/sim/lidar_scanner.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <sys/resource.h>
#include <time.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

using namespace lanemap;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kSource = std::string(LANEMAP_DATA_DIR) + "/..";

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// CPU time of the calling thread, ms.
double cpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

struct Setup {
  osm::OsmData osm;
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<sim::SimWorld> world;
  std::unique_ptr<sim::Trajectory> traj;
  YAML::Node vehicle;
};

Setup setup(double duration_s) {
  Setup s;
  s.osm = osm::readOsm(kSource + "/data/osm/west-oakland.osm");
  s.sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(s.osm));
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(kSource + "/config/sim_world.yaml");
  wo.seed = 1;
  s.world = sim::buildWorld(*s.sk, wo);
  sim::DriveOptions d;
  d.seed = 1;
  d.duration_s = duration_s;
  const auto plan = sim::planDrive(*s.sk, s.world->truth(), d);
  s.traj = std::make_unique<sim::Trajectory>(s.world->truth(), *s.world, plan, d);
  s.vehicle = YAML::LoadFile(kSource + "/config/vehicle.yaml");
  return s;
}

// Homography from a BEV image (forward 0..30 m up the image, +-15 m across, 0.1 m pixels) to the
// camera image on the vehicle's ground plane, pinhole (warpPerspective cannot undistort).
cv::Mat ipmHomography(const camera::CameraModel& cam) {
  std::vector<cv::Point2f> bev, img;
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{{6, -4}, {6, 4}, {30, -15}, {30, 15}}) {
    bev.emplace_back(static_cast<float>((15.0 - y) / 0.1), static_cast<float>((30.0 - x) / 0.1));
    const auto p = cam.projectCameraPinhole(cam.vehicleToCamera() * Eigen::Vector3d(x, y, 0.0));
    img.emplace_back(static_cast<float>(p->x()), static_cast<float>(p->y()));
  }
  return cv::getPerspectiveTransform(bev, img);
}

std::vector<ground::SweepPacket> packetsOf(const sim::LidarSweep& sweep) {
  std::vector<ground::SweepPacket> out;
  for (const auto& p : sweep.packets) {
    const uint32_t usec = p[1200] | p[1201] << 8 | p[1202] << 16 | static_cast<uint32_t>(p[1203]) << 24;
    out.push_back(ground::SweepPacket{static_cast<int64_t>(usec), p.data(), p.size()});
  }
  return out;
}

void benchFrames(int frames) {
  Setup s = setup(90.0);
  const auto cam = camera::CameraModel::fromYaml(s.vehicle["camera"]);
  const auto lidar_opt = sim::LidarScannerOptions::fromYaml(s.vehicle["lidar"]);
  sim::RenderOptions ro;
  ro.shadows = false;
  const sim::CameraRenderer renderer(cam, ro);
  sim::LidarScanner scanner(lidar_opt);
  const bev::Projector projector(cam);
  bev::ProjectorOptions cast_options;
  cast_options.mesh_raster = false;
  const bev::Projector caster(cam, cast_options);
  const cv::Mat H = ipmHomography(cam);
  const auto& traj = *s.traj;
  auto poseAt = [&](double t) { return traj.at(t).vehicle_to_enu; };
  std::printf("camera %dx%d: %zu candidate pixels within 30 m, %zu on the projection lattice\n", cam.width(),
              cam.height(), projector.candidatePixels(), projector.latticePixels());
  double t_flat = 0, t_crown = 0, t_mesh = 0, t_mesh_full = 0, t_cast = 0, t_warp = 0, t_dec = 0, t_ext = 0, t_tri = 0, t_idx = 0,
         t_ground = 0, t_ground_full = 0;
  size_t points = 0, ground = 0, mesh_points = 0, tris = 0, tris_full = 0, cells_flat = 0, cells_crown = 0, cells_mesh = 0,
         cells_mesh_full = 0, cells_cast = 0, cells_differ = 0;
  ground::SweepGroundOptions full_options;  // every ground point a vertex (before decimation)
  full_options.decimate_m = 0.0;
  int n = 0;
  for (double t = 2.0; n < frames && t < traj.duration() - 1.0; t += (traj.duration() - 3.0) / frames, ++n) {
    const auto st = traj.at(t);
    const cv::Mat labels = renderer.render(*s.world, st.vehicle_to_enu, st.lanelet, 1).labels;
    // Trajectory time t seconds = t * 1e6 microseconds past the hour (t < 3600).
    const auto sweep = scanner.scan(*s.world, t - scanner.sweepPeriodS(), poseAt, 3);
    double c0 = cpuMs();
    const auto pts = ground::sweepToEnu(packetsOf(sweep), lidar_opt.mount,
                                        [&](int64_t u) { return std::optional<Eigen::Isometry3d>(poseAt(u * 1e-6)); });
    t_dec += cpuMs() - c0;
    c0 = cpuMs();
    const auto g = ground::buildSweepGround(*pts);
    t_ground += cpuMs() - c0;
    c0 = cpuMs();
    const auto g_full = ground::buildSweepGround(*pts, full_options);
    t_ground_full += cpuMs() - c0;
    t_ext += g.ms_extract;
    t_tri += g.ms_triangulate;
    t_idx += g.ms_index;
    points += g.points;
    ground += g.ground_points;
    mesh_points += g.mesh_points;
    tris += g.mesh->triangleCount();
    tris_full += g_full.mesh->triangleCount();
    c0 = cpuMs();
    cells_flat += projector.project(labels, st.vehicle_to_enu).cells.size();
    t_flat += cpuMs() - c0;
    c0 = cpuMs();
    {
      // No LIDAR, crown_slope 0.02: the driven road's crown (lanemap-bev-builder then), its set-up included.
      bev::CrownOptions crown_options;
      crown_options.slope = 0.02;
      const auto crown = bev::RoadCrown::around(*s.sk, st.vehicle_to_enu, crown_options);
      cells_crown += projector.project(labels, st.vehicle_to_enu, nullptr, crown ? &*crown : nullptr).cells.size();
    }
    t_crown += cpuMs() - c0;
    c0 = cpuMs();
    const auto m = projector.project(labels, st.vehicle_to_enu, g.mesh.get());
    t_mesh += cpuMs() - c0;
    c0 = cpuMs();
    const auto mf = projector.project(labels, st.vehicle_to_enu, g_full.mesh.get());
    t_mesh_full += cpuMs() - c0;
    c0 = cpuMs();
    const auto r = caster.project(labels, st.vehicle_to_enu, g_full.mesh.get());
    t_cast += cpuMs() - c0;
    cells_mesh += m.cells.size();
    cells_mesh_full += mf.cells.size();
    cells_cast += r.cells.size();
    {
      size_t i = 0, j = 0, same = 0;  // both sorted by (y, x)
      while (i < mf.cells.size() && j < r.cells.size()) {
        const auto& a = mf.cells[i];
        const auto& b = r.cells[j];
        if (a.y == b.y && a.x == b.x) {
          same += a.layers == b.layers;
          ++i, ++j;
        } else if (a.y < b.y || (a.y == b.y && a.x < b.x)) {
          ++i;
        } else {
          ++j;
        }
      }
      cells_differ += mf.cells.size() + r.cells.size() - 2 * same;
    }
    cv::Mat ipm;
    const int threads = cv::getNumThreads();
    cv::setNumThreads(1);  // one thread, like the projections
    c0 = cpuMs();
    cv::warpPerspective(labels, ipm, H, cv::Size(300, 300), cv::INTER_NEAREST | cv::WARP_INVERSE_MAP);
    t_warp += cpuMs() - c0;
    cv::setNumThreads(threads);
  }
  std::printf("per frame (%d frames, %dx%d labels, CPU ms of 1 thread):\n", n, cam.width(), cam.height());
  std::printf("  flat projection   %7.2f ms  (%zu cells)   %5.1fx warpPerspective   [baseline of the mesh rows]\n",
              t_flat / n, cells_flat / n, t_flat / t_warp);
  std::printf("  crowned road      %7.2f ms  (%zu cells)   %5.1fx warpPerspective, %.2fx flat  [no LIDAR: the road's"
              " 2 %% crown, core/bev/road_crown.h; off by default]\n", t_crown / n, cells_crown / n, t_crown / t_warp, t_crown / t_flat);
  std::printf("  mesh projection   %7.2f ms  (%zu cells)   %5.1fx warpPerspective, %.2fx flat (target <= 2x)"
              "  [raster, decimated mesh: the default]\n",
              t_mesh / n, cells_mesh / n, t_mesh / t_warp, t_mesh / t_flat);
  std::printf("  mesh, full mesh   %7.2f ms  (%zu cells)   %5.1fx warpPerspective, %.2fx flat  [raster, every ground point]\n",
              t_mesh_full / n, cells_mesh_full / n, t_mesh_full / t_warp, t_mesh_full / t_flat);
  std::printf("  mesh, ray cast    %7.2f ms  (%zu cells)   %5.1fx warpPerspective, %.2fx flat  [per-pixel ray cast, full"
              " mesh: before]\n", t_cast / n, cells_cast / n, t_cast / t_warp, t_cast / t_flat);
  std::printf("  raster vs ray cast on the full mesh: %.3f %% of the cells differ (cell or layers)\n",
              100.0 * cells_differ / std::max<size_t>(1, cells_cast));
  std::printf("  warpPerspective   %7.2f ms  (flat IPM, 300x300 BEV of 30 x 30 m, nearest, pinhole only)\n", t_warp / n);
  std::printf("per sweep: %zu points, %zu ground, %zu mesh vertices (decimate_m %.2f), %zu triangles (%zu without"
              " decimation)\n", points / n, ground / n, mesh_points / n, ground::SweepGroundOptions{}.decimate_m, tris / n,
              tris_full / n);
  std::printf("  decode + ENU      %7.2f ms\n  ground extraction %7.2f ms (wall)\n  Delaunay (CGAL)   %7.2f ms (wall)\n"
              "  triangle index    %7.2f ms (wall)\n  mesh total        %7.2f ms CPU (%.2f ms wall; target <= 5 ms;"
              " worker thread in lanemap-bev-builder)\n  mesh, no decimation %5.2f ms CPU  [before]\n",
              t_dec / n, t_ext / n, t_tri / n, t_idx / n, t_ground / n, (t_ext + t_tri + t_idx) / n, t_ground_full / n);
}

void benchMemory(double duration_s) {
  Setup s = setup(duration_s);
  const auto cam = camera::CameraModel::fromYaml(s.vehicle["camera"]);
  const auto lidar_opt = sim::LidarScannerOptions::fromYaml(s.vehicle["lidar"]);
  const sim::CameraRenderer renderer(cam, sim::RenderOptions{});
  sim::LidarScanner scanner(lidar_opt);
  bev::BevBuilderOptions o = bev::BevBuilderOptions::fromYaml(YAML::LoadFile(kSource + "/config/bev_builder.yaml"));
  o.lidar_to_vehicle = lidar_opt.mount;
  bev::BevBuilder builder(*s.sk, cam, o);
  tracking::RoadTracker tracker(*s.sk);
  const auto& traj = *s.traj;
  auto poseAt = [&](double t) { return traj.at(t).vehicle_to_enu; };
  size_t peak_grid = 0, roads = 0, bytes_out = 0;
  const auto t_start = Clock::now();
  for (int i = 0; i * 0.01 <= traj.duration(); ++i) {
    const double t = i * 0.01;
    const auto st = traj.at(t);
    const auto u = static_cast<int64_t>(std::llround(t * 1e6));
    bev::TimedPose p{u, st.vehicle_to_enu.translation(), Eigen::Quaterniond(st.vehicle_to_enu.linear())};
    builder.addPose(p);
    tracking::PoseInput in{u, p.position.head<2>(), std::atan2(st.vehicle_to_enu(1, 0), st.vehicle_to_enu(0, 0)), true, std::nullopt};
    for (const auto& e : tracker.update(in)) {
      if (e.type == tracking::RoadEventType::kEnteredRoad) builder.roadEntered(e.road_id, e.utime);
      if (e.type == tracking::RoadEventType::kReachedIntersection) builder.roadClosed(e.road_id, e.utime);
    }
    if (i % 10 == 0 && i > 0) {
      const auto sweep = scanner.scan(*s.world, t - scanner.sweepPeriodS(), poseAt, i);
      bev::SweepData d;
      for (const auto& pk : packetsOf(sweep)) {
        d.packet_utime.push_back(pk.utime);
        d.packets.emplace_back(pk.data, pk.data + pk.size);
      }
      builder.addSweep(std::move(d));
    }
    if (i % 20 == 5) builder.addFrame(u, renderer.render(*s.world, st.vehicle_to_enu, st.lanelet, i).labels);
    for (const auto& r : builder.takeClosed()) {
      ++roads;
      bytes_out += r.grid.memoryBytes();
    }
    peak_grid = std::max(peak_grid, builder.accumulator().memoryBytes());
  }
  builder.finish();
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  const auto st = builder.stats();
  std::printf("drive %.0f s (%.0f m): %lld frames projected (%lld on the mesh), %zu roads handed over (%.1f MiB of grids),"
              " %.0f s wall\n", traj.duration(), traj.length(), static_cast<long long>(st.frames_projected),
              static_cast<long long>(st.frames_mesh), roads, bytes_out / 1048576.0, msSince(t_start) / 1000.0);
  std::printf("  peak memory of the open grids + history: %.1f MiB; peak RSS of the process: %.1f MiB\n",
              peak_grid / 1048576.0, ru.ru_maxrss / 1024.0);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc == 3 && std::strcmp(argv[1], "--memory") == 0) {
      benchMemory(std::stod(argv[2]));
    } else {
      benchFrames(argc == 3 && std::strcmp(argv[1], "--frames") == 0 ? std::stoi(argv[2]) : 20);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-bench-bev: %s\n", e.what());
    return 2;
  }
  return 0;
}
