// lanemap-launch's launch file parser (tools/launch/config.h) on its own: a valid file read to
// the values it holds, every error naming the file and the offending key or value, --set, host
// selection and the --list text. The launcher itself (processes, restarts, signals) is
// tests/deploy/launch_test.cc.
#include "tests/common/sim_drive.h"
#include "tools/launch/config.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace {

using namespace lanemap::launch;
using lanemap::testing::TempDir;
namespace fs = std::filesystem;

std::string write(const TempDir& dir, const std::string& yaml, const std::string& name = "l.yaml") {
  std::ofstream(dir.str(name)) << yaml;
  return dir.str(name);
}

// The message of loadLaunch's exception; "" when the file loads.
std::string errorOf(const std::string& path, const std::map<std::string, std::string>& sets = {}) {
  try {
    loadLaunch(path, sets, "/nonexistent-bin", "");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

const std::string kHosts = "hosts: {a: {}}\n";

TEST(LaunchConfig, AValidFileIsReadToItsValues) {
  TempDir dir("launch-config");
  fs::create_directories(dir.path() / "bin");
  fs::create_directories(dir.path() / "work");
  std::ofstream(dir.str("bin/lanemap-tool")) << "";
  const std::string path = write(dir, R"(
name: mine
lcm_url: udpm://239.255.76.67:7667?ttl=0
workdir: work
vars: {out: /tmp/o, speed: "2"}
defaults: {restart: always, restart_delay_s: 0.5, max_restart_delay_s: 4, max_restarts: 3, stop_timeout_s: 2}
hosts:
  car: {hostname: car-pc, address: 10.0.0.2, description: the car}
  desk: {}
processes:
  - {name: tool, host: car, command: 'lanemap-tool --out ${out}/x --url ${LCM_URL}', config: '${WORKDIR}/c.yaml'}
  - name: other
    host: desk
    command: 'sh -c "sleep ${speed}"'
    restart: no
    restart_delay_s: 1
    max_restart_delay_s: 8
    start_delay_s: 1.5
    stop_launch_after_s: 2
    env: {A: '${out}', B: plain}
)");
  const Launch l = loadLaunch(path, {{"speed", "7"}}, dir.str("bin"), "");
  EXPECT_EQ(l.name, "mine");
  EXPECT_EQ(l.lcm_url, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(l.workdir, fs::weakly_canonical(dir.path() / "work"));
  ASSERT_EQ(l.hosts.size(), 2u);
  EXPECT_EQ(l.hosts[0].name, "car");
  EXPECT_EQ(l.hosts[0].hostname, "car-pc");
  EXPECT_EQ(l.hosts[0].address, "10.0.0.2");
  EXPECT_EQ(l.hosts[0].description, "the car");
  EXPECT_EQ(l.hosts[1].name, "desk");
  EXPECT_EQ(l.hosts[1].hostname, "");
  ASSERT_EQ(l.processes.size(), 2u);
  const Spec& a = l.processes[0];
  EXPECT_EQ(a.host, "car");
  // The defaults: block, a lanemap binary from bin_dir, `config:` as --config, ${...} substituted.
  EXPECT_EQ(a.restart, Restart::kAlways);
  EXPECT_DOUBLE_EQ(a.restart_delay_s, 0.5);
  EXPECT_DOUBLE_EQ(a.max_restart_delay_s, 4.0);
  EXPECT_EQ(a.max_restarts, 3);
  EXPECT_DOUBLE_EQ(a.stop_timeout_s, 2.0);
  EXPECT_DOUBLE_EQ(a.stop_launch_after_s, -1.0);
  EXPECT_EQ(a.resolved, dir.str("bin/lanemap-tool") + " --out /tmp/o/x --url udpm://239.255.76.67:7667?ttl=0 --config " +
                            l.workdir.string() + "/c.yaml");
  const Spec& b = l.processes[1];
  EXPECT_EQ(b.restart, Restart::kNever);
  EXPECT_DOUBLE_EQ(b.restart_delay_s, 1.0);
  EXPECT_DOUBLE_EQ(b.max_restart_delay_s, 8.0);
  EXPECT_EQ(b.max_restarts, 3);
  EXPECT_DOUBLE_EQ(b.start_delay_s, 1.5);
  EXPECT_DOUBLE_EQ(b.stop_launch_after_s, 2.0);
  EXPECT_EQ(b.resolved, "sh -c \"sleep 7\"");  // --set speed=7; sh is not in bin_dir: unchanged
  EXPECT_EQ(b.env, (std::map<std::string, std::string>{{"A", "/tmp/o"}, {"B", "plain"}}));

  // --lcm-url replaces the file's bus (also in ${LCM_URL}); without name: the file's stem.
  const Launch u = loadLaunch(write(dir, "hosts: {a: {}}\nprocesses:\n  - {name: p, host: a, command: 'x ${LCM_URL}'}\n",
                                    "plain.yaml"),
                              {}, dir.str("bin"), "memq://");
  EXPECT_EQ(u.name, "plain");
  EXPECT_EQ(u.lcm_url, "memq://");
  EXPECT_EQ(u.processes.at(0).resolved, "x memq://");
  EXPECT_EQ(u.processes.at(0).restart, Restart::kOnFailure);  // the built-in default
  EXPECT_EQ(u.processes.at(0).max_restarts, -1);
}

TEST(LaunchConfig, TheShippedLaunchFilesLoad) {
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(LANEMAP_SOURCE_DIR) / "config/launch")) {
    if (e.path().extension() != ".yaml") continue;
    ++files;
    SCOPED_TRACE(e.path().string());
    Launch l;
    ASSERT_NO_THROW(l = loadLaunch(e.path().string(), {}, "/nonexistent-bin", ""));
    EXPECT_FALSE(l.hosts.empty());
    EXPECT_FALSE(l.processes.empty());
  }
  EXPECT_GE(files, 3u);  // car, demo, replay
}

TEST(LaunchConfig, AnUnknownKeyIsRefusedNamingFileAndKey) {
  TempDir dir("launch-config-keys");
  const std::string proc = "processes:\n  - {name: p, host: a, command: 'true'}\n";
  std::string path = write(dir, kHosts + proc + "lcm_ur1: memq://\n");
  std::string e = errorOf(path);
  EXPECT_EQ(e, path + ": unknown key 'lcm_ur1'");
  path = write(dir, kHosts + "processes:\n  - {name: p, host: a, command: 'true', retsart: always}\n");
  EXPECT_EQ(errorOf(path), path + ": process p: unknown key 'retsart'");
  path = write(dir, "hosts: {a: {hostnme: x}}\n" + proc);
  EXPECT_EQ(errorOf(path), path + ": host a: unknown key 'hostnme'");
  path = write(dir, kHosts + proc + "defaults: {start_delay_s: 1}\n");  // a per-process key only
  EXPECT_EQ(errorOf(path), path + ": defaults: unknown key 'start_delay_s'");
}

TEST(LaunchConfig, ABadRestartPolicyIsRefused) {
  TempDir dir("launch-config-restart");
  std::string path = write(dir, kHosts + "processes:\n  - {name: p, host: a, command: 'true', restart: sometimes}\n");
  EXPECT_EQ(errorOf(path), path + ": process p: restart 'sometimes' (never, on-failure or always)");
  path = write(dir, kHosts + "defaults: {restart: maybe}\nprocesses:\n  - {name: p, host: a, command: 'true'}\n");
  EXPECT_EQ(errorOf(path), path + ": defaults: restart 'maybe' (never, on-failure or always)");
  EXPECT_EQ(parseRestart("no", "x"), Restart::kNever);
  EXPECT_EQ(parseRestart("on_failure", "x"), Restart::kOnFailure);
  EXPECT_EQ(parseRestart("on-failure", "x"), Restart::kOnFailure);
  EXPECT_EQ(parseRestart("always", "x"), Restart::kAlways);
  EXPECT_STREQ(toString(Restart::kOnFailure), "on-failure");
}

TEST(LaunchConfig, InconsistentFilesAreClearErrors) {
  TempDir dir("launch-config-bad");
  const auto err = [&](const std::string& yaml) { return errorOf(write(dir, yaml)); };
  const std::string p = dir.str("l.yaml");
  EXPECT_EQ(errorOf(dir.str("missing.yaml")), "cannot read launch file '" + dir.str("missing.yaml") + "'");
  EXPECT_EQ(err("processes: []\n"), p + ": no hosts: map");
  EXPECT_EQ(err(kHosts), p + ": no processes: list");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a}\n"), p + ": every process needs name, host and command");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a, command: x}\n  - {name: p, host: a, command: y}\n"),
            p + ": process p: name used twice");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: z, command: x}\n"), p + ": process p: host 'z' is not in hosts:");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a, command: x, restart_delay_s: 5, max_restart_delay_s: 2}\n"),
            p + ": process p: need 0 < restart_delay_s <= max_restart_delay_s and stop_timeout_s > 0");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a, command: x, stop_timeout_s: 0}\n"),
            p + ": process p: need 0 < restart_delay_s <= max_restart_delay_s and stop_timeout_s > 0");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a, command: '  '}\n"), p + ": process p: empty command");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a, command: 'x ${nope_not_set}'}\n"),
            p + ": process p: unknown variable ${nope_not_set} (give it with --set nope_not_set=...)");
  EXPECT_EQ(err(kHosts + "processes:\n  - {name: p, host: a, command: 'x ${open'}\n"),
            p + ": process p: unclosed ${ in 'x ${open'");
  EXPECT_EQ(errorOf(write(dir, kHosts + "processes:\n  - {name: p, host: a, command: x}\n"), {{"nothere", "1"}}),
            p + ": --set nothere: no such variable in vars:");
}

TEST(LaunchConfig, SubstituteTakesLaunchVariablesThenTheEnvironment) {
  setenv("LANEMAP_LAUNCH_CONFIG_TEST_VAR", "from-env", 1);
  EXPECT_EQ(substitute("${a}/${LANEMAP_LAUNCH_CONFIG_TEST_VAR}/$x/${a}", {{"a", "A"}}, "w"), "A/from-env/$x/A");
  setenv("LANEMAP_LAUNCH_CONFIG_TEST_VAR", "shadowed", 1);
  EXPECT_EQ(substitute("${LANEMAP_LAUNCH_CONFIG_TEST_VAR}", {{"LANEMAP_LAUNCH_CONFIG_TEST_VAR", "var"}}, "w"), "var");
  unsetenv("LANEMAP_LAUNCH_CONFIG_TEST_VAR");
}

TEST(LaunchConfig, SetArgumentsAreNameValuePairs) {
  EXPECT_EQ(parseSets({"a=1", "b=x=y", "c="}),
            (std::map<std::string, std::string>{{"a", "1"}, {"b", "x=y"}, {"c", ""}}));
  try {
    parseSets({"a=1", "=2"});
    ADD_FAILURE() << "no error for '=2'";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "--set '=2': expected NAME=VALUE");
  }
  EXPECT_THROW(parseSets({"novalue"}), std::runtime_error);
}

TEST(LaunchConfig, HostSelectionAndListing) {
  TempDir dir("launch-config-hosts");
  const std::string path = write(dir, R"(
name: h
lcm_url: memq://
hosts:
  sensors: {hostname: car-pc, address: 10.0.0.2}
  mapping: {description: the mapper}
processes:
  - {name: cam, host: sensors, command: 'cam', restart: always}
  - {name: map, host: mapping, command: 'map'}
  - {name: gps, host: sensors, command: 'gps'}
)");
  const Launch l = loadLaunch(path, {}, "/nonexistent-bin", "");
  using V = std::vector<std::string>;
  EXPECT_EQ(selectHosts(l, {"mapping"}, false, "sensors", "car-pc", path), V{"mapping"});  // --host first
  EXPECT_EQ(selectHosts(l, {}, false, "mapping", "car-pc", path), V{"mapping"});           // then $LANEMAP_HOST
  EXPECT_EQ(selectHosts(l, {}, false, "", "car-pc", path), V{"sensors"});                  // then hostname:
  EXPECT_EQ(selectHosts(l, {}, false, "", "mapping", path), V{"mapping"});                 // or the host's name
  EXPECT_EQ(selectHosts(l, {}, true, "", "elsewhere", path), V{});                         // --all-hosts
  try {
    selectHosts(l, {}, false, "", "elsewhere", path);
    ADD_FAILURE() << "no error for an unknown machine";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "this machine (hostname 'elsewhere') is none of the hosts: sensors mapping; give --host NAME or --all-hosts");
  }
  try {
    selectHosts(l, {"sensors", "nowhere"}, false, "", "car-pc", path);
    ADD_FAILURE() << "no error for --host nowhere";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "--host nowhere: not a host of " + path);
  }
  const auto names = [](const std::vector<Spec>& v) {
    V out;
    for (const auto& s : v) out.push_back(s.name);
    return out;
  };
  EXPECT_EQ(names(processesOn(l, {"sensors"}, false)), (V{"cam", "gps"}));
  EXPECT_EQ(names(processesOn(l, {}, true)), (V{"cam", "map", "gps"}));
  EXPECT_EQ(names(processesOn(l, {}, false)), V{});
  EXPECT_EQ(listing(l), "h: lcm_url memq://, workdir " + fs::current_path().string() +
                            "\nsensors (hostname car-pc) 10.0.0.2\n  cam [restart always]: cam\n  gps [restart on-failure]: gps\n"
                            "mapping: the mapper\n  map [restart on-failure]: map\n");
}

}  // namespace
