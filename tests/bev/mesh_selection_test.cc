// Which LIDAR mesh a frame is projected on (core/bev/bev_builder.h): the mesh of the sweep whose
// middle is nearest to the frame's time, whatever is finished when the frame comes in. Simulated
// VLP-16 sweeps (10 Hz) and frames (5 Hz, 13 ms after a sweep starts, delivered 80 ms late like the
// segmenter's) are fed in delivery order to a builder that meshes in the caller's thread and, at the
// pace of a live drive, to one that meshes in its worker thread: both must choose, for every frame,
// the sweep nearest in time. (Choosing "the newest finished mesh", the rule before, picks the
// previous sweep for every one of these frames: the sweep covering a frame ends 87 ms after it.)
// Without LIDAR a frame does not wait; a LIDAR that stalls makes frames wait mesh_wait_s at most.
#include "core/bev/bev_builder.h"
#include "core/osm/osm_data.h"
#include "core/sim/drive.h"
#include "core/sim/lidar_scanner.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <thread>
#include <variant>

namespace {

using namespace lanemap;

const std::string kSource = LANEMAP_SOURCE_DIR;

struct Pose {
  bev::TimedPose p;
};
struct Frame {
  int64_t utime;
};
struct Sweep {
  bev::SweepData d;
  int64_t mid;
};
struct Event {
  int64_t deliver;  // when it reaches the builder
  std::variant<Pose, Frame, Sweep> what;
};

struct Scenario {
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<camera::CameraModel> camera;
  Eigen::Isometry3d lidar_to_vehicle;
  std::vector<Event> events;               // sorted by delivery
  std::map<int64_t, int64_t> nearest;       // frame utime -> the nearest sweep's middle
};

int64_t us(double t) { return static_cast<int64_t>(std::llround(t * 1e6)); }

// Poses 0..end_s at 100 Hz, sweeps starting every 0.1 s until sweeps_end_s, frames at
// 0.513, 0.713, ... delivered 80 ms late.
Scenario scenario(double end_s, double sweeps_end_s) {
  Scenario s;
  const auto osm = osm::readOsm(kSource + "/data/osm/west-oakland.osm");
  s.sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(osm));
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(kSource + "/config/sim_world.yaml");
  wo.seed = 9;
  static std::unique_ptr<sim::SimWorld> world;  // kept with the trajectory, which refers to it
  static std::unique_ptr<sim::Trajectory> traj;
  traj.reset();
  world = sim::buildWorld(*s.sk, wo);
  sim::DriveOptions drive;
  drive.seed = 9;
  drive.duration_s = end_s + 2.0;
  const auto plan = sim::planDrive(*s.sk, world->truth(), drive);
  traj = std::make_unique<sim::Trajectory>(world->truth(), *world, plan, drive);
  const YAML::Node vehicle = loadYamlFile(kSource + "/config/vehicle.yaml");
  s.camera = std::make_unique<camera::CameraModel>(camera::CameraModel::fromYaml(vehicle["camera"]));
  const auto lidar_options = sim::LidarScannerOptions::fromYaml(vehicle["lidar"]);
  s.lidar_to_vehicle = lidar_options.mount;
  sim::LidarScanner scanner(lidar_options);
  auto poseAt = [&](double t) { return traj->at(t).vehicle_to_enu; };
  for (int i = 0; i * 0.01 <= end_s + 1e-9; ++i) {
    const auto st = traj->at(i * 0.01);
    s.events.push_back({us(i * 0.01), Pose{bev::TimedPose{us(i * 0.01), st.vehicle_to_enu.translation(),
                                                          Eigen::Quaterniond(st.vehicle_to_enu.linear())}}});
  }
  std::vector<int64_t> mids;
  for (int k = 1; 0.1 * k + 0.1 <= sweeps_end_s + 1e-9; ++k) {
    const sim::LidarSweep sweep = scanner.scan(*world, 0.1 * k, poseAt, static_cast<uint64_t>(k));
    Sweep sw;
    for (const auto& p : sweep.packets) {
      const uint32_t usec = p[1200] | p[1201] << 8 | p[1202] << 16 | static_cast<uint32_t>(p[1203]) << 24;
      sw.d.packet_utime.push_back(usec);
      sw.d.packets.emplace_back(p.begin(), p.end());
    }
    sw.d.utime = sw.d.packet_utime.front();
    sw.mid = sw.d.packet_utime.front() + (sw.d.packet_utime.back() - sw.d.packet_utime.front()) / 2;
    mids.push_back(sw.mid);
    s.events.push_back({sw.d.packet_utime.back() + 2000, std::move(sw)});
  }
  std::vector<double> frames;
  for (double t = 0.513; t < end_s - 0.4; t += 0.2) frames.push_back(t);
  // With sweeps to the end: one more frame at the last pose's time, just past the last sweep's end,
  // delivered after every other message (the end of a drive).
  if (sweeps_end_s >= end_s) frames.push_back(end_s);
  for (const double t : frames) {
    s.events.push_back({t == end_s ? us(t) + 100000 : us(t) + 80000, Frame{us(t)}});
    int64_t best = 0;
    for (int64_t m : mids) {
      if (!best || std::llabs(m - us(t)) < std::llabs(best - us(t))) best = m;
    }
    if (best && std::llabs(best - us(t)) <= 500000) s.nearest[us(t)] = best;
  }
  std::stable_sort(s.events.begin(), s.events.end(), [](const Event& a, const Event& b) { return a.deliver < b.deliver; });
  return s;
}

bev::BevBuilderOptions options(const Scenario& s, bool async) {
  bev::BevBuilderOptions o = bev::BevBuilderOptions::fromYaml(loadYamlFile(kSource + "/config/bev_builder.yaml"));
  o.async_mesh = async;
  o.lidar_to_vehicle = s.lidar_to_vehicle;
  return o;
}

// Feeds the scenario (live: each event at its delivery time on the wall clock); returns frame utime
// -> mesh utime (0: flat); *before_finish: the frames projected before finish().
std::map<int64_t, int64_t> run(const Scenario& s, bev::BevBuilder& b, bool live, size_t* before_finish = nullptr) {
  std::map<int64_t, int64_t> chosen;
  b.setMeshChoiceCallback([&](int64_t f, int64_t m) { chosen[f] = m; });
  const cv::Mat blank(s.camera->height(), s.camera->width(), CV_8UC1, cv::Scalar(0));
  const auto start = std::chrono::steady_clock::now();
  for (const Event& e : s.events) {
    if (live) std::this_thread::sleep_until(start + std::chrono::microseconds(e.deliver));
    if (const auto* p = std::get_if<Pose>(&e.what)) b.addPose(p->p);
    if (const auto* f = std::get_if<Frame>(&e.what)) b.addFrame(f->utime, blank);
    if (const auto* w = std::get_if<Sweep>(&e.what)) b.addSweep(w->d);
  }
  if (before_finish) *before_finish = chosen.size();
  b.finish();
  return chosen;
}

TEST(MeshSelection, EachFrameUsesTheSweepNearestInTimeWhetherMeshedInlineOrInTheWorker) {
  const Scenario s = scenario(3.0, 3.0);
  ASSERT_GE(s.nearest.size(), 10u);
  for (const bool async : {false, true}) {
    bev::BevBuilder b(*s.sk, *s.camera, options(s, async));
    size_t before_finish = 0;
    const auto chosen = run(s, b, async, &before_finish);
    // The last frame, after the last message: a live process publishes its counters before
    // finish(), so no frame may be left waiting for a sweep that will not come.
    EXPECT_EQ(before_finish, s.nearest.size()) << "async " << async;
    const auto st = b.stats();
    EXPECT_EQ(st.frames_mesh_wait_expired, 0) << "async " << async;
    EXPECT_EQ(st.sweeps_replaced, 0) << "async " << async;
    size_t checked = 0;
    for (const auto& [frame, mid] : s.nearest) {
      ASSERT_TRUE(chosen.count(frame)) << "frame " << frame << " not projected, async " << async;
      EXPECT_EQ(chosen.at(frame), mid) << "frame " << frame << ", async " << async;
      // These frames lie 13 ms into a sweep: the nearest is the sweep covering them (the last frame,
      // just past the last sweep: that sweep).
      if (frame != s.nearest.rbegin()->first) {
        EXPECT_GT(mid, frame);
      }
      ++checked;
    }
    EXPECT_EQ(checked, s.nearest.size());
  }
}

TEST(MeshSelection, WithoutSweepsFramesDoNotWaitAndAStalledLidarHoldsThemAtMostMeshWait) {
  Scenario s = scenario(3.0, 1.2);  // sweeps stop at 1.2 s
  bev::BevBuilder b(*s.sk, *s.camera, options(s, false));
  std::map<int64_t, int64_t> chosen;
  std::map<int64_t, int64_t> projected_at;  // frame -> newest pose fed when it was projected
  int64_t newest_pose = 0;
  b.setMeshChoiceCallback([&](int64_t f, int64_t m) {
    chosen[f] = m;
    projected_at[f] = newest_pose;
  });
  const cv::Mat blank(s.camera->height(), s.camera->width(), CV_8UC1, cv::Scalar(0));
  for (const Event& e : s.events) {
    if (const auto* p = std::get_if<Pose>(&e.what)) {
      newest_pose = p->p.utime;
      b.addPose(p->p);
    }
    if (const auto* f = std::get_if<Frame>(&e.what)) b.addFrame(f->utime, blank);
    if (const auto* w = std::get_if<Sweep>(&e.what)) b.addSweep(w->d);
  }
  b.finish();
  const double wait = options(s, false).mesh_wait_s;
  int stalled = 0, absent = 0;
  for (const auto& [frame, at] : projected_at) {
    const int64_t delay = at - frame;
    if (frame < us(1.15)) continue;  // sweeps still coming
    if (frame < us(1.15) + 1000000) {
      // The LIDAR stalled: the frame waits for a sweep covering it until mesh_wait_s, then takes the
      // nearest mesh there is (within max_mesh_age_s) or the flat plane.
      EXPECT_GE(delay, us(wait) - 10000) << "frame " << frame;
      EXPECT_LE(delay, us(wait) + 10000) << "frame " << frame;
      ++stalled;
    } else {
      // A second without sweeps: no LIDAR, no waiting beyond the pose that covers the frame.
      EXPECT_LT(delay, us(wait) / 2) << "frame " << frame;
      EXPECT_EQ(chosen.at(frame), 0) << "flat";
      ++absent;
    }
  }
  EXPECT_GE(stalled, 3);
  EXPECT_GE(absent, 2);
  EXPECT_EQ(b.stats().frames_mesh_wait_expired, stalled);
}

}  // namespace
