// lanemap-launch's launch configuration (config/launch/*.yaml; the format is described in
// docs/recording.md and config/launch/car.yaml): hosts, processes with their restart policies, and
// ${...} variables. Every error is a std::runtime_error whose message names the file and, for a
// bad key, the key.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace lanemap::launch {

enum class Restart { kNever, kOnFailure, kAlways };

struct Spec {
  std::string name, host, command, config;
  Restart restart = Restart::kOnFailure;
  double restart_delay_s = 1.0;
  double max_restart_delay_s = 30.0;
  int max_restarts = -1;  // -1: unlimited
  double stop_timeout_s = 5.0;
  double start_delay_s = 0.0;
  // When this process ends for good, stop the whole launch this many seconds later (a log player
  // whose end is the end of the job; like roslaunch's required). < 0: no.
  double stop_launch_after_s = -1.0;
  std::map<std::string, std::string> env;
  std::string resolved;  // the command line run by /bin/sh
};

struct Host {
  std::string name, hostname, address, description;
};

struct Launch {
  std::string name;
  std::string lcm_url;
  std::filesystem::path workdir;
  std::vector<Host> hosts;
  std::vector<Spec> processes;
};

// never (or no), on-failure (or on_failure), always; anything else throws, naming `where`.
Restart parseRestart(const std::string& s, const std::string& where);
const char* toString(Restart r);

// ${name}: a launch variable, else an environment variable; anything else is an error.
std::string substitute(const std::string& text, const std::map<std::string, std::string>& vars,
                       const std::string& where);

// Reads and checks a launch file: unknown keys, undeclared hosts, duplicate names, bad restart
// policies and delays are errors. `overrides` (--set) replace variables of its vars:; ${BIN},
// ${LCM_URL} and ${WORKDIR} are given. A command whose first word names a file in `bin_dir` runs
// from there; `config:` becomes --config. `url_flag` (--lcm-url), when not empty, replaces lcm_url.
Launch loadLaunch(const std::string& path, const std::map<std::string, std::string>& overrides,
                  const std::string& bin_dir, const std::string& url_flag);

// --set NAME=VALUE arguments as a map; throws for one without a NAME or '='.
std::map<std::string, std::string> parseSets(const std::vector<std::string>& sets);

// The hosts whose processes run here: `requested` (--host), else `env_host` ($LANEMAP_HOST) when
// not empty, else the hosts whose name or hostname: is `machine_hostname`; none of them with
// `all_hosts`. Throws when no host matches the machine, or a requested host is not in the file
// (`file` names it in the message).
std::vector<std::string> selectHosts(const Launch& launch, std::vector<std::string> requested, bool all_hosts,
                                     const std::string& env_host, const std::string& machine_hostname,
                                     const std::string& file);
// The processes of those hosts (every process with all_hosts), in file order.
std::vector<Spec> processesOn(const Launch& launch, const std::vector<std::string>& hosts, bool all_hosts);

// lanemap-launch --list: the hosts and their processes.
std::string listing(const Launch& launch);

}  // namespace lanemap::launch
