// Power loss and kills of a map store writer (issue 18): every file of the store is written
// atomically and durably (core/io/atomic_file.h), so a writer killed at any moment leaves a store
// that loads, at the state before the step it was in or after it, never half.
//
// The writer is a child process that does what the BEV builder and the lane mapper do to a store,
// pass after pass of one road: two checkpoints of the open road (bev/open/road_R.bev + .json), the
// road stored (bev/road_R.bev, merged into the earlier passes), its checkpoint removed, its lanes
// written (lanes/road_R.osm + its sidecar). Each step's effect on what a restarted graph loads is
// modelled (expectedAfter): after a kill the store must load to the model's state after the steps
// the child reported done, or after one more (the step it was in).
//  - RandomKills: SIGKILL after a random delay (seeded), many times; the next writer goes on from
//    the state found (as a restarted process does).
//  - EveryStepOfAPass: the child exits inside the write functions at each of their steps in turn
//    (io::setWriteStepHook): temporary created, half written, written, flushed, renamed, folder
//    flushed, removed.
//  - Durable order: each step is on disk (file flushed before its rename, folder flushed after
//    it) before the next one starts, so a power loss, which can only undo what was not flushed, also
//    leaves a state of the model.
#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/bev/road_bev.h"
#include "core/io/atomic_file.h"
#include "core/io/lanelet2.h"
#include "core/map/lane_map.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace {

using namespace lanemap;
namespace fs = std::filesystem;
namespace lt = lanemap::testing;

constexpr int64_t kRoad = 42;
constexpr int kStepsPerPass = 5;
constexpr int kFramesPerPass = 3;
constexpr double kOriginLat = 37.8, kOriginLon = -122.3;

// The grid of pass p after f frames: every frame adds 1 to cell (p, 0) and to the marker cell
// (1000, 0), plus a band of cells so that the file spans several tiles (~1 MB).
bev::BevGrid passGrid(int p, int frames) {
  bev::BevGrid g;
  for (int f = 0; f < frames; ++f) {
    g.addFrame();
    g.add(bev::BevGrid::Cell(p, 0), bev::Layer::kObserved, 1);
    g.add(bev::BevGrid::Cell(1000, 0), bev::Layer::kObserved, 1);
    for (int x = 0; x < 600; x += 7) g.add(bev::BevGrid::Cell(x, 300 + (x % 50)), bev::Layer::kDrivable, 1);
  }
  return g;
}

// Lanes of pass p: one lanelet whose road_id (kept in the sidecar only) and whose geometry (in the
// OSM file) both say p.
map::LaneMap passLanes(int p) {
  map::LaneMap m;
  m.origin_lat = kOriginLat;
  m.origin_lon = kOriginLon;
  const auto line = [&](int64_t id, double y) {
    map::LineString l;
    l.id = id;
    l.type = map::LineType::kDashed;
    for (int i = 0; i < 200; ++i) l.points.emplace_back(p + 0.25 * i, y, 0.0);
    return l;
  };
  m.lines = {line(1, 3.5), line(2, 0.0)};
  map::Lanelet ll;
  ll.id = 10;
  ll.left_id = 1;
  ll.right_id = 2;
  ll.road_id = p;
  for (size_t i = 0; i < m.lines[0].points.size(); ++i) ll.centre.push_back(0.5 * (m.lines[0].points[i] + m.lines[1].points[i]));
  m.lanelets = {ll};
  return m;
}

std::string lanesPath(const std::string& store) { return store + "/lanes/road_" + std::to_string(kRoad) + ".osm"; }

// Step e of the writer (pass e / 5), as the processes do it.
void doStep(const std::string& store, int64_t e) {
  const int p = static_cast<int>(e / kStepsPerPass);
  bev::RoadBev road;
  road.road_id = kRoad;
  switch (e % kStepsPerPass) {
    case 0:  // the open road checkpointed mid-road
      road.grid = passGrid(p, kFramesPerPass - 1);
      bev::storeCheckpoint(store, road, 1000 + e);
      break;
    case 1:  // and again a frame later
      road.grid = passGrid(p, kFramesPerPass);
      bev::storeCheckpoint(store, road, 1000 + e);
      break;
    case 2:  // the road closes: stored (merged into the earlier passes)
      road.grid = passGrid(p, kFramesPerPass);
      bev::storeRoad(store, road);
      break;
    case 3:
      bev::removeCheckpoint(store, kRoad);
      break;
    case 4:  // the lane mapper maps it
      io::createDirectories(store + "/lanes");
      io::writeLanelet2(passLanes(p), lanesPath(store));
      break;
  }
}

// What a restarted graph finds in the store.
struct StoreState {
  int stored_frames = 0;      // bev/road_R.bev (0: none)
  int checkpoint_frames = 0;  // the checkpoint loadCheckpoints carries on (0: none)
  int lanes_version = -1;     // the pass of lanes/road_R.osm (-1: none)
  bool operator==(const StoreState& o) const {
    return std::tie(stored_frames, checkpoint_frames, lanes_version) == std::tie(o.stored_frames, o.checkpoint_frames, o.lanes_version);
  }
};
std::ostream& operator<<(std::ostream& os, const StoreState& s) {
  return os << "{stored " << s.stored_frames << ", checkpoint " << s.checkpoint_frames << ", lanes " << s.lanes_version << "}";
}

// The model: the state after the first e steps.
StoreState expectedAfter(int64_t e) {
  const int p = static_cast<int>(e / kStepsPerPass), r = static_cast<int>(e % kStepsPerPass);
  StoreState s;
  s.stored_frames = kFramesPerPass * (p + (r >= 3 ? 1 : 0));
  s.checkpoint_frames = r == 1 ? kFramesPerPass - 1 : r == 2 ? kFramesPerPass : 0;  // r == 3: already stored
  s.lanes_version = p - 1;
  return s;
}

// Loads the store as the processes do and checks each file's content is whole and consistent;
// failures are test failures (the state is returned anyway).
StoreState loadStore(const std::string& store) {
  StoreState s;
  const std::string grid_path = bev::roadGridPath(store, kRoad);
  if (fs::exists(grid_path)) {
    const bev::BevGrid g = bev::BevGrid::load(grid_path);  // throws on a torn file
    s.stored_frames = g.frames();
    EXPECT_EQ(g.count(bev::BevGrid::Cell(1000, 0), bev::Layer::kObserved), g.frames()) << "merge half done";
    EXPECT_EQ(g.frames() % kFramesPerPass, 0);
    for (int q = 0; q < g.frames() / kFramesPerPass; ++q) EXPECT_EQ(g.count(bev::BevGrid::Cell(q, 0), bev::Layer::kObserved), kFramesPerPass) << "pass " << q;
  }
  std::vector<std::string> errors;
  std::vector<int64_t> already_stored;
  const auto cps = bev::loadCheckpoints(store, &errors, &already_stored);
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_LE(cps.size(), 1u);
  if (!cps.empty()) {
    const auto& c = cps[0];
    EXPECT_EQ(c.road_id, kRoad);
    s.checkpoint_frames = c.grid.frames();
    const int pass = s.stored_frames / kFramesPerPass;  // the pass after the stored ones
    EXPECT_EQ(c.grid.count(bev::BevGrid::Cell(pass, 0), bev::Layer::kObserved), c.grid.frames()) << "checkpoint of another pass";
  }
  const std::string lanes = lanesPath(store);
  if (fs::exists(lanes)) {
    const io::Lanelet2File f = io::readLanelet2File(lanes, kOriginLat, kOriginLon);
    EXPECT_FALSE(f.sidecar.empty()) << "the map's sidecar is not the one written with it";
    EXPECT_EQ(f.map.lanelets.size(), 1u);
    if (!f.map.lanelets.empty() && !f.map.lines.empty()) {
      s.lanes_version = static_cast<int>(f.map.lanelets[0].road_id);
      const double x0 = f.map.line(1) ? f.map.line(1)->points.front().x() : -1;
      EXPECT_NEAR(x0, s.lanes_version, 1e-3) << "geometry and sidecar of different passes";
    }
  }
  return s;
}

// The temporaries left by killed writers: removed by removeStaleTemporaries, none after.
int tempFilesIn(const std::string& store) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(store)) {
    if (e.path().filename().string().find(".tmp.") != std::string::npos) ++n;
  }
  return n;
}
int removeTemporaries(const std::string& store) {
  int n = 0;
  for (const char* dir : {"", "/bev", "/bev/open", "/lanes"}) n += io::removeStaleTemporaries(store + dir);
  return n;
}

// Runs steps from `first` on in a child; it writes one byte to the pipe after each. Returns the pid.
pid_t startWriter(const std::string& store, int64_t first, int64_t last, int pipe_wr) {
  const pid_t pid = fork();
  if (pid == 0) {
    try {
      for (int64_t e = first; e < last; ++e) {
        doStep(store, e);
        const char b = 1;
        if (write(pipe_wr, &b, 1) != 1) _exit(3);
      }
    } catch (const std::exception& ex) {
      std::fprintf(stderr, "writer: %s\n", ex.what());
      _exit(2);
    }
    _exit(0);
  }
  return pid;
}

int readDone(int pipe_rd) {
  int n = 0;
  char buf[256];
  for (;;) {
    const ssize_t r = read(pipe_rd, buf, sizeof(buf));
    if (r <= 0) break;
    n += static_cast<int>(r);
  }
  return n;
}

TEST(PowerLoss, AWriterKilledAtRandomMomentsLeavesAStoreAtTheStateBeforeOrAfterItsStep) {
  // The kills must fall at many points of many steps on any machine: the delay before a kill is
  // drawn up to a few steps' time as measured here (a step's flushes take ~1 ms on one disk, tens
  // on another), and rounds go on past 60 until the store went through several passes (at most 400).
  double step_ms = 0;
  {
    lt::TempDir scratch("power-loss-timing");
    const auto t0 = std::chrono::steady_clock::now();
    for (int64_t e = 0; e < 2 * kStepsPerPass; ++e) doStep(scratch.str(), e);
    step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / (2 * kStepsPerPass);
  }
  const int max_delay_us = static_cast<int>(std::max(60000.0, 1000.0 * 6 * step_ms));
  std::printf("one step %.1f ms here: kills drawn within %d ms\n", step_ms, max_delay_us / 1000);
  for (const unsigned seed : {1u, 2u}) {
    lt::TempDir dir("power-loss");
    const std::string store = dir.str();
    std::mt19937 rng(seed);
    int64_t e = 0;  // steps the store holds
    int kills = 0, mid_step = 0, temporaries = 0;
    for (int round = 0; round < 60 || (e <= 4 * kStepsPerPass && round < 400); ++round) {
      int fds[2];
      ASSERT_EQ(pipe2(fds, O_CLOEXEC), 0);
      const pid_t pid = startWriter(store, e, e + 1000, fds[1]);
      ASSERT_GT(pid, 0);
      close(fds[1]);
      std::this_thread::sleep_for(std::chrono::microseconds(std::uniform_int_distribution<int>(0, max_delay_us)(rng)));
      kill(pid, SIGKILL);
      int status = 0;
      waitpid(pid, &status, 0);
      ASSERT_TRUE(WIFSIGNALED(status)) << "the writer ended by itself (status " << status << ") before the kill";
      ++kills;
      const int done = readDone(fds[0]);
      close(fds[0]);
      temporaries += tempFilesIn(store);
      const StoreState got = loadStore(store);
      const StoreState before = expectedAfter(e + done), after = expectedAfter(e + done + 1);
      if (got == after && !(got == before)) {
        e += done + 1;
        ++mid_step;
      } else {
        ASSERT_EQ(got, before) << "seed " << seed << " round " << round << ": after " << (e + done)
                               << " steps the store is neither at that state nor at " << after;
        e += done;
      }
      ASSERT_FALSE(::testing::Test::HasFailure()) << "seed " << seed << " round " << round << " step " << e;
      removeTemporaries(store);
      ASSERT_EQ(tempFilesIn(store), 0);
    }
    // The kills fell at many points: the store went through many passes, and some kills came
    // after a step's effect but before the child said so.
    std::printf("seed %u: %d kills, %lld steps (%lld passes), %d found one step further than reported, %d temporaries left and removed\n",
                seed, kills, static_cast<long long>(e), static_cast<long long>(e / kStepsPerPass), mid_step, temporaries);
    EXPECT_GT(e, 3 * kStepsPerPass);
  }
}

// The n-th step of the write functions at which the child exits (fault injection).
int g_exit_at = -1, g_steps_seen = 0;
void exitAtStep(io::WriteStep, const std::string&) {
  if (++g_steps_seen == g_exit_at) _exit(7);
}

std::vector<std::pair<io::WriteStep, std::string>> g_trace;
void recordStep(io::WriteStep s, const std::string& path) { g_trace.emplace_back(s, path); }

TEST(PowerLoss, AWriterStoppedAtEveryStepOfTheWriteFunctionsLeavesAWholeStore) {
  // How many write-function steps one pass has (from a fresh store and from one with a pass).
  lt::TempDir scratch("power-loss-count");
  io::setWriteStepHook(recordStep);
  for (int64_t e = 0; e < 2 * kStepsPerPass; ++e) doStep(scratch.str(), e);
  io::setWriteStepHook(nullptr);
  const int total = static_cast<int>(g_trace.size());
  ASSERT_GT(total, 30);
  int crashes = 0;
  for (int n = 1; n <= total; ++n) {
    lt::TempDir dir("power-loss-step");
    const std::string store = dir.str();
    int fds[2];
    ASSERT_EQ(pipe2(fds, O_CLOEXEC), 0);
    const pid_t pid = fork();
    if (pid == 0) {
      g_exit_at = n;
      io::setWriteStepHook(exitAtStep);
      for (int64_t e = 0; e < 2 * kStepsPerPass; ++e) {
        doStep(store, e);
        const char b = 1;
        if (write(fds[1], &b, 1) != 1) _exit(3);
      }
      _exit(0);
    }
    close(fds[1]);
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 7) << "step " << n << ": status " << status;
    ++crashes;
    const int done = readDone(fds[0]);
    close(fds[0]);
    const StoreState got = loadStore(store);
    EXPECT_TRUE(got == expectedAfter(done) || got == expectedAfter(done + 1))
        << "stopped at write step " << n << " (" << static_cast<int>(g_trace[n - 1].first) << " of " << g_trace[n - 1].second
        << ") in step " << done << ": " << got << ", expected " << expectedAfter(done) << " or " << expectedAfter(done + 1);
    removeTemporaries(store);
    EXPECT_EQ(tempFilesIn(store), 0);
  }
  std::printf("%d stops, one at each write step of two passes\n", crashes);
}

TEST(PowerLoss, EveryStepIsOnDiskBeforeTheNextStarts) {
  // What a power loss can undo is what was not flushed: a file whose data was not fsynced before
  // its rename, a rename or removal whose folder was not fsynced. The trace of two passes from a
  // fresh store: each file flushed before its rename, each folder flushed after a rename, a
  // removal or a new folder, before anything else is written.
  lt::TempDir dir("power-loss-order");
  g_trace.clear();
  io::setWriteStepHook(recordStep);
  for (int64_t e = 0; e < 2 * kStepsPerPass; ++e) doStep(dir.str(), e);
  io::setWriteStepHook(nullptr);
  ASSERT_FALSE(g_trace.empty());
  std::string pending_folder;   // a folder change not yet flushed
  std::set<std::string> synced;  // files flushed, not yet renamed into place
  std::set<std::string> placed;  // files flushed and renamed into place
  int renames = 0, removals = 0, folder_syncs = 0;
  for (const auto& [step, path] : g_trace) {
    switch (step) {
      case io::WriteStep::kTemporaryCreated:
      case io::WriteStep::kRemoved:
        EXPECT_TRUE(pending_folder.empty()) << path << " starts before folder " << pending_folder << " is flushed";
        if (step == io::WriteStep::kRemoved) {
          pending_folder = fs::path(path).parent_path().string();
          ++removals;
        }
        break;
      case io::WriteStep::kFileSynced: synced.insert(path); break;
      case io::WriteStep::kRenamed: {
        EXPECT_TRUE(pending_folder.empty()) << path << " renamed before folder " << pending_folder << " is flushed";
        // A written file is flushed before its rename; a sidecar moved into place was flushed as
        // MAP.next.lanemap.json.
        const std::string suffix = ".lanemap.json";
        if (synced.erase(path)) {
          placed.insert(path);
        } else {
          const std::string from = path.size() > suffix.size() ? path.substr(0, path.size() - suffix.size()) + ".next" + suffix : "";
          EXPECT_TRUE(placed.count(from)) << path << " renamed without being flushed";
        }
        pending_folder = fs::path(path).parent_path().string();
        ++renames;
        break;
      }
      case io::WriteStep::kFolderSynced:
        if (!pending_folder.empty()) { EXPECT_EQ(fs::path(path), fs::path(pending_folder)); }
        pending_folder.clear();
        ++folder_syncs;
        break;
      default: break;
    }
  }
  EXPECT_TRUE(pending_folder.empty()) << "the last change of " << pending_folder << " is not flushed";
  // Two passes: 4 checkpoint grids + 4 JSONs, 2 stored grids, 2 x (map + sidecar written, sidecar
  // renamed, map_projector_info.yaml).
  EXPECT_EQ(renames, 4 + 4 + 2 + 2 * 4);
  EXPECT_EQ(removals, 2 * 2);
  // The folders a fresh store needed (bev, bev/open, lanes) were flushed into their parents too.
  EXPECT_GE(folder_syncs, renames + removals + 3);
}

}  // namespace
