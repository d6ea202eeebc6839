#include "core/ground/sweep_ground.h"

#include <chrono>

namespace lanemap::ground {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::optional<SweepPoints> sweepToEnu(const std::vector<SweepPacket>& packets, const Eigen::Isometry3d& lidar_to_vehicle,
                                      const PoseLookup& pose, std::optional<lidar::Model> model) {
  SweepPoints out;
  lidar::PacketDecoder decoder(model);
  std::vector<lidar::LidarPoint> pts;
  int64_t first = 0, last = 0;
  for (const auto& pk : packets) {
    ++out.packets;
    pts.clear();
    if (decoder.decode(pk.data, pk.size, pts) != lidar::DecodeStatus::kOk) {
      ++out.packets_bad;
      continue;
    }
    const auto vehicle_to_enu = pose(pk.utime);
    if (!vehicle_to_enu) {
      ++out.packets_without_pose;
      continue;
    }
    if (first == 0) first = pk.utime;
    last = pk.utime;
    const Eigen::Isometry3d lidar_to_enu = *vehicle_to_enu * lidar_to_vehicle;
    for (const auto& p : pts) out.enu.push_back(lidar_to_enu * Eigen::Vector3d(p.x, p.y, p.z));
  }
  if (first == 0) return std::nullopt;
  out.utime_mid = first + (last - first) / 2;
  const auto mid = pose(out.utime_mid);
  if (!mid) return std::nullopt;
  out.vehicle_to_enu_mid = *mid;
  return out;
}

SweepGround buildSweepGround(const SweepPoints& sweep, const SweepGroundOptions& options) {
  SweepGround g;
  g.utime = sweep.utime_mid;
  g.points = sweep.enu.size();
  auto t0 = std::chrono::steady_clock::now();
  const Eigen::Isometry3d enu_to_vehicle = sweep.vehicle_to_enu_mid.inverse();
  std::vector<Eigen::Vector3d> vehicle;
  vehicle.reserve(sweep.enu.size());
  for (const auto& p : sweep.enu) vehicle.push_back(enu_to_vehicle * p);
  std::vector<Eigen::Vector3d> ground;
  const double max_r2 = options.max_range_m * options.max_range_m;
  for (int i : extractGround(vehicle, options.extraction)) {
    if (vehicle[i].head<2>().squaredNorm() <= max_r2) ground.push_back(sweep.enu[i]);
  }
  g.ground_points = ground.size();
  g.ms_extract = msSince(t0);
  t0 = std::chrono::steady_clock::now();
  TriangleMesh mesh = triangulateGround(ground, options.max_edge_m);
  g.ms_triangulate = msSince(t0);
  t0 = std::chrono::steady_clock::now();
  g.mesh = std::make_shared<const MeshGround>(std::move(mesh), options.index);
  g.ms_index = msSince(t0);
  return g;
}

}  // namespace lanemap::ground
