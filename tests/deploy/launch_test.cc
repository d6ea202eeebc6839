// lanemap-launch (tools/launch.cc, tools/launch/): host selection, command resolution, restart policies with
// back-off and max_restarts, stopping everything on SIGTERM (SIGKILL for a process that ignores
// it), and clear errors for bad launch files. Children are plain shell commands that leave traces
// in files, so no network is involved.
#include "tests/common/child_process.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <fstream>
#include <sstream>

namespace {

using namespace lanemap::testing;
using namespace std::chrono_literals;

std::string launchBin() { return binPath("lanemap-launch"); }

int lines(const std::string& path) {
  const std::string s = readFile(path);
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

bool alive(pid_t pid) { return pid > 0 && kill(pid, 0) == 0; }

TEST(Launch, CarConfigurationPlacesDriversMappingAndRecordingOnTheirHosts) {
  const auto r = runCommand(launchBin() + " " + LANEMAP_SOURCE_DIR + "/config/launch/car.yaml --list");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Per host, the processes under it, commands resolved to build/bin, configs appended.
  const auto sensors = r.output.find("\nsensors"), segmenter = r.output.find("\nsegmenter"),
             mapping = r.output.find("\nmapping");
  ASSERT_NE(sensors, std::string::npos) << r.output;
  ASSERT_NE(mapping, std::string::npos) << r.output;
  const auto camera = r.output.find(binPath("lanemap-camera-v4l2") + " --config config/camera_v4l2.yaml");
  const auto seg = r.output.find(binPath("lanemap-segmenter") + " --config config/segmenter.yaml");
  const auto tracker = r.output.find(binPath("lanemap-road-tracker") + " --osm data/osm/west-oakland.osm --config config/road_tracker.yaml");
  const auto bev = r.output.find(binPath("lanemap-bev-builder") + " --osm data/osm/west-oakland.osm --store map-store");
  const auto lanes = r.output.find(binPath("lanemap-lane-mapper") + " --osm data/osm/west-oakland.osm --store map-store");
  ASSERT_NE(camera, std::string::npos) << r.output;
  ASSERT_NE(seg, std::string::npos) << r.output;
  ASSERT_NE(tracker, std::string::npos) << r.output;
  ASSERT_NE(bev, std::string::npos) << r.output;
  ASSERT_NE(lanes, std::string::npos) << r.output;
  EXPECT_TRUE(camera > sensors && camera < segmenter) << r.output;
  EXPECT_TRUE(seg > segmenter && seg < mapping) << r.output;
  EXPECT_TRUE(tracker > mapping && bev > mapping && lanes > mapping) << r.output;
  EXPECT_NE(r.output.find("lcm_url udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608"), std::string::npos);
  // The binaries it names exist (the ones built today).
  for (const char* b : {"lanemap-camera-v4l2", "lanemap-lidar-vlp16", "lanemap-pose-nmea", "lanemap-segmenter",
                        "lanemap-road-tracker", "lanemap-bev-builder", "lanemap-lane-mapper"}) {
    EXPECT_TRUE(std::filesystem::exists(binPath(b))) << b;
  }
  const auto dry = runCommand(launchBin() + " " + LANEMAP_SOURCE_DIR + "/config/launch/car.yaml --host mapping --dry-run");
  ASSERT_EQ(dry.exit_code, 0) << dry.output;
  EXPECT_EQ(std::count(dry.output.begin(), dry.output.end(), '\n'), 3) << dry.output;
  EXPECT_EQ(dry.output.rfind("mapping/road_tracker: " + binPath("lanemap-road-tracker") +
                                 " --osm data/osm/west-oakland.osm --config config/road_tracker.yaml\n", 0), 0u)
      << dry.output;
  // LANEMAP_HOST picks the host when --host is not given.
  const auto env = runCommand("LANEMAP_HOST=sensors " + launchBin() + " " + LANEMAP_SOURCE_DIR +
                              "/config/launch/car.yaml --dry-run");
  EXPECT_EQ(std::count(env.output.begin(), env.output.end(), '\n'), 4) << env.output;
}

TEST(Launch, RestartPoliciesBackOffAndGiveUp) {
  TempDir dir("launch");
  std::ofstream(dir.str("l.yaml")) << "name: t\nlcm_url: memq://\nvars: {out: x}\n"
                                      "hosts: {a: {}, b: {}}\n"
                                      "processes:\n"
                                      "  - {name: fails, host: a, command: 'echo run >> ${out}/fails; exit 3', "
                                      "restart: on-failure, restart_delay_s: 0.1, max_restart_delay_s: 0.2, max_restarts: 3}\n"
                                      "  - {name: once, host: a, command: 'echo $LCM_DEFAULT_URL >> ${out}/once', restart: never}\n"
                                      "  - {name: ok, host: a, command: 'echo run >> ${out}/ok', restart: on-failure}\n"
                                      "  - {name: other, host: b, command: 'echo run >> ${out}/other'}\n";
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = runCommand(launchBin() + " " + dir.str("l.yaml") + " --host a --set out=" + dir.str() + " --status-interval 0");
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 1) << r.output;  // one process failed for good
  EXPECT_EQ(lines(dir.str("fails")), 4) << r.output;  // first run + max_restarts 3
  EXPECT_EQ(readFile(dir.str("once")), "memq://\n");  // the launch file's bus, through the environment
  EXPECT_EQ(lines(dir.str("ok")), 1);                 // exit 0 with on-failure: not restarted
  EXPECT_FALSE(std::filesystem::exists(dir.str("other")));  // another host's process
  // Back-off 0.1, 0.2, 0.2 s between the four runs.
  EXPECT_GE(secs, 0.45);
  EXPECT_LT(secs, 5.0);
  EXPECT_NE(r.output.find("restart 1 in 0.1 s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("restart 2 in 0.2 s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("max_restarts reached"), std::string::npos) << r.output;

  // restart: always restarts a process that exits cleanly too.
  std::ofstream(dir.str("always.yaml")) << "hosts: {a: {}}\nprocesses:\n"
                                           "  - {name: loop, host: a, command: 'echo run >> " + dir.str("always") +
                                               "', restart: always, restart_delay_s: 0.05, max_restarts: 2}\n";
  const auto a = runCommand(launchBin() + " " + dir.str("always.yaml") + " --all-hosts --status-interval 0");
  EXPECT_EQ(lines(dir.str("always")), 3) << a.output;
}

TEST(Launch, AProcessWhoseStoreIsHeldElsewhereIsNotRestarted) {
  // Exit 4 (core/io/store_lock.h kExitStoreInUse): another BEV builder or lane mapper holds the store.
  TempDir dir("launch-held");
  std::ofstream(dir.str("l.yaml")) << "hosts: {a: {}}\nprocesses:\n"
                                      "  - {name: held, host: a, command: 'echo run >> " + dir.str("held") +
                                          "; exit 4', restart: on-failure, restart_delay_s: 0.05}\n";
  const auto r = runCommand(launchBin() + " " + dir.str("l.yaml") + " --all-hosts --status-interval 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(lines(dir.str("held")), 1) << r.output;
  EXPECT_NE(r.output.find("its map store is held by another process: not restarted"), std::string::npos) << r.output;
}

TEST(Launch, SigtermStopsEveryProcessAndKillsOneThatIgnoresIt) {
  TempDir dir("launch-stop");
  std::ofstream(dir.str("l.yaml")) << "hosts: {a: {}}\nprocesses:\n"
                                      "  - {name: sleeper, host: a, command: 'echo $$ > " + dir.str("p1") + "; exec sleep 100'}\n"
                                      "  - {name: stubborn, host: a, stop_timeout_s: 0.5, command: \"trap '' TERM; echo $$ > " +
                                          dir.str("p2") + "; while true; do sleep 0.05; done\"}\n";
  ChildProcess launch({launchBin(), dir.str("l.yaml"), "--host", "a", "--status-interval", "0.2"});
  ASSERT_TRUE(launch.started());
  pid_t p1 = 0, p2 = 0;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while ((p1 == 0 || p2 == 0) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
    p1 = std::atoi(readFile(dir.str("p1")).c_str());
    p2 = std::atoi(readFile(dir.str("p2")).c_str());
  }
  ASSERT_TRUE(alive(p1) && alive(p2));
  std::this_thread::sleep_for(300ms);  // a status table or two
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(launch.stop(), 0);  // SIGTERM
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(secs, 0.45);  // waited stop_timeout_s for the stubborn one ...
  EXPECT_LT(secs, 3.0);   // ... then killed it
  std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(alive(p1));
  EXPECT_FALSE(alive(p2));
}

TEST(Launch, BadFilesAndHostsAreClearErrors) {
  TempDir dir("launch-bad");
  auto run = [&](const std::string& yaml, const std::string& args = "--host a") {
    std::ofstream(dir.str("b.yaml")) << yaml;
    return runCommand(launchBin() + " " + dir.str("b.yaml") + " " + args);
  };
  const std::string ok = "hosts: {a: {}}\nprocesses:\n  - {name: p, host: a, command: 'true'}\n";
  auto r = run(ok, "--host nowhere");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--host nowhere: not a host"), std::string::npos) << r.output;
  r = run("hosts: {a: {}}\nprocesses:\n  - {name: p, host: z, command: 'true'}\n");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("host 'z' is not in hosts"), std::string::npos) << r.output;
  r = run("hosts: {a: {}}\nprocesses:\n  - {name: p, host: a, command: 'x ${nope_not_set}'}\n");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("unknown variable ${nope_not_set}"), std::string::npos) << r.output;
  r = run("hosts: {a: {}}\nprocesses:\n  - {name: p, host: a, command: 'true', restart: sometimes}\n");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("restart 'sometimes'"), std::string::npos) << r.output;
  r = run("hosts: {a: {}}\nprocesses:\n  - {name: p, host: a, command: 'true', retsart: always}\n");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("unknown key 'retsart'"), std::string::npos) << r.output;
  r = run(ok, "--host a --set nothere=1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--set nothere"), std::string::npos) << r.output;
  r = runCommand("LANEMAP_HOST= " + launchBin() + " " + dir.str("b.yaml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("is none of the hosts: a"), std::string::npos) << r.output;
}

}  // namespace
