// The map store in trouble (issue 18, docs/robustness.md's bad-input rows): a second process on the
// same store, a read-only store, a full disk. Each gives a clear message and exit code, and
// leaves the store as it was: nothing partial, no temporary, the old files still loading.
//
// The read-only store and the full disk are real: the test re-runs itself in a private mount
// namespace (`unshare -rm`, unprivileged) where the store folder is bind-mounted read-only, or is
// a 512 KiB tmpfs. The processes there use memq:// (no network).
#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/bev/road_bev.h"
#include "core/io/atomic_file.h"
#include "core/io/lanelet2.h"
#include "core/io/store_lock.h"
#include "core/map/lane_map.h"
#include "tests/bev/bev_replay.h"
#include "tests/common/child_process.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>

namespace {

using namespace lanemap;
namespace fs = std::filesystem;
namespace lt = lanemap::testing;

const std::string kSource = std::string(LANEMAP_DATA_DIR) + "/..";
const std::string kOsm = std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm";

bev::RoadBev roadWithFrames(int64_t id, int frames, int tiles) {
  bev::RoadBev r;
  r.road_id = id;
  for (int f = 0; f < frames; ++f) {
    r.grid.addFrame();
    for (int t = 0; t < tiles; ++t) r.grid.add(bev::BevGrid::Cell(t * r.grid.options().tile_cells, 0), bev::Layer::kObserved, 1);
  }
  return r;
}

map::LaneMap laneMap(int points, double x0) {
  map::LaneMap m;
  m.origin_lat = 37.8;
  m.origin_lon = -122.3;
  for (int id : {1, 2}) {
    map::LineString l;
    l.id = id;
    l.type = map::LineType::kDashed;
    for (int i = 0; i < points; ++i) l.points.emplace_back(x0 + 0.1 * i, id == 1 ? 3.5 : 0.0, 0.0);
    m.lines.push_back(l);
  }
  map::Lanelet ll;
  ll.id = 10;
  ll.left_id = 1;
  ll.right_id = 2;
  ll.road_id = 5;
  for (int i = 0; i < points; ++i) ll.centre.push_back(0.5 * (m.lines[0].points[i] + m.lines[1].points[i]));
  m.lanelets = {ll};
  return m;
}

int temporaries(const std::string& dir) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) n += e.path().filename().string().find(".tmp.") != std::string::npos;
  return n;
}

// A store with one stored road (3 frames) and the lanes of road 5.
void fillStore(const std::string& store) {
  bev::storeRoad(store, roadWithFrames(7, 3, 1));
  io::createDirectories(store + "/lanes");
  io::writeLanelet2(laneMap(20, 0.0), store + "/lanes/road_5.osm");
}

// The store still as fillStore left it.
void expectStoreUnchanged(const std::string& store) {
  EXPECT_EQ(bev::BevGrid::load(bev::roadGridPath(store, 7)).frames(), 3);
  const auto f = io::readLanelet2File(store + "/lanes/road_5.osm", 37.8, -122.3);
  EXPECT_FALSE(f.sidecar.empty()) << "the old map lost its sidecar";
  ASSERT_EQ(f.map.lanelets.size(), 1u);
  EXPECT_EQ(f.map.lanelets[0].road_id, 5);
  EXPECT_NEAR(f.map.line(1)->points.front().x(), 0.0, 1e-3);
  EXPECT_EQ(temporaries(store), 0);
  EXPECT_FALSE(fs::exists(store + "/lanes/road_5.next.lanemap.json")) << "a sidecar of a map never written is left";
}

// Re-runs the current test in a private mount namespace after `setup` (sh, with $D the folder);
// the test then finds LANEMAP_TEST_STORE set. Returns the exit status.
int rerunInMountNamespace(const std::string& dir, const std::string& setup) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string filter = std::string(info->test_suite_name()) + "." + info->name();
  char exe[4096] = {0};
  if (readlink("/proc/self/exe", exe, sizeof(exe) - 1) <= 0) return -1;
  const std::string cmd = "D='" + dir + "' unshare -rm sh -c '" + setup + " && LANEMAP_TEST_STORE=\"$D\" exec \"$0\" --gtest_filter=\"$1\"' '" +
                          exe + "' '" + filter + "'";
  const int rc = std::system(cmd.c_str());
  return rc == -1 ? -1 : WEXITSTATUS(rc);
}

std::string processCommand(const std::string& name, const std::string& store) {
  return lt::binPath("lanemap-" + name) + " --lcm-url memq:// --config " + kSource + "/config/" +
         (name == "bev-builder" ? "bev_builder" : "lane_mapper") + ".yaml --osm " + kOsm + " --store " + store;
}

TEST(StoreLock, ASecondWriterIsRefusedNamingTheHolderAndAKilledHolderBlocksNothing) {
  lt::TempDir dir("store-lock");
  const std::string store = dir.str("store");
  {
    const io::StoreLock first(store, "bev_builder");
    EXPECT_EQ(first.path(), store + "/.lock-bev_builder");
    try {
      const io::StoreLock second(store, "bev_builder");
      ADD_FAILURE() << "a second bev_builder lock was given";
    } catch (const io::StoreInUseError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("in use by bev_builder, pid " + std::to_string(getpid())), std::string::npos) << m;
      EXPECT_NE(m.find(store), std::string::npos) << m;
    }
    const io::StoreLock other_role(store, "lane_mapper");  // the lane mapper beside the BEV builder: normal
  }
  { const io::StoreLock again(store, "bev_builder"); }  // released with its holder
  // A holder killed with SIGKILL: the kernel drops its lock, the lock file stays and blocks nothing.
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    const io::StoreLock held(store, "bev_builder");
    const char b = 1;
    if (write(fds[1], &b, 1) != 1) _exit(3);
    pause();
    _exit(0);
  }
  char b;
  ASSERT_EQ(read(fds[0], &b, 1), 1);
  EXPECT_THROW(io::StoreLock(store, "bev_builder"), io::StoreInUseError);
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  EXPECT_NO_THROW(io::StoreLock(store, "bev_builder"));
  close(fds[0]);
  close(fds[1]);
}

TEST(StoreLock, ASecondBevBuilderOrLaneMapperOnTheSameStoreExitsWith4) {
  lt::TempDir dir("store-lock-proc");
  const std::string store = dir.str("store");
  for (const std::string name : {"bev-builder", "lane-mapper"}) {
    const std::string role = name == "bev-builder" ? "bev_builder" : "lane_mapper";
    lt::ChildProcess first({"/bin/sh", "-c", "exec " + processCommand(name, store) + " 2>/dev/null"});
    ASSERT_TRUE(first.started());
    // Until the first holds the lock (its pid in the lock file).
    const std::string lock = store + "/.lock-" + role;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (io::StoreLock::describeHolder(lock).find("pid " + std::to_string(first.pid())) == std::string::npos &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    const auto second = lt::runCommand(processCommand(name, store));
    EXPECT_EQ(second.exit_code, io::kExitStoreInUse) << second.output;
    EXPECT_NE(second.output.find("is in use by " + role + ", pid " + std::to_string(first.pid())), std::string::npos) << second.output;
    EXPECT_NE(second.output.find("another --store"), std::string::npos) << second.output;
    EXPECT_EQ(first.stop(), 0) << name << " (the first) did not run on";
  }
}

TEST(StoreErrors, AReadOnlyStoreIsAClearErrorAndStaysAsItWas) {
  const char* inner = std::getenv("LANEMAP_TEST_STORE");
  if (!inner) {
    lt::TempDir dir("store-ro");
    fillStore(dir.str());
    ASSERT_EQ(rerunInMountNamespace(dir.str(), "mount --bind \"$D\" \"$D\" && mount -o remount,ro,bind \"$D\" \"$D\""), 0);
    expectStoreUnchanged(dir.str());
    return;
  }
  const std::string store = inner;
  ASSERT_NE(::access(store.c_str(), W_OK), 0) << "the store is not read-only here";
  const auto throwsNaming = [](const std::function<void()>& f, const std::string& what) {
    try {
      f();
      ADD_FAILURE() << "no error for " << what;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("Read-only file system"), std::string::npos) << what << ": " << e.what();
    }
  };
  throwsNaming([&] { bev::storeRoad(store, roadWithFrames(7, 2, 1)); }, "storeRoad");
  throwsNaming([&] { bev::storeCheckpoint(store, roadWithFrames(8, 2, 1), 5); }, "storeCheckpoint");
  throwsNaming([&] { io::writeLanelet2(laneMap(20, 1.0), store + "/lanes/road_5.osm"); }, "writeLanelet2");
  throwsNaming([&] { io::StoreLock(store, "bev_builder"); }, "StoreLock");
  for (const std::string name : {"bev-builder", "lane-mapper"}) {
    const auto r = lt::runCommand(processCommand(name, store));
    EXPECT_EQ(r.exit_code, io::kExitStoreError) << r.output;
    EXPECT_NE(r.output.find("map store '" + store + "' cannot be written (Read-only file system)"), std::string::npos) << r.output;
  }
  expectStoreUnchanged(store);
}

TEST(StoreErrors, AFullDiskFailsTheWriteAndLeavesTheOldFiles) {
  const char* inner = std::getenv("LANEMAP_TEST_STORE");
  if (!inner) {
    lt::TempDir dir("store-full");
    ASSERT_EQ(rerunInMountNamespace(dir.str(), "mount -t tmpfs -o size=512k tmpfs \"$D\""), 0);
    return;
  }
  const std::string store = inner;
  fillStore(store);  // ~70 KB of the 512 KiB
  const auto throwsNoSpace = [](const std::function<void()>& f, const std::string& what) {
    try {
      f();
      ADD_FAILURE() << "no error for " << what;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << what << ": " << e.what();
    }
  };
  // A road of 12 tiles (~800 KB) merged into the stored one, a checkpoint of it, a 60,000-point map.
  throwsNoSpace([&] { bev::storeRoad(store, roadWithFrames(7, 2, 12)); }, "storeRoad");
  throwsNoSpace([&] { bev::storeCheckpoint(store, roadWithFrames(7, 2, 12), 5); }, "storeCheckpoint");
  throwsNoSpace([&] { io::writeLanelet2(laneMap(60000, 1.0), store + "/lanes/road_5.osm"); }, "writeLanelet2");
  expectStoreUnchanged(store);
  EXPECT_TRUE(bev::loadCheckpoints(store).empty()) << "a checkpoint that could not be written is not half there";
  // The BEV builder on a store with no room left: a clear error at the start, exit 2.
  {
    std::ofstream fill(store + "/filler", std::ios::binary);
    const std::string mb(1 << 20, 'x');
    fill << mb;  // fails at the end of the room; what is written stays
  }
  const auto r = lt::runCommand(processCommand("bev-builder", store));
  EXPECT_EQ(r.exit_code, io::kExitStoreError) << r.output;
  EXPECT_NE(r.output.find("No space left on device"), std::string::npos) << r.output;
  // lanemap-offline writing its map there: exit 2 with the reason, no map, no temporary.
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  ASSERT_FALSE(drive.empty());
  const auto off = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --log " + drive + "/drive.lcmlog --osm " + drive +
                                  "/roads.osm --out " + store + "/offline");
  EXPECT_EQ(off.exit_code, 2) << off.output;
  EXPECT_NE(off.output.find("No space left on device"), std::string::npos) << off.output;
  EXPECT_FALSE(fs::exists(store + "/offline/map.osm"));
  fs::remove_all(store + "/offline");
  fs::remove(store + "/filler");
  expectStoreUnchanged(store);
}

}  // namespace
