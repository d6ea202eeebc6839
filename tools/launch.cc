// lanemap-launch: starts the processes of one host of a launch configuration (config/launch/*.yaml),
// like libbot2's procman deputy: each process in its own process group, restarted per its policy
// (never / on-failure / always, with a doubling back-off), all stopped on SIGINT/SIGTERM (SIGTERM,
// then SIGKILL after stop_timeout_s), a status table printed every few seconds and a line on every
// start and exit. Every child gets LCM_DEFAULT_URL = the configuration's lcm_url, so lanemap
// processes, lcm-logger and lcm-logplayer all join the same bus.
//
//   lanemap-launch config/launch/car.yaml --host sensors
//   lanemap-launch config/launch/replay.yaml --host mapping --host viewer --set drive=/data/d1
//   lanemap-launch config/launch/car.yaml --list            # hosts and processes, then exit
//
// Without --host: $LANEMAP_HOST, else the machine's hostname matched against the hosts' names and
// their `hostname:` keys. The launcher exits when none of its processes runs or will restart:
// 0 if every process ended with status 0, else 1 (and 0 after a SIGINT/SIGTERM stop).
// The file format is described in docs/recording.md and config/launch/car.yaml.
#include "processes/framework/share_dir.h"
#include "tools/launch/config.h"
#include "tools/launch/supervisor.h"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>

using namespace lanemap::launch;

int main(int argc, char** argv) {
  CLI::App app("lanemap-launch: start the processes of one host of a launch configuration (procman-like)");
  std::string file, url_flag, log_dir;
  std::vector<std::string> hosts, sets;
  bool all_hosts = false, list = false, dry_run = false;
  double status_interval = 10.0;
  app.add_option("launch_file", file, "launch configuration (config/launch/*.yaml)")->required();
  app.add_option("--host", hosts, "host(s) whose processes to run (default: $LANEMAP_HOST, then the hostname)");
  app.add_flag("--all-hosts", all_hosts, "run every process on this machine (one-machine setup)");
  app.add_option("--set", sets, "NAME=VALUE for a variable of the file's vars: (repeatable)");
  app.add_option("--lcm-url", url_flag, "override the file's lcm_url");
  app.add_option("--log-dir", log_dir, "write each process's output to DIR/<name>.log instead of the terminal");
  app.add_option("--status-interval", status_interval, "seconds between status tables (0: only at the end)");
  app.add_flag("--list", list, "print the hosts and their processes, then exit");
  app.add_flag("--dry-run", dry_run, "print what would run on the selected host(s), then exit");
  CLI11_PARSE(app, argc, argv);

  try {
    const auto overrides = parseSets(sets);
    file = lanemap::resolveShippedFile(file);  // config/launch/X.yaml from an installation too
    const std::filesystem::path bin = lanemap::executableDir();
    Launch launch = loadLaunch(file, overrides, bin.empty() ? "." : bin.string(), url_flag);
    if (list) {
      std::cout << listing(launch);
      return 0;
    }
    const char* env = std::getenv("LANEMAP_HOST");
    char hostname[256] = {0};
    gethostname(hostname, sizeof(hostname) - 1);
    hosts = selectHosts(launch, hosts, all_hosts, env ? env : "", hostname, file);
    std::vector<Spec> mine = processesOn(launch, hosts, all_hosts);
    if (dry_run) {
      for (const auto& p : mine) std::cout << p.host << "/" << p.name << ": " << p.resolved << "\n";
      return 0;
    }
    if (mine.empty()) throw std::runtime_error("no process runs on the selected host(s)");
    if (!log_dir.empty()) std::filesystem::create_directories(log_dir);
    stopOnSignals();
    return supervise(std::move(launch), std::move(mine), log_dir, status_interval);
  } catch (const std::exception& e) {
    std::cerr << "lanemap-launch: " << e.what() << "\n";
    return 2;
  }
}
