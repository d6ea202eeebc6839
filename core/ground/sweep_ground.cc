#include "core/ground/sweep_ground.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

namespace lanemap::ground {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::vector<Eigen::Vector3d> decimateGround(const std::vector<Eigen::Vector3d>& points, double cell_m) {
  if (!(cell_m > 0.0)) return points;
  // Cell (kx, ky) of each point; the cells in (kx, ky) order, each's points in index order.
  const double inv = 1.0 / cell_m;
  std::vector<int64_t> kx(points.size()), ky(points.size());
  int64_t x_lo = std::numeric_limits<int64_t>::max(), x_hi = std::numeric_limits<int64_t>::min();
  int64_t y_lo = x_lo, y_hi = x_hi;
  for (size_t i = 0; i < points.size(); ++i) {
    kx[i] = static_cast<int64_t>(std::floor(points[i].x() * inv));
    ky[i] = static_cast<int64_t>(std::floor(points[i].y() * inv));
    x_lo = std::min(x_lo, kx[i]), x_hi = std::max(x_hi, kx[i]), y_lo = std::min(y_lo, ky[i]), y_hi = std::max(y_hi, ky[i]);
  }
  std::vector<std::pair<uint64_t, int>> keyed(points.size());
  const bool small = !points.empty() && x_hi - x_lo < (int64_t{1} << 16) && y_hi - y_lo < (int64_t{1} << 16);
  if (small) {
    // A 32-bit key (kx - x_lo) << 16 | (ky - y_lo): the same order as (kx, ky). Two stable
    // counting passes of 16 bits (LSD radix) on the points in index order sort by (key, index),
    // as std::sort of (key, index) pairs does, in linear time (a sweep: ~8k ground points).
    std::vector<std::pair<uint64_t, int>> tmp(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      tmp[i] = {static_cast<uint64_t>(kx[i] - x_lo) << 16 | static_cast<uint64_t>(ky[i] - y_lo), static_cast<int>(i)};
    }
    std::vector<uint32_t> count(65537);
    for (int shift : {0, 16}) {
      std::fill(count.begin(), count.end(), 0u);
      for (const auto& e : tmp) ++count[((e.first >> shift) & 0xFFFF) + 1];
      for (size_t b = 1; b < count.size(); ++b) count[b] += count[b - 1];
      for (const auto& e : tmp) keyed[count[(e.first >> shift) & 0xFFFF]++] = e;
      if (shift == 0) tmp.swap(keyed);
    }
  } else {
    for (size_t i = 0; i < points.size(); ++i) {
      const uint64_t key = (static_cast<uint64_t>(kx[i] + (int64_t{1} << 31)) << 32) | static_cast<uint32_t>(ky[i] + (int64_t{1} << 31));
      keyed[i] = {key, static_cast<int>(i)};
    }
    std::sort(keyed.begin(), keyed.end());  // by cell, then by index: deterministic
  }
  std::vector<Eigen::Vector3d> out;
  for (size_t a = 0; a < keyed.size();) {
    size_t b = a;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (; b < keyed.size() && keyed[b].first == keyed[a].first; ++b) sum += points[keyed[b].second];
    out.push_back(sum / static_cast<double>(b - a));
    a = b;
  }
  return out;
}

std::optional<SweepPoints> sweepToEnu(const std::vector<SweepPacket>& packets, const Eigen::Isometry3d& lidar_to_vehicle,
                                      const PoseLookup& pose, std::optional<lidar::Model> model) {
  SweepPoints out;
  lidar::PacketDecoder decoder(model);
  std::vector<lidar::LidarPoint> pts;
  out.enu.reserve(packets.size() * 384);  // a VLP-16 packet: 12 blocks x 32 firings
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
  ground.reserve(vehicle.size() / 2);
  const double max_r2 = options.max_range_m * options.max_range_m;
  for (int i : extractGround(vehicle, options.extraction)) {
    if (vehicle[i].head<2>().squaredNorm() <= max_r2) ground.push_back(sweep.enu[i]);
  }
  g.ground_points = ground.size();
  ground = decimateGround(ground, options.decimate_m);
  g.mesh_points = ground.size();
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
