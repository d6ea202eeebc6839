// The BEV builder (core/bev/bev_builder.h) on a simulated drive's log, replayed in-process with the
// road tracker (tests/bev/bev_replay.h): the road the car drove to its end is handed over, stored
// and reloaded exactly, its drivable cells lie on the simulator's true lanes and its marking cells
// on true paint; bad input (wrong size, unknown classes, undecodable, out of order, late, no pose,
// NaN poses) is counted and skipped.
#include "core/bev/bev_store.h"
#include "core/sim/world_builder.h"
#include "tests/bev/bev_replay.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <limits>
#include <set>

namespace {

using namespace lanemap;
namespace lt = lanemap::testing;
using bev::BevGrid;
using bev::Layer;

std::string drive() {
  return lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed,
                                 lt::kBevDriveArgs);
}

// Roads the simulated car drove to their end (scenario.json route entries with a left_utime).
std::set<int64_t> completedRoads(const std::string& dir) {
  std::ifstream f(dir + "/scenario.json");
  const auto j = nlohmann::json::parse(f);
  std::set<int64_t> ids;
  for (const auto& r : j["route"]) {
    if (!r["left_utime"].is_null()) ids.insert(r["road_id"].get<int64_t>());
  }
  return ids;
}

struct Agreement {
  size_t drivable = 0, drivable_on_lane = 0;     // cells the grid calls drivable
  size_t lane = 0, lane_found = 0;               // true lane cells the grid observed
  size_t paint = 0, paint_on_paint = 0;          // cells the grid calls dashed/solid, near true paint
};

Agreement compare(const BevGrid& g, const sim::World& world) {
  Agreement a;
  const int t = g.options().tile_cells;
  g.forEachTile([&](const BevGrid::Cell& o, const uint16_t*) {
    for (int r = 0; r < t; ++r) {
      for (int c = 0; c < t; ++c) {
        const BevGrid::Cell cell(o.x() + c, o.y() + r);
        if (g.count(cell, Layer::kObserved) < 2) continue;
        const Eigen::Vector2d p = g.cellCentre(cell);
        const auto s = world.sample(p.x(), p.y());
        const bool on_lane = s.lanelet >= 0 && (s.surface == sim::Surface::kAsphalt || s.surface == sim::Surface::kDashedPaint ||
                                                s.surface == sim::Surface::kSolidPaint);
        const bool drivable = g.fraction(cell, Layer::kDrivable) >= 0.5f;
        a.drivable += drivable;
        a.drivable_on_lane += drivable && on_lane;
        const bool lane = s.surface == sim::Surface::kAsphalt && s.lanelet >= 0;
        a.lane += lane;
        a.lane_found += lane && drivable;
        const bool paint = g.fraction(cell, Layer::kDashedLine) + g.fraction(cell, Layer::kSolidLine) >= 0.5f;
        a.paint += paint;
        if (!paint) continue;
        // On true paint, or within one cell of it (lines are 0.15 m wide; poses are off by ~0.1 m).
        for (const Eigen::Vector2d& d : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.1, 0), Eigen::Vector2d(-0.1, 0),
                                        Eigen::Vector2d(0, 0.1), Eigen::Vector2d(0, -0.1)}) {
          const auto q = world.sample(p.x() + d.x(), p.y() + d.y()).surface;
          if (q == sim::Surface::kDashedPaint || q == sim::Surface::kSolidPaint) {
            ++a.paint_on_paint;
            break;
          }
        }
      }
    }
  });
  return a;
}

TEST(BevBuilder, AReplayedDriveHandsOverTheDrivenRoadWithCellsOnTheTrueLanes) {
  const std::string dir = drive();
  ASSERT_FALSE(dir.empty());
  const auto expected_roads = completedRoads(dir);
  ASSERT_FALSE(expected_roads.empty()) << "the drive must finish a road";
  const auto r = lt::replayLog(dir + "/drive.lcmlog", lt::replayOptions(true));
  const auto s = r->builder->stats();
  std::printf("frames %lld projected (%lld mesh, %lld flat), sweeps %lld meshed; project %.1f ms mean, mesh %.1f ms mean\n",
              static_cast<long long>(s.frames_projected), static_cast<long long>(s.frames_mesh),
              static_cast<long long>(s.frames_flat), static_cast<long long>(s.sweeps_meshed),
              s.project_ms_sum / std::max<int64_t>(1, s.frames_projected), s.mesh_ms_sum / std::max<int64_t>(1, s.sweeps_meshed));
  EXPECT_EQ(s.frames_projected, s.frames_received) << "every frame of the log has a pose";
  EXPECT_GE(s.frames_received, 85);
  EXPECT_GE(s.frames_mesh, s.frames_projected * 9 / 10) << "LIDAR sweeps come at 10 Hz";
  EXPECT_EQ(s.sweeps_meshed, s.sweeps_received);
  EXPECT_EQ(s.frames_wrong_size + s.frames_unknown_class + s.frames_decode_error + s.frames_no_pose, 0);

  std::set<int64_t> closed;
  for (const auto& road : r->closed) closed.insert(road.road_id);
  EXPECT_EQ(closed, expected_roads);

  const std::string src = LANEMAP_SOURCE_DIR;
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(src + "/config/sim_world.yaml");
  wo.seed = lt::kBevDriveSeed;
  const auto world = sim::buildWorld(*r->sk, wo);
  lt::TempDir store("bev-store");
  for (const auto& road : r->closed) {
    EXPECT_GT(road.grid.frames(), 40) << road.road_id;
    const auto stored = bev::storeRoad(store.str(), road);
    EXPECT_EQ(stored.path, store.str("bev/road_" + std::to_string(road.road_id) + ".bev"));
    const BevGrid loaded = BevGrid::load(stored.path);
    EXPECT_EQ(loaded.frames(), road.grid.frames());
    EXPECT_EQ(loaded.tileCount(), road.grid.tileCount());
    EXPECT_EQ(stored.width, road.grid.cellBounds().sizes().x());
    EXPECT_NEAR(stored.origin.x(), road.grid.cellBounds().min().x() * 0.1, 1e-9);

    const Agreement a = compare(loaded, *world);
    const double precision = double(a.drivable_on_lane) / std::max<size_t>(1, a.drivable);
    const double recall = double(a.lane_found) / std::max<size_t>(1, a.lane);
    const double paint = double(a.paint_on_paint) / std::max<size_t>(1, a.paint);
    std::printf("road %lld: %d frames, %zu tiles; drivable cells %zu, on a true lane %.1f %%; true lane cells seen %zu,"
                " drivable %.1f %%; line cells %zu, within 0.1 m of true paint %.1f %%\n",
                static_cast<long long>(road.road_id), road.grid.frames(), road.grid.tileCount(), a.drivable,
                100 * precision, a.lane, 100 * recall, a.paint, 100 * paint);
    EXPECT_GT(a.drivable, 20000u);
    EXPECT_GT(precision, 0.95);
    EXPECT_GT(recall, 0.8);
    EXPECT_GT(paint, 0.85);
  }
}

TEST(BevBuilder, BadFramesAndPosesAreCountedAndSkipped) {
  const std::string src = LANEMAP_SOURCE_DIR;
  const auto sk = skeleton::Skeleton::build(osm::readOsm(src + "/data/osm/west-oakland.osm"));
  const auto camera = camera::CameraModel::fromYaml(loadYamlFile(src + "/config/vehicle.yaml")["camera"]);
  bev::BevBuilder b(sk, camera, lt::replayOptions(false));
  const int64_t t0 = 1'700'000'000'000'000;
  auto pose = [&](int64_t utime) {
    bev::TimedPose p;
    p.utime = utime;
    p.position = Eigen::Vector3d(1e-6 * (utime - t0) * 10.0, 0.0, 0.0);
    return p;
  };
  const cv::Mat good(camera.height(), camera.width(), CV_8UC1, cv::Scalar(1));
  b.addFrame(t0 - 1'000'000, good);  // before any pose: waits ...
  for (int64_t u = t0; u <= t0 + 1'000'000; u += 10'000) b.addPose(pose(u));  // ... and is late
  b.addFrame(t0 + 100'000, good);                      // projected
  b.addFrame(t0 + 50'000, good);                       // out of order
  b.addFrame(t0 + 200'000, cv::Mat(360, 639, CV_8UC1, cv::Scalar(0)));   // wrong size
  b.addFrame(t0 + 210'000, cv::Mat(360, 640, CV_16UC1, cv::Scalar(0)));  // wrong type
  cv::Mat unknown = good.clone();
  unknown.at<uint8_t>(200, 300) = 11;
  b.addFrame(t0 + 220'000, unknown);                   // unknown class
  b.addEncodedFrame(t0 + 230'000, bev::LabelEncoding::kPng, {1, 2, 3, 4}, 640, 360);       // not a PNG
  b.addEncodedFrame(t0 + 240'000, bev::LabelEncoding::kRaw, std::vector<uint8_t>(100), 640, 360);  // short
  std::vector<uint8_t> png;
  cv::imencode(".png", good, png);
  b.addEncodedFrame(t0 + 250'000, bev::LabelEncoding::kPng, png, 640, 360);  // projected
  bev::TimedPose nan = pose(t0 + 1'010'000);
  nan.position.x() = std::numeric_limits<double>::quiet_NaN();
  b.addPose(nan);                                      // invalid
  b.addPose(pose(t0 + 500'000));                       // out of order
  b.addPose(pose(t0 + 2'000'000));                     // after a 1 s gap
  b.addFrame(t0 + 1'500'000, good);                    // inside the gap: no pose
  b.addFrame(t0 + 2'100'000, good);                    // waits for a later pose ...
  EXPECT_EQ(b.stats().frames_projected, 2);
  b.addPose(pose(t0 + 2'110'000));                     // ... and is projected
  const auto s = b.stats();
  EXPECT_EQ(s.frames_received, 11);
  EXPECT_EQ(s.frames_projected, 3);
  EXPECT_EQ(s.frames_flat, 3);
  EXPECT_EQ(s.frames_late, 1);
  EXPECT_EQ(s.frames_out_of_order, 1);
  EXPECT_EQ(s.frames_wrong_size, 2);
  EXPECT_EQ(s.frames_unknown_class, 1);
  EXPECT_EQ(s.frames_decode_error, 2);
  EXPECT_EQ(s.frames_no_pose, 1);
  EXPECT_EQ(s.poses_invalid, 1);
  EXPECT_EQ(s.poses_out_of_order, 1);
  EXPECT_EQ(s.poses_received, 101 + 4);
}

TEST(BevBuilder, RoadsOpenAndCloseOnEventsAndMemoryStaysWithTheActiveRoad) {
  const std::string src = LANEMAP_SOURCE_DIR;
  const auto sk = skeleton::Skeleton::build(osm::readOsm(src + "/data/osm/west-oakland.osm"));
  const auto camera = camera::CameraModel::fromYaml(loadYamlFile(src + "/config/vehicle.yaml")["camera"]);
  auto options = lt::replayOptions(false);
  options.accumulator.history_s = 0.0;
  bev::BevBuilder b(sk, camera, options);
  // Drive along two consecutive roads' polylines, frames of all-ego-lane labels at 10 Hz.
  const auto& a = sk.roads().front();
  const auto* next = sk.road(sk.intersection(a.to)->outgoing.front());
  ASSERT_TRUE(next);
  const cv::Mat lane(camera.height(), camera.width(), CV_8UC1, cv::Scalar(1));
  int64_t u = 1'700'000'000'000'000;
  size_t peak_a = 0;
  auto driveAlong = [&](const skeleton::AtomicRoad& road) {
    for (double s = 0.0; s < road.length; s += 0.1) {
      const Eigen::Vector2d p = sk.pointAt(road, s), t = sk.tangentAt(road, s);
      bev::TimedPose pose;
      pose.utime = (u += 10'000);
      pose.position = Eigen::Vector3d(p.x(), p.y(), 0.0);
      pose.orientation = Eigen::AngleAxisd(std::atan2(t.y(), t.x()), Eigen::Vector3d::UnitZ());
      b.addPose(pose);
      if ((u / 10'000) % 10 == 0) b.addFrame(u - 5'000, lane);
      peak_a = std::max(peak_a, b.accumulator().memoryBytes());
    }
  };
  EXPECT_FALSE(b.withOpenRoad([](const bev::RoadBev&) { ADD_FAILURE() << "no road is open yet"; }));
  b.roadEntered(a.id, u);
  driveAlong(a);
  int64_t open = -1;
  int open_frames = 0;
  EXPECT_TRUE(b.withOpenRoad([&](const bev::RoadBev& r) { open = r.road_id, open_frames = r.grid.frames(); }));
  EXPECT_EQ(open, a.id);
  EXPECT_GT(open_frames, 0);
  b.roadClosed(a.id, u);
  b.roadEntered(next->id, u);
  driveAlong(*next);
  const auto closed = b.takeClosed();
  ASSERT_EQ(closed.size(), 1u);
  EXPECT_EQ(closed[0].road_id, a.id);
  EXPECT_EQ(closed[0].cells_outside > 0, true) << "frames also see beyond the corridor";
  // Every stored cell is inside road a's corridor.
  const int t = closed[0].grid.options().tile_cells;
  size_t outside = 0, cells = 0;
  closed[0].grid.forEachTile([&](const BevGrid::Cell& o, const uint16_t* counts) {
    for (int k = 0; k < t * t; ++k) {
      if (!counts[k]) continue;
      ++cells;
      outside += !closed[0].corridor->contains(closed[0].grid.cellCentre(BevGrid::Cell(o.x() + k % t, o.y() + k / t)));
    }
  });
  EXPECT_GT(cells, 1000u);
  EXPECT_EQ(outside, 0u);
  EXPECT_EQ(b.accumulator().activeRoads(), std::vector<int64_t>{next->id});
  EXPECT_TRUE(b.withOpenRoad([&](const bev::RoadBev& r) { open = r.road_id; }));
  EXPECT_EQ(open, next->id);
  // Closing handed road a's memory over: what is held now is the next road's grid only.
  EXPECT_EQ(b.accumulator().memoryBytes(), b.accumulator().active(next->id)->grid.memoryBytes());
  EXPECT_GT(peak_a, 0u);
}

// Without the LIDAR, projection.crown_slope (config/bev_builder.yaml, off as shipped) puts frames on
// the driven road's crown (core/bev/road_crown.h): the simulator's roads have a 2 % crown, so the
// line cells of the roads handed over lie nearer true paint than on the flat plane. A bad value of
// the key is refused, naming it.
TEST(BevBuilder, WithoutTheLidarTheCrownKeyPutsLinesNearerTheTruePaint) {
  const std::string dir = drive();
  ASSERT_FALSE(dir.empty());
  const std::string src = LANEMAP_SOURCE_DIR;
  YAML::Node cfg = loadYamlFile(src + "/config/bev_builder.yaml");
  EXPECT_EQ(bev::BevBuilderOptions::fromYaml(cfg).crown.slope, 0.0) << "off as shipped";
  YAML::Node crowned_cfg = YAML::Clone(cfg);
  crowned_cfg["projection"]["crown_slope"] = 0.02;
  bev::BevBuilderOptions crowned = bev::BevBuilderOptions::fromYaml(crowned_cfg);
  EXPECT_EQ(crowned.crown.slope, 0.02);
  crowned.use_lidar = false;
  crowned.async_mesh = false;
  crowned_cfg["projection"]["crown_slope"] = -0.01;
  EXPECT_THROW(bev::BevBuilderOptions::fromYaml(crowned_cfg), config::ConfigError);

  const auto flat = lt::replayLog(dir + "/drive.lcmlog", lt::replayOptions(false));
  const auto crown = lt::replayLog(dir + "/drive.lcmlog", crowned);
  ASSERT_FALSE(flat->closed.empty());
  ASSERT_EQ(flat->closed.size(), crown->closed.size());
  sim::WorldOptions wo = sim::WorldOptions::fromYamlFile(src + "/config/sim_world.yaml");
  wo.seed = lt::kBevDriveSeed;
  const auto world = sim::buildWorld(*flat->sk, wo);
  Agreement f, c;
  for (size_t i = 0; i < flat->closed.size(); ++i) {
    const Agreement a = compare(flat->closed[i].grid, *world), b = compare(crown->closed[i].grid, *world);
    f.paint += a.paint, f.paint_on_paint += a.paint_on_paint, c.paint += b.paint, c.paint_on_paint += b.paint_on_paint;
  }
  const double pf = double(f.paint_on_paint) / std::max<size_t>(1, f.paint), pc = double(c.paint_on_paint) / std::max<size_t>(1, c.paint);
  std::printf("line cells within 0.1 m of true paint: flat %zu cells, %.1f %%; crown %zu cells, %.1f %%\n", f.paint, 100 * pf,
              c.paint, 100 * pc);
  EXPECT_GT(f.paint, 500u);
  EXPECT_GT(pc, pf);
}

}  // namespace
