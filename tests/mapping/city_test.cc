// lanemap-city (issue 14): drives projected apart (several at once, or by Slurm's array tasks, on a
// one-node Slurm cluster the test brings up) and fused in the store's order with --no-drive-offsets
// give the map `lanemap-offline --log A --log B --log C` makes of them, byte for byte; by default
// each drive's own offset is solved first (the map of lanemap-offline --traversals ...
// --drive-offsets); a later run projects only its new drives; bad input gets a clear error and
// leaves the store as it was.
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"
#include "tests/common/temp_dir.h"

#include <Eigen/Core>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/file.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

namespace lt = lanemap::testing;
namespace fs = std::filesystem;
using lanemap::testing::readFile;

namespace {

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// Three 20 s drives of one West Oakland world: 1, 2 along drive 1's route (it closes drive 1's
// roads again: aligned merges), 3 a route of its own. Made once for every test process
// (sharedSimDrive), the sequential run's map once for each.
class City : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new lt::TempDir("city");
    const std::string world = "--world-seed 11 --no-lidar --camera-hz 5";
    drives_[1] = lt::sharedSimDrive("osm/west-oakland.osm", 20, 1, world);
    const auto s1 = readJson(drives_[1] + "/scenario.json");
    std::string route;
    for (const auto& road : s1["route"]) route += std::to_string(road["from"].get<int64_t>()) + ",";
    route += std::to_string(s1["route"].back()["to"].get<int64_t>());
    drives_[2] = lt::sharedSimDrive("osm/west-oakland.osm", 20, 2, world + " --route " + route);
    drives_[3] = lt::sharedSimDrive("osm/west-oakland.osm", 20, 3, world);
    // The reference: the three drives mapped in one lanemap-offline run.
    const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --osm " + osm() + " --log " + log(1) +
                                  " --log " + log(2) + " --log " + log(3) + " --out " + tmp_->str("sequential"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    delete tmp_;
    tmp_ = nullptr;
  }
  static std::string osm() { return drives_[1] + "/roads.osm"; }
  static std::string log(int i) { return drives_[i] + "/drive.lcmlog"; }
  static std::string city(const std::string& store) {
    return lt::binPath("lanemap-city") + " --oracle --no-lidar --osm " + osm() + " --store " + tmp_->str(store);
  }
  static void expectSequentialMap(const std::string& map_dir) {
    for (const char* f : {"map.osm", "map.geojson", "map.png"}) {
      EXPECT_EQ(readFile(map_dir + "/" + f), readFile(tmp_->str("sequential/") + f)) << f << " differs from the sequential run's";
    }
    auto a = readJson(map_dir + "/summary.json"), b = readJson(tmp_->str("sequential/summary.json"));
    a.erase("seconds");
    b.erase("seconds");
    EXPECT_EQ(a, b);
  }
  // A sharded fusion's summary lists the roads (and each drive's merges) in road order, one
  // process in the order it mapped them: the same entries.
  static nlohmann::json inRoadOrder(nlohmann::json s) {
    auto byRoad = [](nlohmann::json& a) {
      std::stable_sort(a.begin(), a.end(), [](const nlohmann::json& x, const nlohmann::json& y) {
        return x["road_id"].get<int64_t>() < y["road_id"].get<int64_t>();
      });
    };
    s.erase("seconds");
    byRoad(s["roads"]);
    byRoad(s["partial_not_mapped"]);
    for (auto& d : s["drives"]) byRoad(d["merged"]);
    return s;
  }
  static void expectMapOf(const std::string& map_dir, const std::string& reference_dir) {
    for (const char* f : {"map.osm", "map.geojson", "map.png"}) {
      EXPECT_EQ(readFile(map_dir + "/" + f), readFile(reference_dir + "/" + f)) << f << " differs from " << reference_dir << "'s";
    }
    EXPECT_EQ(inRoadOrder(readJson(map_dir + "/summary.json")), inRoadOrder(readJson(reference_dir + "/summary.json")));
  }
  static lt::TempDir* tmp_;
  static std::string drives_[4];
};
lt::TempDir* City::tmp_ = nullptr;
std::string City::drives_[4];

}  // namespace

TEST_F(City, DrivesProjectedOnTwoCoresFuseIntoTheMapOfOneSequentialRun) {
  const auto seq = readJson(tmp_->str("sequential/summary.json"));
  ASSERT_EQ(seq["drives"].size(), 3u);
  ASSERT_FALSE(seq["drives"][1]["merged"].empty()) << "drive 2 merged nothing onto drive 1: the test shows no fusion";
  const auto r = lt::runCommand(city("two-cores") + " --no-drive-offsets --jobs 2 " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 drives projected"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("on 2 jobs"), std::string::npos) << r.output;
  for (const char* slot : {"0000", "0001", "0002"}) {
    EXPECT_TRUE(fs::exists(tmp_->str("two-cores/projections/") + slot + "/projection.json")) << slot;
  }
  expectSequentialMap(tmp_->str("two-cores/map"));
}

TEST_F(City, ALaterRunProjectsOnlyItsNewDrivesAndFusesThemAll) {
  auto r = lt::runCommand(city("later") + " --no-drive-offsets " + log(1) + " " + log(2));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::file_time_type first = fs::last_write_time(tmp_->str("later/projections/0000/projection.json"));
  r = lt::runCommand(city("later") + " --no-drive-offsets " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(log(2) + " is in the store already (0001)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 drive projected"), std::string::npos) << r.output;
  EXPECT_EQ(fs::last_write_time(tmp_->str("later/projections/0000/projection.json")), first);  // not projected again
  EXPECT_TRUE(fs::exists(tmp_->str("later/projections/0002/projection.json")));
  expectSequentialMap(tmp_->str("later/map"));
}

// The Slurm jobs lanemap-city writes, run as Slurm would run them (each array task with its
// SLURM_ARRAY_TASK_ID, then the fusion): the same map. (No Slurm cluster here: the scheduler is
// not in the test, the job scripts are.)
TEST_F(City, TheSlurmJobScriptsRunTaskByTaskGiveTheSameMap) {
  auto r = lt::runCommand(city("slurm") + " --no-drive-offsets --slurm --slurm-dry-run " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string project = readFile(tmp_->str("slurm/slurm/project.sbatch"));
  EXPECT_NE(project.find("#SBATCH --array=0-2\n"), std::string::npos) << project;
  // The fusion job fuses as asked (it runs lanemap-city again, whose default solves the offsets).
  EXPECT_NE(readFile(tmp_->str("slurm/slurm/fuse.sbatch")).find(" --no-drive-offsets\n"), std::string::npos);
  EXPECT_FALSE(fs::exists(tmp_->str("slurm/map")));  // nothing run
  for (int task : {2, 0, 1}) {  // array tasks run in any order
    r = lt::runCommand("SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " bash " + tmp_->str("slurm/slurm/project.sbatch"));
    ASSERT_EQ(r.exit_code, 0) << "task " << task << ": " << r.output;
  }
  r = lt::runCommand("SLURM_ARRAY_TASK_ID=3 bash " + tmp_->str("slurm/slurm/project.sbatch"));
  EXPECT_EQ(r.exit_code, 2) << r.output;  // no such task
  r = lt::runCommand("bash " + tmp_->str("slurm/slurm/fuse.sbatch"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectSequentialMap(tmp_->str("slurm/map"));
}

// --align-rotation reaches every lanemap-offline the fusion runs: the one fusion job, and the
// sharded chain's plan (read by each step); with --no-align it is refused.
TEST_F(City, TheRotationSearchReachesTheFusionJobs) {
  auto r = lt::runCommand(city("turns") + " --align-rotation --slurm --slurm-dry-run " + log(1) + " " + log(2));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string fuse = readFile(tmp_->str("turns/slurm/fuse.sbatch"));
  EXPECT_NE(fuse.find(" --align-rotation"), std::string::npos) << fuse;
  r = lt::runCommand(city("turns-shards") + " --align-rotation --shards 2 --slurm --slurm-dry-run " + log(1) + " " + log(2));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* job : {"fuse-prepare", "fuse-shards", "fuse-assemble"}) {
    const std::string script = readFile(tmp_->str("turns-shards/slurm/") + job + ".sbatch");
    EXPECT_NE(script.find(" --align-rotation"), std::string::npos) << job << ": " << script;
  }
  r = lt::runCommand(city("turns-no") + " --align-rotation --no-align " + log(1));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("excludes"), std::string::npos) << r.output;
}

// --shards N: each shard's roads aligned, fused and explored apart, then assembled: the map of one
// fusion process, byte for byte (the summary's entries the same, in road order), whatever N; with
// the drives' offsets solved too (the default), once, for every shard.
TEST_F(City, AFusionInShardsOfRoadsGivesTheMapOfOneProcessWhateverTheNumberOfShards) {
  auto r = lt::runCommand(city("shards1") + " --no-drive-offsets --shards 1 " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("fused in 1 shards"), std::string::npos) << r.output;
  expectMapOf(tmp_->str("shards1/map"), tmp_->str("sequential"));
  EXPECT_FALSE(fs::exists(tmp_->str("shards1/fusion"))) << "the shards' work is removed once the map is in place";
  r = lt::runCommand(city("shards3") + " --no-drive-offsets --shards 3 --jobs 2 " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("fused in 3 shards on 2 jobs"), std::string::npos) << r.output;
  expectMapOf(tmp_->str("shards3/map"), tmp_->str("sequential"));
  const auto seq = readJson(tmp_->str("sequential/summary.json"));
  std::set<int64_t> roads;
  for (const auto& e : seq["roads"]) roads.insert(e["road_id"].get<int64_t>() % 3);
  EXPECT_GE(roads.size(), 2u) << "the roads fall into one shard of 3: the test shows no sharding";
  // The default: each drive's offset solved first (once), every shard undoing the same offsets.
  r = lt::runCommand(city("offsets-one") + " " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = lt::runCommand(city("offsets-shards") + " --shards 2 " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectMapOf(tmp_->str("offsets-shards/map"), tmp_->str("offsets-one/map"));
  EXPECT_NE(readFile(tmp_->str("offsets-shards/map/map.osm")), readFile(tmp_->str("sequential/map.osm")))
      << "the offsets moved nothing: the test cannot tell that the shards undid them";
}

// The sharded fusion's Slurm jobs, run as Slurm would (array tasks in any order, each step after
// the one before): the same map. An assembly before every shard has finished is refused and
// leaves no map; the steps refuse what they cannot do.
TEST_F(City, TheShardedSlurmJobsRunStepByStepGiveTheSameMap) {
  auto r = lt::runCommand(city("slurm-shards") + " --no-drive-offsets --shards 2 --slurm --slurm-dry-run " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string dir = tmp_->str("slurm-shards/slurm/");
  EXPECT_FALSE(fs::exists(dir + "fuse.sbatch")) << "one fusion job besides the sharded ones";
  EXPECT_NE(readFile(dir + "fuse-shards.sbatch").find("#SBATCH --array=0-1\n"), std::string::npos) << readFile(dir + "fuse-shards.sbatch");
  EXPECT_NE(readFile(dir + "fuse-prepare.sbatch").find("--shards 2 --fuse-step prepare"), std::string::npos);
  for (int task : {1, 2, 0}) {
    r = lt::runCommand("SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " bash " + dir + "project.sbatch");
    ASSERT_EQ(r.exit_code, 0) << "task " << task << ": " << r.output;
  }
  r = lt::runCommand("SLURM_ARRAY_TASK_ID=0 bash " + dir + "fuse-shards.sbatch");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no sharded fusion is prepared"), std::string::npos) << r.output;
  r = lt::runCommand("bash " + dir + "fuse-prepare.sbatch");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = lt::runCommand("SLURM_ARRAY_TASK_ID=1 bash " + dir + "fuse-shards.sbatch");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = lt::runCommand("bash " + dir + "fuse-assemble.sbatch");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("shard 0 has not finished"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp_->str("slurm-shards/map")));
  r = lt::runCommand("SLURM_ARRAY_TASK_ID=2 bash " + dir + "fuse-shards.sbatch");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no shard 2: the fusion is prepared in 2 shards"), std::string::npos) << r.output;
  r = lt::runCommand("SLURM_ARRAY_TASK_ID=0 bash " + dir + "fuse-shards.sbatch");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = lt::runCommand("bash " + dir + "fuse-assemble.sbatch");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectMapOf(tmp_->str("slurm-shards/map"), tmp_->str("sequential"));

  // lanemap-offline's own checks: an assembly missing a shard, or of other drives' shards.
  std::string trav;
  for (const char* slot : {"0000", "0001", "0002"}) trav += " --traversals " + tmp_->str("slurm-shards/projections/") + slot;
  const std::string offline = lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --osm " + osm();
  for (int k : {0, 1, 2}) {
    r = lt::runCommand(offline + trav + " --shard " + std::to_string(k) + "/3 --out " + tmp_->str("own/s") + std::to_string(k));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  r = lt::runCommand(offline + trav + " --assemble " + tmp_->str("own/s0") + " --assemble " + tmp_->str("own/s2") + " --out " + tmp_->str("own/m"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("shard 1/3 is missing: its roads would be lost"), std::string::npos) << r.output;
  r = lt::runCommand(offline + " --traversals " + tmp_->str("slurm-shards/projections/0000") + " --assemble " + tmp_->str("own/s0") +
                     " --assemble " + tmp_->str("own/s1") + " --assemble " + tmp_->str("own/s2") + " --out " + tmp_->str("own/m"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is a shard of other drives than these --traversals"), std::string::npos) << r.output;
  r = lt::runCommand(offline + trav + " --shard 3/3 --out " + tmp_->str("own/bad"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--shard takes K/N with 0 <= K < N"), std::string::npos) << r.output;
  r = lt::runCommand(offline + trav + " --assemble " + tmp_->str("own/s0") + " --assemble " + tmp_->str("own/s1") + " --assemble " +
                     tmp_->str("own/s2") + " --out " + tmp_->str("own/m"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectMapOf(tmp_->str("own/m"), tmp_->str("sequential"));
}

// A one-node Slurm cluster on this machine (munged, slurmctld, slurmd in a private network
// namespace: tests/mapping/slurm_cluster.sh): lanemap-city --slurm --shards 2 submits the
// projection array, then the fusion's steps, each after the one before (afterok): the
// preparation, the shards (an array) and the assembly; when the jobs have run, the store holds the
// sequential run's map.
TEST_F(City, ASlurmClusterOnThisMachineRunsTheJobsToTheSameMap) {
  if (geteuid() != 0) GTEST_SKIP() << "starting Slurm's daemons needs root (CI runs as root)";
  for (const char* tool : {"munged", "slurmctld", "slurmd", "sbatch", "unshare"}) {
    ASSERT_EQ(lt::runCommand(std::string("command -v ") + tool).exit_code, 0)
        << tool << " is missing: scripts/install-deps.sh installs munge and slurm-wlm";
  }
  const auto r = lt::runCommand("unshare -n " + std::string(LANEMAP_SOURCE_DIR) + "/tests/mapping/slurm_cluster.sh " +
                                tmp_->str("cluster") + " 240 " + city("on-slurm") + " --no-drive-offsets --shards 2 --slurm " + log(1) + " " +
                                log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("projection array job"), std::string::npos) << r.output;
  for (const char* job : {"fuse-prepare job", "fuse-shards job", "fuse-assemble job"}) {
    EXPECT_NE(r.output.find(job), std::string::npos) << r.output;
  }
  for (const char* task : {"0", "1", "2"}) {
    EXPECT_TRUE(fs::exists(tmp_->str("on-slurm/slurm/project-") + task + ".log")) << "array task " << task << " did not run";
  }
  for (const char* task : {"0", "1"}) {
    EXPECT_TRUE(fs::exists(tmp_->str("on-slurm/slurm/fuse-shards-") + task + ".log")) << "shard task " << task << " did not run";
  }
  ASSERT_TRUE(fs::exists(tmp_->str("on-slurm/map/map.osm"))) << readFile(tmp_->str("on-slurm/slurm/fuse-assemble.log"));
  expectMapOf(tmp_->str("on-slurm/map"), tmp_->str("sequential"));
}

// By default each drive's own offset is solved over the roads drives share (--drive-offsets). Drives
// 1 and 2 drive one route, each with its campaign pose offset (scenario.json pose_offset, drawn per
// drive): the difference of their solved offsets is the difference of those, and the linked drives'
// offsets have zero mean; a drive that shares no road keeps none. The map is lanemap-offline's of
// the store's projections with --drive-offsets, byte for byte.
TEST_F(City, DriveOffsetsSolvedOverSharedRoadsAreTheDrivesPoseOffsets) {
  auto r = lt::runCommand(city("offsets") + " --drive-offsets --no-drive-offsets " + log(1));
  EXPECT_NE(r.exit_code, 0) << "both asked: refused";
  EXPECT_FALSE(fs::exists(tmp_->str("offsets/map")));
  r = lt::runCommand(city("offsets") + " " + log(1) + " " + log(2) + " " + log(3));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string trav;
  for (const char* slot : {"0000", "0001", "0002"}) trav += " --traversals " + tmp_->str("offsets/projections/") + slot;
  r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --osm " + osm() + trav + " --drive-offsets --out " +
                     tmp_->str("offsets-offline"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"map.osm", "map.geojson"}) {
    EXPECT_EQ(readFile(tmp_->str("offsets/map/") + f), readFile(tmp_->str("offsets-offline/") + f)) << f;
  }
  EXPECT_NE(readFile(tmp_->str("offsets/map/map.osm")), readFile(tmp_->str("sequential/map.osm")))
      << "the offsets moved nothing: the test cannot tell the default from --no-drive-offsets";
  const auto summary = readJson(tmp_->str("offsets/map/summary.json"));
  ASSERT_EQ(summary["drives"].size(), 3u);
  Eigen::Vector2d solved[3], pose[3];
  int measurements[3];
  for (int d = 0; d < 3; ++d) {
    const auto& j = summary["drives"][d];
    ASSERT_TRUE(j.contains("offset_m")) << j.dump();
    solved[d] = {j["offset_m"][0].get<double>(), j["offset_m"][1].get<double>()};
    measurements[d] = j["offset_measurements"].get<int>();
    const auto s = readJson(drives_[d + 1] + "/scenario.json")["pose_offset"];
    pose[d] = {s["east_m"].get<double>(), s["north_m"].get<double>()};
  }
  ASSERT_GT(measurements[0], 0) << "drives 1 and 2 share their route";
  ASSERT_GT(measurements[1], 0);
  const Eigen::Vector2d diff_pose = pose[0] - pose[1], diff_solved = solved[0] - solved[1];
  std::printf("pose offsets 1-2 %.2f %.2f m, solved %.2f %.2f m (drive 3: %d measurements)\n", diff_pose.x(), diff_pose.y(),
              diff_solved.x(), diff_solved.y(), measurements[2]);
  ASSERT_GT(diff_pose.norm(), 0.2) << "the drives' offsets differ enough to test";
  // To 0.2 m: along a road of continuous lines the shift is fixed by dashes and stop lines only
  // (bev_align.h), and the drives' heading biases turn their evidence a little (seen: 0.17 m east).
  EXPECT_NEAR(diff_solved.x(), diff_pose.x(), 0.2);
  EXPECT_NEAR(diff_solved.y(), diff_pose.y(), 0.2);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int d = 0; d < 3; ++d) {
    if (measurements[d] > 0) sum += solved[d];
    if (measurements[d] == 0) {
      EXPECT_EQ(solved[d], Eigen::Vector2d::Zero()) << "drive " << d + 1 << " linked to none";
    }
  }
  EXPECT_LT(sum.norm(), 1e-6) << "the linked drives' offsets have zero mean";
}

TEST_F(City, BadInputGetsAClearErrorAndLeavesTheStoreAsItWas) {
  auto r = lt::runCommand(city("bad") + " " + log(1));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string map_before = readFile(tmp_->str("bad/map/map.osm"));
  ASSERT_FALSE(map_before.empty());

  // A second run while one holds the store.
  {
    const int fd = ::open(tmp_->str("bad/.lock").c_str(), O_RDWR);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);
    ASSERT_EQ(ftruncate(fd, 0), 0);
    ASSERT_EQ(pwrite(fd, "4242", 4, 0), 4);
    r = lt::runCommand(city("bad") + " " + log(2));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("is in use by another lanemap-city (pid 4242)"), std::string::npos) << r.output;
    ::close(fd);
  }
  EXPECT_FALSE(fs::exists(tmp_->str("bad/projections/0001")));

  // Not a log: its projection fails, is not added, the others are; the map is made of those.
  std::ofstream(tmp_->str("not-a-log.lcmlog")) << "this is not an LCM log\n";
  r = lt::runCommand(city("bad") + " " + tmp_->str("not-a-log.lcmlog"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("could not be projected"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not an LCM log"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp_->str("bad/projections/0001")));
  EXPECT_EQ(readFile(tmp_->str("bad/map/map.osm")), map_before);

  // A drive of another area (a small network on another continent): named, not added, and the
  // map stays; lanemap-offline mapping it alone says why instead of "no road was mapped".
  const std::string elsewhere = lt::sharedSimDrive("osm/dev/tiny_roundabout.osm", 4, 1, "--no-lidar --camera-hz 5");
  r = lt::runCommand(city("bad") + " " + elsewhere + "/drive.lcmlog");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("could not be projected"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("poses comes within 50 m of a road of the OSM data"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("a drive of another area, or the wrong --osm?"), std::string::npos) << r.output;
  int projections = 0;
  for (const auto& e : fs::directory_iterator(tmp_->str("bad/projections"))) projections += e.is_directory();
  EXPECT_EQ(projections, 1) << "only the first drive's projection is in the store";
  EXPECT_EQ(readFile(tmp_->str("bad/map/map.osm")), map_before);
  r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --osm " + osm() + " --log " + elsewhere +
                     "/drive.lcmlog --out " + tmp_->str("elsewhere"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("poses comes within 50 m of a road of the OSM data"), std::string::npos) << r.output;
  // Beside a drive of the area: that one is mapped, the other named in summary.json.
  r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --osm " + osm() + " --log " + log(1) + " --log " +
                     elsewhere + "/drive.lcmlog --out " + tmp_->str("with-elsewhere"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto with = readJson(tmp_->str("with-elsewhere/summary.json"));
  ASSERT_EQ(with["drives"].size(), 2u);
  EXPECT_FALSE(with["drives"][0].contains("not_mapped"));
  EXPECT_NE(with["drives"][1].value("not_mapped", std::string()).find("a drive of another area"), std::string::npos) << with.dump();
  EXPECT_GT(with["lanelets"].get<int>(), 0);

  // A projection of another format (an older lanemap): named, and the map stays.
  fs::copy(tmp_->str("bad/projections/0000"), tmp_->str("bad/projections/0005"));
  auto m = readJson(tmp_->str("bad/projections/0005/projection.json"));
  m["lanemap_projection"] = 0;
  std::ofstream(tmp_->str("bad/projections/0005/projection.json")) << m.dump();
  r = lt::runCommand(city("bad"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("projection format 0, this lanemap reads 1: project the drive again"), std::string::npos) << r.output;
  EXPECT_EQ(readFile(tmp_->str("bad/map/map.osm")), map_before);
  EXPECT_FALSE(fs::exists(tmp_->str("bad/map.partial")));

  // The store's drives fused on another city's OSM: named, and the map stays.
  fs::remove_all(tmp_->str("bad/projections/0005"));
  r = lt::runCommand(lt::binPath("lanemap-city") + " --oracle --no-lidar --osm " + lt::dataPath("osm/monaco.osm.pbf") +
                     " --store " + tmp_->str("bad"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("was projected on another OSM file"), std::string::npos) << r.output;
  EXPECT_EQ(readFile(tmp_->str("bad/map/map.osm")), map_before);

  // No drive and an empty store; a drive that does not exist.
  r = lt::runCommand(city("empty"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no drive"), std::string::npos) << r.output;
  r = lt::runCommand(city("empty") + " " + tmp_->str("nowhere/drive.lcmlog"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no such drive log"), std::string::npos) << r.output;
}
