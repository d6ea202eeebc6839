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
#include "core/io/store_lock.h"
#include "processes/framework/share_dir.h"

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop.store(true); }

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
  fs::path workdir;
  std::vector<Host> hosts;
  std::vector<Spec> processes;
};

std::string timestamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%H:%M:%S", std::localtime(&t));
  return buf;
}

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

void checkKeys(const YAML::Node& node, const std::set<std::string>& keys, const std::string& where) {
  for (const auto& kv : node) {
    const auto key = kv.first.as<std::string>();
    if (!keys.count(key)) throw std::runtime_error(where + ": unknown key '" + key + "'");
  }
}

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

struct Proc {
  Spec spec;
  pid_t pid = -1;
  int starts = 0;
  int restarts = 0;
  int last_status = 0;  // exit code, or -signal
  bool done = false;    // ended and will not restart
  Clock::time_point started, next_start;
  double next_delay_s = 0;
  bool failed_for_good = false;
};


class Launcher {
 public:
  Launcher(Launch launch, std::vector<Spec> mine, std::string log_dir, double status_interval_s)
      : launch_(std::move(launch)), log_dir_(std::move(log_dir)), status_interval_s_(status_interval_s) {
    const auto now = Clock::now();
    for (auto& s : mine) {
      Proc p;
      p.next_delay_s = s.restart_delay_s;
      p.next_start = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s.start_delay_s));
      p.spec = std::move(s);
      procs_.push_back(std::move(p));
    }
  }

  int run() {
    auto next_status = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(status_interval_s_));
    while (!g_stop.load()) {
      reap();
      const auto now = Clock::now();
      bool active = false;
      for (auto& p : procs_) {
        if (p.pid < 0 && !p.done && now >= p.next_start) spawn(p);
        if (!p.done) active = true;
        if (p.done && p.spec.stop_launch_after_s >= 0 && !stop_at_) {
          stop_at_ = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(p.spec.stop_launch_after_s));
          log(p.spec.name + " ended: stopping the launch in " + std::to_string(p.spec.stop_launch_after_s) + " s");
        }
      }
      if (!active) break;
      if (stop_at_ && now >= *stop_at_) {
        stopAll();
        printStatus();
        log("stopped after " + std::string("the end of a process with stop_launch_after_s"));
        return 0;
      }
      if (status_interval_s_ > 0 && now >= next_status) {
        printStatus();
        next_status = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(status_interval_s_));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (g_stop.load()) {
      log("stopping (signal)");
      stopAll();
      printStatus();
      return 0;
    }
    printStatus();
    const bool all_ok = std::all_of(procs_.begin(), procs_.end(), [](const Proc& p) { return p.last_status == 0; });
    log(all_ok ? "all processes ended" : "all processes ended, some failed");
    return all_ok ? 0 : 1;
  }

 private:
  void log(const std::string& msg) const {
    std::cout << "[launch " << timestamp() << "] " << msg << std::endl;
  }

  void spawn(Proc& p) {
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid < 0) {
      log(p.spec.name + ": fork failed: " + std::strerror(errno));
      scheduleRestart(p, -1);
      return;
    }
    if (pid == 0) {
      setpgid(0, 0);                   // its own process group: stopped as a whole, no terminal ^C
      prctl(PR_SET_PDEATHSIG, SIGTERM);  // a killed launcher takes its processes along
      sigset_t none;
      sigemptyset(&none);
      sigprocmask(SIG_SETMASK, &none, nullptr);
      signal(SIGINT, SIG_DFL);
      signal(SIGTERM, SIG_DFL);
      if (chdir(launch_.workdir.c_str()) != 0) _exit(126);
      if (!launch_.lcm_url.empty()) setenv("LCM_DEFAULT_URL", launch_.lcm_url.c_str(), 1);
      setenv("LANEMAP_PROCESS", p.spec.name.c_str(), 1);
      for (const auto& [k, v] : p.spec.env) setenv(k.c_str(), v.c_str(), 1);
      if (!log_dir_.empty()) {
        const std::string file = log_dir_ + "/" + p.spec.name + ".log";
        const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
        if (fd >= 0) {
          dup2(fd, 1);
          dup2(fd, 2);
        }
      }
      // A simple command replaces the shell (the pid is the process's); a compound one keeps it.
      const bool compound = p.spec.resolved.find_first_of(";&|\n") != std::string::npos;
      const std::string cmd = (compound ? "" : "exec ") + p.spec.resolved;
      execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    setpgid(pid, pid);  // also here: no race with a kill before the child ran setpgid
    p.pid = pid;
    p.started = Clock::now();
    ++p.starts;
    log(p.spec.host + "/" + p.spec.name + ": started, pid " + std::to_string(pid) + ": " + p.spec.resolved);
  }

  void scheduleRestart(Proc& p, int status) {
    p.pid = -1;
    p.last_status = status;
    const double ran_s = std::chrono::duration<double>(Clock::now() - p.started).count();
    const bool failed = status != 0;
    // Exit 4: another process holds its map store (core/io/store_lock.h): a restart would fail the same way.
    const bool store_in_use = status == lanemap::io::kExitStoreInUse;
    const bool restart = !store_in_use && (p.spec.restart == Restart::kAlways || (p.spec.restart == Restart::kOnFailure && failed));
    const std::string how = status >= 0 ? "exited with status " + std::to_string(status)
                                        : std::string("killed by signal ") + strsignal(-status);
    if (!restart) {
      p.done = true;
      if (store_in_use) p.failed_for_good = true;
      log(p.spec.host + "/" + p.spec.name + ": " + how + " after " + fixed(ran_s) + " s (" +
          (store_in_use ? std::string("its map store is held by another process: not restarted")
                        : "restart: " + std::string(toString(p.spec.restart))) + ")");
      return;
    }
    if (p.spec.max_restarts >= 0 && p.restarts >= p.spec.max_restarts) {
      p.done = true;
      p.failed_for_good = true;
      log(p.spec.host + "/" + p.spec.name + ": " + how + "; " + std::to_string(p.restarts) +
          " restarts done, max_restarts reached: giving up");
      return;
    }
    // A process that ran for a while starts its back-off afresh.
    if (ran_s > 10.0 * p.spec.max_restart_delay_s || ran_s > 60.0) p.next_delay_s = p.spec.restart_delay_s;
    const double delay = p.next_delay_s;
    p.next_delay_s = std::min(p.next_delay_s * 2.0, p.spec.max_restart_delay_s);
    ++p.restarts;
    p.next_start = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(delay));
    log(p.spec.host + "/" + p.spec.name + ": " + how + " after " + fixed(ran_s) + " s; restart " +
        std::to_string(p.restarts) + " in " + fixed(delay) + " s");
  }

  static std::string fixed(double x) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.1f", x);
    return buf;
  }

  static int statusOf(int wstatus) {
    return WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : WIFSIGNALED(wstatus) ? -WTERMSIG(wstatus) : -1;
  }

  void reap() {
    for (auto& p : procs_) {
      if (p.pid <= 0) continue;
      int ws = 0;
      if (waitpid(p.pid, &ws, WNOHANG) == p.pid) scheduleRestart(p, statusOf(ws));
    }
  }

  void stopAll() {
    const auto t0 = Clock::now();
    for (auto& p : procs_) {
      if (p.pid > 0) kill(-p.pid, SIGTERM);
    }
    while (true) {
      bool running = false;
      const double waited = std::chrono::duration<double>(Clock::now() - t0).count();
      for (auto& p : procs_) {
        if (p.pid <= 0) continue;
        int ws = 0;
        if (waitpid(p.pid, &ws, WNOHANG) == p.pid) {
          p.last_status = statusOf(ws);
          log(p.spec.host + "/" + p.spec.name + ": stopped (" +
              (p.last_status >= 0 ? "status " + std::to_string(p.last_status)
                                  : std::string("signal ") + strsignal(-p.last_status)) + ")");
          kill(-p.pid, SIGKILL);  // anything it left behind in its group
          p.pid = -1;
          p.done = true;
          continue;
        }
        if (waited > p.spec.stop_timeout_s) {
          log(p.spec.host + "/" + p.spec.name + ": no exit " + fixed(p.spec.stop_timeout_s) + " s after SIGTERM: SIGKILL");
          kill(-p.pid, SIGKILL);
        }
        running = true;
      }
      if (!running) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (auto& p : procs_) p.done = true;
  }

  void printStatus() const {
    std::ostringstream out;
    out << "[launch " << timestamp() << "] " << launch_.name << ": " << procs_.size() << " process(es)\n";
    char line[512];
    std::snprintf(line, sizeof(line), "  %-10s %-18s %-8s %-22s %8s %6s\n", "HOST", "NAME", "PID", "STATE", "UPTIME",
                  "RESTARTS");
    out << line;
    const auto now = Clock::now();
    for (const auto& p : procs_) {
      std::string state;
      double up = 0;
      if (p.pid > 0) {
        state = "running";
        up = std::chrono::duration<double>(now - p.started).count();
      } else if (p.done) {
        state = p.last_status >= 0 ? "ended (" + std::to_string(p.last_status) + ")"
                                   : "ended (signal " + std::to_string(-p.last_status) + ")";
        if (p.failed_for_good) state = "failed (" + std::to_string(p.last_status) + ")";
      } else {
        state = p.starts == 0 ? "waiting to start" : "restarting";
      }
      std::snprintf(line, sizeof(line), "  %-10s %-18s %-8s %-22s %8.1f %6d\n", p.spec.host.c_str(),
                    p.spec.name.c_str(), p.pid > 0 ? std::to_string(p.pid).c_str() : "-", state.c_str(), up,
                    p.restarts);
      out << line;
    }
    std::cout << out.str() << std::flush;
  }

  Launch launch_;
  std::string log_dir_;
  double status_interval_s_;
  std::vector<Proc> procs_;
  std::optional<Clock::time_point> stop_at_;
};

std::string binDir() {
  const fs::path dir = lanemap::executableDir();
  return dir.empty() ? "." : dir.string();
}

}  // namespace

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
    std::map<std::string, std::string> overrides;
    for (const auto& s : sets) {
      const auto eq = s.find('=');
      if (eq == std::string::npos || eq == 0) throw std::runtime_error("--set '" + s + "': expected NAME=VALUE");
      overrides[s.substr(0, eq)] = s.substr(eq + 1);
    }
    file = lanemap::resolveShippedFile(file);  // config/launch/X.yaml from an installation too
    Launch launch = loadLaunch(file, overrides, binDir(), url_flag);
    if (list) {
      std::cout << launch.name << ": lcm_url " << launch.lcm_url << ", workdir " << launch.workdir.string() << "\n";
      for (const auto& h : launch.hosts) {
        std::cout << h.name << (h.hostname.empty() ? "" : " (hostname " + h.hostname + ")")
                  << (h.address.empty() ? "" : " " + h.address) << (h.description.empty() ? "" : ": " + h.description)
                  << "\n";
        for (const auto& p : launch.processes) {
          if (p.host == h.name) std::cout << "  " << p.name << " [restart " << toString(p.restart) << "]: " << p.resolved << "\n";
        }
      }
      return 0;
    }
    if (!all_hosts && hosts.empty()) {
      if (const char* env = std::getenv("LANEMAP_HOST"); env && *env) {
        hosts.push_back(env);
      } else {
        char buf[256] = {0};
        gethostname(buf, sizeof(buf) - 1);
        for (const auto& h : launch.hosts) {
          if (h.name == buf || h.hostname == buf) hosts.push_back(h.name);
        }
        if (hosts.empty()) {
          std::string names;
          for (const auto& h : launch.hosts) names += " " + h.name;
          throw std::runtime_error(std::string("this machine (hostname '") + buf + "') is none of the hosts:" + names +
                                   "; give --host NAME or --all-hosts");
        }
      }
    }
    for (const auto& h : hosts) {
      if (std::none_of(launch.hosts.begin(), launch.hosts.end(), [&](const Host& x) { return x.name == h; })) {
        throw std::runtime_error("--host " + h + ": not a host of " + file);
      }
    }
    std::vector<Spec> mine;
    for (const auto& p : launch.processes) {
      if (all_hosts || std::find(hosts.begin(), hosts.end(), p.host) != hosts.end()) mine.push_back(p);
    }
    if (dry_run) {
      for (const auto& p : mine) std::cout << p.host << "/" << p.name << ": " << p.resolved << "\n";
      return 0;
    }
    if (mine.empty()) throw std::runtime_error("no process runs on the selected host(s)");
    if (!log_dir.empty()) fs::create_directories(log_dir);

    struct sigaction sa {};
    sa.sa_handler = onSignal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    sigaction(SIGHUP, &sa, nullptr);
    Launcher launcher(std::move(launch), std::move(mine), log_dir, status_interval);
    return launcher.run();
  } catch (const std::exception& e) {
    std::cerr << "lanemap-launch: " << e.what() << "\n";
    return 2;
  }
}
