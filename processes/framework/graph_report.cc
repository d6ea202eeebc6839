#include "processes/framework/graph_report.h"

#include "lanemap/lane_map_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "processes/framework/channels.h"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace lanemap {
namespace {

constexpr int64_t kSecond = 1000000;

std::string fmt(const char* format, double a) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, a);
  return buf;
}

std::string ms(double v) { return std::isnan(v) ? "-" : fmt("%.1f", v); }
std::string pct(double v) { return std::isnan(v) ? "-" : fmt("%.1f%%", 100.0 * v); }

// Counters that count frames a process received and did not turn into output (a counter a
// process has not reported, e.g. frames_failed before the first failure, is 0).
const std::vector<std::pair<std::string, std::vector<std::string>>>& frameDropCounters() {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> m = {
      {"segmenter", {"frames_dropped", "frames_corrupt", "frames_wrong_size", "frames_failed"}},
      {"bev_builder",
       {"frames_queue_full", "frames_late", "frames_out_of_order", "frames_no_pose", "frames_decode_error",
        "frames_wrong_size", "frames_unknown_class", "frames_pending"}},
  };
  return m;
}

// The graph's processes in data-flow order, then any other.
std::vector<const ProcessHealth*> inFlowOrder(const std::map<std::string, ProcessHealth>& all) {
  static const std::vector<std::string> order = {"segmenter", "road_tracker", "bev_builder", "lane_mapper"};
  std::vector<const ProcessHealth*> out;
  for (const auto& n : order) {
    if (auto it = all.find(n); it != all.end()) out.push_back(&it->second);
  }
  for (const auto& [n, p] : all) {
    if (std::find(order.begin(), order.end(), n) == order.end()) out.push_back(&p);
  }
  return out;
}

}  // namespace

int64_t ProcessHealth::counter(const std::string& name) const {
  auto it = counters.find(name);
  return it == counters.end() ? -1 : it->second;
}

const ProcessHealth* GraphReport::process(const std::string& name) const {
  auto it = processes.find(name);
  return it == processes.end() ? nullptr : &it->second;
}

double GraphReport::mapCompleteAfterS() const {
  if (lane_maps == 0 || drive_end_utime == 0 || last_lane_map_utime < drive_start_utime) return std::nan("");
  return static_cast<double>(last_lane_map_utime - drive_end_utime) * 1e-6;
}

std::vector<GraphLoss> GraphReport::frameLosses() const {
  std::vector<GraphLoss> out;
  for (const auto& [proc, names] : frameDropCounters()) {
    const ProcessHealth* p = process(proc);
    if (!p) continue;
    // The oracle segmenter (truth_received) has no frame queue: it republishes every message.
    if (proc == "segmenter" && p->has("truth_received")) continue;
    for (const auto& n : names) out.push_back({proc + " " + n, std::max<int64_t>(0, p->counter(n))});
  }
  auto pub = [&](const std::string& ch) -> int64_t {
    auto it = published.find(ch);
    return it == published.end() ? -1 : it->second;
  };
  const ProcessHealth* seg = process("segmenter");
  const ProcessHealth* bev = process("bev_builder");
  // Hand-overs: published by one side, received by the other.
  if (seg && seg->has("frames_received") && pub(channels::kCameraFront) >= 0) {
    out.push_back({std::string(channels::kCameraFront) + " player -> segmenter",
                   pub(channels::kCameraFront) - seg->counter("frames_received")});
  }
  if (seg && seg->has("truth_received") && pub(channels::kSemanticFrontTruth) >= 0) {
    out.push_back({std::string(channels::kSemanticFrontTruth) + " player -> segmenter",
                   pub(channels::kSemanticFrontTruth) - seg->counter("truth_received")});
  }
  if (bev && bev->has("frames_received")) {
    if (labels_channel == channels::kSemanticFront && seg && seg->has("labels_published")) {
      out.push_back({labels_channel + " segmenter -> bev_builder",
                     seg->counter("labels_published") - bev->counter("frames_received")});
    } else if (labels_channel != channels::kSemanticFront && pub(labels_channel) >= 0) {
      out.push_back({labels_channel + " player -> bev_builder", pub(labels_channel) - bev->counter("frames_received")});
    }
  }
  return out;
}

std::vector<GraphLoss> GraphReport::otherLosses() const {
  std::vector<GraphLoss> out;
  auto pub = [&](const std::string& ch) -> int64_t {
    auto it = published.find(ch);
    return it == published.end() ? -1 : it->second;
  };
  const ProcessHealth* rt = process("road_tracker");
  const ProcessHealth* bev = process("bev_builder");
  const ProcessHealth* lm = process("lane_mapper");
  const int64_t poses = pub(channels::kPose);
  if (poses >= 0) {
    if (rt) out.push_back({"POSE player -> road_tracker", poses - rt->counter("poses_received")});
    if (bev) out.push_back({"POSE player -> bev_builder", poses - bev->counter("poses_received")});
  }
  if (rt) out.push_back({"road_tracker poses_out_of_order", std::max<int64_t>(0, rt->counter("poses_out_of_order"))});
  if (bev) {
    out.push_back({"bev_builder poses_out_of_order", std::max<int64_t>(0, bev->counter("poses_out_of_order"))});
    if (pub(channels::kLidarPackets) >= 0) {
      out.push_back({"LIDAR_PACKETS player -> bev_builder", pub(channels::kLidarPackets) - bev->counter("sweeps_received")});
    }
    out.push_back({"bev_builder sweeps_no_pose", std::max<int64_t>(0, bev->counter("sweeps_no_pose"))});
    out.push_back({"bev_builder sweeps_replaced", std::max<int64_t>(0, bev->counter("sweeps_replaced"))});
    out.push_back({"bev_builder roads_write_failed", std::max<int64_t>(0, bev->counter("roads_write_failed"))});
    if (lm) {
      out.push_back({"BEV_ROAD bev_builder -> lane_mapper",
                     std::max<int64_t>(0, bev->counter("roads_written")) - std::max<int64_t>(0, lm->counter("bev_roads_received"))});
    }
  }
  if (lm) out.push_back({"lane_mapper roads_failed", std::max<int64_t>(0, lm->counter("roads_failed"))});
  return out;
}

int64_t GraphReport::framesLost() const {
  int64_t n = 0;
  for (const auto& l : frameLosses()) n += std::max<int64_t>(0, l.count);
  return n;
}

std::map<std::string, int64_t> countLogChannels(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot read LCM log '" + path + "'");
  std::map<std::string, int64_t> n;
  while (const lcm::LogEvent* ev = log.readNextEvent()) ++n[ev->channel];
  return n;
}

GraphReport readGraphReport(const std::string& graph_log, const std::string& drive_log,
                            const std::string& labels_channel) {
  GraphReport r;
  r.labels_channel = labels_channel;
  if (!drive_log.empty()) r.published = countLogChannels(drive_log);
  std::vector<status_t> statuses;
  std::vector<std::pair<int64_t, std::pair<int64_t, double>>> closed;  // road id, (reached, to map)
  {
    lcm::LogFile log(graph_log, "r");
    if (!log.good()) throw std::runtime_error("cannot read LCM log '" + graph_log + "'");
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      const std::string ch = ev->channel;
      if (ch == channels::kPose) {
        if (r.poses_recorded++ == 0) r.drive_start_utime = ev->timestamp;
        r.drive_end_utime = ev->timestamp;
      } else if (ch == channels::kStatus) {
        status_t s;
        if (s.decode(ev->data, 0, static_cast<int>(ev->datalen)) >= 0) statuses.push_back(std::move(s));
      } else if (ch == channels::kLaneMap) {
        ++r.lane_maps;
        r.last_lane_map_utime = ev->timestamp;
        lane_map_t m;
        if (m.decode(ev->data, 0, static_cast<int>(ev->datalen)) >= 0 && m.kind == lane_map_t::KIND_ROAD) {
          for (auto& [id, t] : closed) {
            if (id == m.id && std::isnan(t.second)) t.second = static_cast<double>(ev->timestamp - t.first) * 1e-6;
          }
        }
      } else if (ch == channels::kBevRoad) {
        ++r.bev_roads;
      } else if (ch == channels::kRoadEvent) {
        ++r.road_events;
        road_event_t e;
        if (e.decode(ev->data, 0, static_cast<int>(ev->datalen)) >= 0 && e.type == road_event_t::TYPE_REACHED_INTERSECTION) {
          closed.push_back({e.road_id, {ev->timestamp, std::nan("")}});
        }
      }
    }
  }
  for (const auto& [id, t] : closed) r.road_to_map_s.push_back({id, t.second});
  // STATUS cpu_fraction covers the second before its utime: those within the drive.
  const bool window = r.drive_end_utime > r.drive_start_utime;
  std::map<std::string, std::pair<double, int>> cpu_sum;
  for (const auto& s : statuses) {
    ProcessHealth& p = r.processes[s.process];
    p.name = s.process;
    ++p.statuses;
    p.pids.insert(s.pid);
    p.state = s.state;
    p.counters.clear();
    for (int i = 0; i < s.num_counters; ++i) p.counters[s.counter_names[i]] = s.counter_values[i];
    if (!std::isnan(s.latency_p50_ms)) {
      p.latency_p50_ms = s.latency_p50_ms;
      p.latency_p99_ms = s.latency_p99_ms;
      if (std::isnan(p.latency_p99_worst_ms) || s.latency_p99_ms > p.latency_p99_worst_ms) p.latency_p99_worst_ms = s.latency_p99_ms;
    }
    const bool in_drive = !window || (s.utime >= r.drive_start_utime + kSecond && s.utime <= r.drive_end_utime + kSecond);
    if (in_drive && s.state != "stopped") {
      auto& [sum, n] = cpu_sum[s.process];
      sum += s.cpu_fraction;
      ++n;
      if (std::isnan(p.cpu_max) || s.cpu_fraction > p.cpu_max) p.cpu_max = s.cpu_fraction;
    }
  }
  for (auto& [name, p] : r.processes) {
    auto it = cpu_sum.find(name);
    if (it != cpu_sum.end() && it->second.second > 0) p.cpu_mean = it->second.first / it->second.second;
  }
  return r;
}

void printGraphReport(const GraphReport& r, std::ostream& out) {
  char line[256];
  if (r.poses_recorded > 0) {
    std::snprintf(line, sizeof(line), "drive played: %.1f s (%lld POSE recorded), %d processes reported STATUS\n",
                  r.driveSeconds(), static_cast<long long>(r.poses_recorded), static_cast<int>(r.processes.size()));
  } else {
    std::snprintf(line, sizeof(line), "drive played: no POSE recorded, %d processes reported STATUS\n",
                  static_cast<int>(r.processes.size()));
  }
  out << line;
  if (r.published.count(channels::kPose) && r.published.at(channels::kPose) != r.poses_recorded) {
    // lcm-logger's own subscription queue overflowed: the recording's drive window is approximate.
    std::snprintf(line, sizeof(line), "  (the recorder missed %lld of the %lld POSE played: the drive window is approximate)\n",
                  static_cast<long long>(r.published.at(channels::kPose) - r.poses_recorded),
                  static_cast<long long>(r.published.at(channels::kPose)));
    out << line;
  }
  out << "CPU: share of one core over the drive (STATUS cpu_fraction, 1 s each); latency: p50/p99 of each\n"
         "process's last 500 events (input received -> output done, see its header), worst p99 of any STATUS\n";
  std::snprintf(line, sizeof(line), "  %-14s %8s %8s %11s %11s %11s %9s\n", "process", "CPU mean", "CPU max", "p50 ms",
                "p99 ms", "worst p99", "restarts");
  out << line;
  double cpu_total = 0.0;
  for (const ProcessHealth* pp : inFlowOrder(r.processes)) {
    const ProcessHealth& p = *pp;
    if (!std::isnan(p.cpu_mean)) cpu_total += p.cpu_mean;
    std::snprintf(line, sizeof(line), "  %-14s %8s %8s %11s %11s %11s %9d\n", p.name.c_str(), pct(p.cpu_mean).c_str(),
                  pct(p.cpu_max).c_str(), ms(p.latency_p50_ms).c_str(), ms(p.latency_p99_ms).c_str(),
                  ms(p.latency_p99_worst_ms).c_str(), static_cast<int>(p.pids.size()) - 1);
    out << line;
  }
  std::snprintf(line, sizeof(line), "  %-14s %8s   (sum of the means, in cores)\n", "all", pct(cpu_total).c_str());
  out << line;

  const ProcessHealth* seg = r.process("segmenter");
  const ProcessHealth* bev = r.process("bev_builder");
  if (bev) {
    std::snprintf(line, sizeof(line), "frame-to-BEV (bev_builder: labels received -> projected into the grid): p50 %s ms, p99 %s ms\n",
                  ms(bev->latency_p50_ms).c_str(), ms(bev->latency_p99_ms).c_str());
    out << line;
    if (seg && r.labels_channel == channels::kSemanticFront) {
      const bool oracle = seg->has("truth_received");
      std::snprintf(line, sizeof(line), "  segmenter (%s): p50 %s ms, p99 %s ms\n",
                    oracle ? "oracle: truth labels received -> republished" : "camera frame received -> labels published",
                    ms(seg->latency_p50_ms).c_str(), ms(seg->latency_p99_ms).c_str());
      out << line;
      std::snprintf(line, sizeof(line), "  %s-to-BEV (segmenter + bev_builder, percentiles added): p50 %s ms, p99 %s ms\n",
                    oracle ? "labels" : "camera", ms(seg->latency_p50_ms + bev->latency_p50_ms).c_str(),
                    ms(seg->latency_p99_ms + bev->latency_p99_ms).c_str());
      out << line;
    }
    std::snprintf(line, sizeof(line), "frames: %lld received by bev_builder, %lld projected (%lld on the LIDAR mesh)\n",
                  static_cast<long long>(bev->counter("frames_received")), static_cast<long long>(bev->counter("frames_projected")),
                  static_cast<long long>(bev->counter("frames_mesh")));
    out << line;
  }
  if (seg && seg->has("frames_received")) {
    std::snprintf(line, sizeof(line), "segmenter: %lld frames received, %lld segmented, %lld dropped (queue of the newest)\n",
                  static_cast<long long>(seg->counter("frames_received")), static_cast<long long>(seg->counter("frames_segmented")),
                  static_cast<long long>(std::max<int64_t>(0, seg->counter("frames_dropped"))));
    out << line;
  }

  out << "frame losses (drop counters of the last STATUS; hand-overs: published - received):\n";
  for (const auto& l : r.frameLosses()) {
    std::snprintf(line, sizeof(line), "  %-48s %6lld\n", l.what.c_str(), static_cast<long long>(l.count));
    out << line;
  }
  out << "other losses:\n";
  for (const auto& l : r.otherLosses()) {
    std::snprintf(line, sizeof(line), "  %-48s %6lld\n", l.what.c_str(), static_cast<long long>(l.count));
    out << line;
  }
  const int64_t lost = r.framesLost();
  if (lost == 0) {
    out << "no frame dropped\n";
  } else {
    out << lost << " frame(s) dropped or lost\n";
  }
  if (!r.road_to_map_s.empty()) {
    out << "roads closed (ROAD_EVENT reached intersection -> its LANE_MAP):";
    for (const auto& [id, s] : r.road_to_map_s) {
      out << " " << id << (std::isnan(s) ? ": not mapped" : ": " + fmt("%.2f s", s)) << ";";
    }
    out << "\n";
  }
  const ProcessHealth* lm = r.process("lane_mapper");
  const double after = r.mapCompleteAfterS();
  if (std::isnan(after)) {
    out << "map: no LANE_MAP after the drive's start\n";
  } else {
    std::snprintf(line, sizeof(line), "map complete %.1f s %s the drive's end (last LANE_MAP; %lld LANE_MAP, roads: %lld written by bev_builder, %lld mapped)\n",
                  std::abs(after), after >= 0 ? "after" : "before", static_cast<long long>(r.lane_maps),
                  static_cast<long long>(bev ? bev->counter("roads_written") : -1),
                  static_cast<long long>(lm ? lm->counter("roads_mapped") : -1));
    out << line;
  }
}

}  // namespace lanemap
