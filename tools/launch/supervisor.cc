// lanemap-launch's supervisor (see supervisor.h).
#include "tools/launch/supervisor.h"
#include "core/io/store_lock.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

namespace lanemap::launch {

namespace {

using Clock = std::chrono::steady_clock;

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop.store(true); }

std::string timestamp() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%H:%M:%S", std::localtime(&t));
  return buf;
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

}  // namespace

void stopOnSignals() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);
}

int supervise(Launch launch, std::vector<Spec> mine, const std::string& log_dir, double status_interval_s) {
  Launcher launcher(std::move(launch), std::move(mine), log_dir, status_interval_s);
  return launcher.run();
}

}  // namespace lanemap::launch
