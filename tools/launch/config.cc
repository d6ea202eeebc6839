// lanemap-launch's launch configuration (see config.h).
#include "tools/launch/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <sstream>
#include <stdexcept>

namespace lanemap::launch {

namespace fs = std::filesystem;

Restart parseRestart(const std::string& s, const std::string& where) {
  if (s == "never" || s == "no") return Restart::kNever;
  if (s == "on-failure" || s == "on_failure") return Restart::kOnFailure;
  if (s == "always") return Restart::kAlways;
  throw std::runtime_error(where + ": restart '" + s + "' (never, on-failure or always)");
}

const char* toString(Restart r) {
  return r == Restart::kNever ? "never" : r == Restart::kAlways ? "always" : "on-failure";
}

// ${name}: a launch variable, else an environment variable; anything else is an error.
std::string substitute(const std::string& text, const std::map<std::string, std::string>& vars,
                       const std::string& where) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '$' && i + 1 < text.size() && text[i + 1] == '{') {
      const std::size_t end = text.find('}', i + 2);
      if (end == std::string::npos) throw std::runtime_error(where + ": unclosed ${ in '" + text + "'");
      const std::string key = text.substr(i + 2, end - i - 2);
      if (auto it = vars.find(key); it != vars.end()) {
        out += it->second;
      } else if (const char* env = std::getenv(key.c_str())) {
        out += env;
      } else {
        throw std::runtime_error(where + ": unknown variable ${" + key + "} (give it with --set " + key + "=...)");
      }
      i = end;
    } else {
      out += text[i];
    }
  }
  return out;
}

namespace {

void checkKeys(const YAML::Node& node, const std::set<std::string>& keys, const std::string& where) {
  for (const auto& kv : node) {
    const auto key = kv.first.as<std::string>();
    if (!keys.count(key)) throw std::runtime_error(where + ": unknown key '" + key + "'");
  }
}

}  // namespace

Launch loadLaunch(const std::string& path, const std::map<std::string, std::string>& overrides,
                  const std::string& bin_dir, const std::string& url_flag) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error("cannot read launch file '" + path + "'");
  }
  checkKeys(root, {"name", "lcm_url", "workdir", "vars", "defaults", "hosts", "processes"}, path);
  Launch l;
  l.name = root["name"] ? root["name"].as<std::string>() : fs::path(path).stem().string();
  l.lcm_url = url_flag.empty() ? (root["lcm_url"] ? root["lcm_url"].as<std::string>() : "") : url_flag;
  const fs::path dir = fs::absolute(path).parent_path();
  l.workdir = root["workdir"] ? fs::weakly_canonical(dir / root["workdir"].as<std::string>()) : fs::current_path();

  std::map<std::string, std::string> vars;
  if (root["vars"]) {
    for (const auto& kv : root["vars"]) vars[kv.first.as<std::string>()] = kv.second.as<std::string>();
  }
  for (const auto& [k, v] : overrides) {
    if (!vars.count(k)) throw std::runtime_error(path + ": --set " + k + ": no such variable in vars:");
    vars[k] = v;
  }
  vars["BIN"] = bin_dir;
  vars["LCM_URL"] = l.lcm_url;
  vars["WORKDIR"] = l.workdir.string();

  if (!root["hosts"] || !root["hosts"].IsMap()) throw std::runtime_error(path + ": no hosts: map");
  for (const auto& kv : root["hosts"]) {
    Host h;
    h.name = kv.first.as<std::string>();
    const YAML::Node n = kv.second;
    if (n && n.IsMap()) {
      checkKeys(n, {"hostname", "address", "description"}, path + ": host " + h.name);
      if (n["hostname"]) h.hostname = n["hostname"].as<std::string>();
      if (n["address"]) h.address = n["address"].as<std::string>();
      if (n["description"]) h.description = n["description"].as<std::string>();
    }
    l.hosts.push_back(h);
  }
  Spec defaults;
  if (root["defaults"]) {
    const YAML::Node d = root["defaults"];
    checkKeys(d, {"restart", "restart_delay_s", "max_restart_delay_s", "max_restarts", "stop_timeout_s"},
              path + ": defaults");
    if (d["restart"]) defaults.restart = parseRestart(d["restart"].as<std::string>(), path + ": defaults");
    if (d["restart_delay_s"]) defaults.restart_delay_s = d["restart_delay_s"].as<double>();
    if (d["max_restart_delay_s"]) defaults.max_restart_delay_s = d["max_restart_delay_s"].as<double>();
    if (d["max_restarts"]) defaults.max_restarts = d["max_restarts"].as<int>();
    if (d["stop_timeout_s"]) defaults.stop_timeout_s = d["stop_timeout_s"].as<double>();
  }
  std::set<std::string> names;
  if (!root["processes"] || !root["processes"].IsSequence()) throw std::runtime_error(path + ": no processes: list");
  for (const auto& n : root["processes"]) {
    Spec s = defaults;
    if (!n["name"] || !n["host"] || !n["command"]) {
      throw std::runtime_error(path + ": every process needs name, host and command");
    }
    s.name = n["name"].as<std::string>();
    const std::string where = path + ": process " + s.name;
    checkKeys(n, {"name", "host", "command", "config", "restart", "restart_delay_s", "max_restart_delay_s",
                  "max_restarts", "stop_timeout_s", "start_delay_s", "stop_launch_after_s", "env"},
              where);
    if (!names.insert(s.name).second) throw std::runtime_error(where + ": name used twice");
    s.host = n["host"].as<std::string>();
    if (std::none_of(l.hosts.begin(), l.hosts.end(), [&](const Host& h) { return h.name == s.host; })) {
      throw std::runtime_error(where + ": host '" + s.host + "' is not in hosts:");
    }
    s.command = n["command"].as<std::string>();
    if (n["config"]) s.config = n["config"].as<std::string>();
    if (n["restart"]) s.restart = parseRestart(n["restart"].as<std::string>(), where);
    if (n["restart_delay_s"]) s.restart_delay_s = n["restart_delay_s"].as<double>();
    if (n["max_restart_delay_s"]) s.max_restart_delay_s = n["max_restart_delay_s"].as<double>();
    if (n["max_restarts"]) s.max_restarts = n["max_restarts"].as<int>();
    if (n["stop_timeout_s"]) s.stop_timeout_s = n["stop_timeout_s"].as<double>();
    if (n["start_delay_s"]) s.start_delay_s = n["start_delay_s"].as<double>();
    if (n["stop_launch_after_s"]) s.stop_launch_after_s = n["stop_launch_after_s"].as<double>();
    if (n["env"]) {
      for (const auto& kv : n["env"]) s.env[kv.first.as<std::string>()] = substitute(kv.second.as<std::string>(), vars, where);
    }
    if (!(s.restart_delay_s > 0) || !(s.max_restart_delay_s >= s.restart_delay_s) || !(s.stop_timeout_s > 0)) {
      throw std::runtime_error(where + ": need 0 < restart_delay_s <= max_restart_delay_s and stop_timeout_s > 0");
    }
    // The command: variables substituted; a first word without '/' that names a lanemap binary
    // runs from the build's bin folder; `config:` becomes --config.
    std::string cmd = substitute(s.command, vars, where);
    const std::size_t start = cmd.find_first_not_of(" \t");
    if (start == std::string::npos) throw std::runtime_error(where + ": empty command");
    const std::size_t end = cmd.find_first_of(" \t", start);
    const std::string first = cmd.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (first.find('/') == std::string::npos && fs::exists(fs::path(bin_dir) / first)) {
      cmd = (fs::path(bin_dir) / first).string() + (end == std::string::npos ? "" : cmd.substr(end));
    }
    if (!s.config.empty()) cmd += " --config " + substitute(s.config, vars, where);
    s.resolved = cmd;
    l.processes.push_back(s);
  }
  return l;
}

std::map<std::string, std::string> parseSets(const std::vector<std::string>& sets) {
  std::map<std::string, std::string> overrides;
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) throw std::runtime_error("--set '" + s + "': expected NAME=VALUE");
    overrides[s.substr(0, eq)] = s.substr(eq + 1);
  }
  return overrides;
}

std::vector<std::string> selectHosts(const Launch& launch, std::vector<std::string> hosts, bool all_hosts,
                                     const std::string& env_host, const std::string& machine_hostname,
                                     const std::string& file) {
  if (!all_hosts && hosts.empty()) {
    if (!env_host.empty()) {
      hosts.push_back(env_host);
    } else {
      for (const auto& h : launch.hosts) {
        if (h.name == machine_hostname || h.hostname == machine_hostname) hosts.push_back(h.name);
      }
      if (hosts.empty()) {
        std::string names;
        for (const auto& h : launch.hosts) names += " " + h.name;
        throw std::runtime_error(std::string("this machine (hostname '") + machine_hostname + "') is none of the hosts:" + names +
                                 "; give --host NAME or --all-hosts");
      }
    }
  }
  for (const auto& h : hosts) {
    if (std::none_of(launch.hosts.begin(), launch.hosts.end(), [&](const Host& x) { return x.name == h; })) {
      throw std::runtime_error("--host " + h + ": not a host of " + file);
    }
  }
  return hosts;
}

std::vector<Spec> processesOn(const Launch& launch, const std::vector<std::string>& hosts, bool all_hosts) {
  std::vector<Spec> mine;
  for (const auto& p : launch.processes) {
    if (all_hosts || std::find(hosts.begin(), hosts.end(), p.host) != hosts.end()) mine.push_back(p);
  }
  return mine;
}

std::string listing(const Launch& launch) {
  std::ostringstream out;
  out << launch.name << ": lcm_url " << launch.lcm_url << ", workdir " << launch.workdir.string() << "\n";
  for (const auto& h : launch.hosts) {
    out << h.name << (h.hostname.empty() ? "" : " (hostname " + h.hostname + ")")
        << (h.address.empty() ? "" : " " + h.address) << (h.description.empty() ? "" : ": " + h.description)
        << "\n";
    for (const auto& p : launch.processes) {
      if (p.host == h.name) out << "  " << p.name << " [restart " << toString(p.restart) << "]: " << p.resolved << "\n";
    }
  }
  return out.str();
}

}  // namespace lanemap::launch
