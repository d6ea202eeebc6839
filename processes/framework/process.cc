#include "processes/framework/process.h"

#include "core/geo/wall_clock.h"
#include "lanemap/status_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/log_reader.h"
#include "processes/framework/share_dir.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <stdexcept>
#include <thread>
#include <vector>

namespace lanemap {
namespace {

std::atomic<bool> g_stop{false};

void onSignal(int) { g_stop.store(true); }

double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string hostName() {
  char buf[256] = {0};
  if (gethostname(buf, sizeof(buf) - 1) != 0) return "unknown";
  return buf;
}

}  // namespace


void Counters::add(const std::string& name, int64_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  values_[name] += n;
}

void Counters::set(const std::string& name, int64_t value) {
  std::lock_guard<std::mutex> lock(mutex_);
  values_[name] = value;
}

int64_t Counters::get(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = values_.find(name);
  return it == values_.end() ? 0 : it->second;
}

std::map<std::string, int64_t> Counters::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return values_;
}

void LatencyWindow::add(double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  samples_.push_back(ms);
  while (samples_.size() > 500) samples_.pop_front();
}

double LatencyWindow::percentile(double p) const {
  std::vector<double> v;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    v.assign(samples_.begin(), samples_.end());
  }
  if (v.empty()) return std::nan("");
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::floor(p * (v.size() - 1) + 0.5)));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

std::string resolveLcmUrl(const std::string& flag, const YAML::Node& config) {
  if (!flag.empty()) return flag;
  if (config && config["lcm_url"] && !config["lcm_url"].as<std::string>().empty()) {
    return config["lcm_url"].as<std::string>();
  }
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) return env;
  return "";
}

YAML::Node loadYamlFile(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error("cannot read config file '" + path + "'");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("config file '" + path + "': " + e.what());
  }
}

Process::Process(std::string name)
    : name_(std::move(name)), cli_("lanemap " + name_ + " (an LCM process of lanemap)") {
  cli_.add_option("-c,--config", config_path_, "YAML config file");
  cli_.add_option("--lcm-url", lcm_url_flag_,
                  "LCM URL, e.g. udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608 "
                  "(default: config lcm_url, then $LCM_DEFAULT_URL)");
  auto* in = cli_.add_option("--replay", replay_in_,
                             "process replay: handle every event of this LCM log in order on an in-process bus "
                             "(memq://), one at a time, then exit (tests/replay)");
  auto* out = cli_.add_option("--replay-out", replay_out_,
                              "... and write what the process publishes to this LCM log; alone: the process reads its "
                              "own input (a driver's --file or --pcap) on an in-process bus and this log records its output");
  in->needs(out);
}

Process::~Process() {
  if (!replay_log_) return;
  idle_ = nullptr;  // the app is gone: what it published on its way out is in the queue
  drainReplay(false);
  replay_log_.reset();
}

int Process::init(int argc, char** argv) {
  try {
    cli_.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli_.exit(e);
  }
  try {
    if (!config_path_.empty()) {
      config_path_ = resolveShippedFile(config_path_);
      settings_ = config::YamlReader::loadFile(config_path_);
      config_ = settings_.node();
    }
    settings_.allow({"lcm_url"});
  } catch (const std::exception& e) {
    std::cerr << name_ << ": " << e.what() << "\n";
    return 2;
  }
  const std::string url = recording() ? std::string("memq://") : resolveLcmUrl(lcm_url_flag_, config_);
  if (recording()) {
    replay_log_ = std::make_unique<lcm::LogFile>(replay_out_, "w");
    if (!replay_log_->good()) {
      std::cerr << name_ << ": cannot write the replay output '" << replay_out_ << "'\n";
      return 2;
    }
  }
  lcm_ = std::make_unique<lcm::LCM>(url);
  if (!lcm_->good()) {
    std::cerr << name_ << ": cannot open LCM '" << (url.empty() ? "(default)" : url) << "'\n";
    return 3;
  }
  if (recording()) lcm_->subscribe(".*", &Process::onReplayMessage, this);  // first: sees every message
  g_stop.store(false);
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  last_cpu_s_ = processCpuSeconds();
  last_status_wall_ = std::chrono::steady_clock::now();
  setState("running");
  return -1;
}

void Process::setState(const std::string& state) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  state_ = state;
}

void Process::publishStatus() {
  status_t msg;
  msg.utime = geo::wallUtime();
  msg.process = name_;
  msg.host = hostName();
  msg.pid = static_cast<int32_t>(getpid());
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    msg.state = state_;
  }
  for (const auto& [k, v] : counters_.snapshot()) {
    msg.counter_names.push_back(k);
    msg.counter_values.push_back(v);
  }
  msg.num_counters = static_cast<int32_t>(msg.counter_names.size());
  msg.latency_p50_ms = latency_.percentile(0.5);
  msg.latency_p99_ms = latency_.percentile(0.99);
  const auto wall = std::chrono::steady_clock::now();
  const double cpu = processCpuSeconds();
  const double dt = std::chrono::duration<double>(wall - last_status_wall_).count();
  msg.cpu_fraction = dt > 0 ? (cpu - last_cpu_s_) / dt : 0.0;
  last_cpu_s_ = cpu;
  last_status_wall_ = wall;
  lcm_->publish(channels::kStatus, &msg);
}

int Process::spin() {
  if (replaying()) return replay();
  auto next_status = std::chrono::steady_clock::now();
  while (!g_stop.load()) {
    const int rc = lcm_->handleTimeout(100);
    if (rc < 0 && g_stop.load()) break;  // a signal interrupted the wait
    if (rc < 0) {
      std::cerr << name_ << ": LCM handle failed\n";
      return 1;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_status) {
      publishStatus();
      next_status = now + std::chrono::seconds(1);
    }
  }
  setState("stopped");
  publishStatus();
  return 0;
}

int Process::replay() {
  try {
    LogReader in(replay_in_);
    while (const lcm::LogEvent* ev = in.next()) {
      if (ev->channel == channels::kStatus) continue;
      replay_utime_ = ev->timestamp;
      replay_inputs_.emplace_back(ev->channel, std::string(static_cast<const char*>(ev->data), static_cast<size_t>(ev->datalen)));
      lcm_->publish(ev->channel, ev->data, static_cast<unsigned>(ev->datalen));
      drainReplay(true);
      if (g_stop.load()) break;
    }
    std::cerr << name_ << ": replayed " << in.events() << " events of " << replay_in_ << ", " << replay_events_
              << " published so far\n";
  } catch (const std::exception& e) {
    std::cerr << name_ << ": replay: " << e.what() << "\n";
    return 2;
  }
  setState("stopped");
  return 0;
}

// Handles what is queued; with wait_idle, also waits for the app's worker (setIdleCheck) and
// handles what it published, until both are done.
void Process::drainReplay(bool wait_idle) {
  for (;;) {
    while (lcm_->handleTimeout(0) > 0) {
    }
    if (!wait_idle || !idle_) return;
    if (idle_()) {
      if (lcm_->handleTimeout(0) <= 0) return;  // idle and nothing came meanwhile
      continue;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void Process::onReplayMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!replay_inputs_.empty() && replay_inputs_.front().first == channel &&
      replay_inputs_.front().second.size() == rbuf->data_size &&
      std::equal(replay_inputs_.front().second.begin(), replay_inputs_.front().second.end(), static_cast<const char*>(rbuf->data))) {
    replay_inputs_.pop_front();  // an input coming back
    return;
  }
  if (channel == channels::kStatus || !replay_log_) return;
  lcm::LogEvent ev;
  ev.eventnum = replay_events_++;
  ev.timestamp = replay_utime_;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(rbuf->data_size);
  ev.data = rbuf->data;
  replay_log_->writeEvent(&ev);
}

void Process::requestStop() { g_stop.store(true); }
bool Process::stopRequested() { return g_stop.load(); }

}  // namespace lanemap
