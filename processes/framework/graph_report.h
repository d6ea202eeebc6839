// How a live run of the graph went, from what it said about itself: an LCM log recorded beside it
// (config/launch/demo.yaml's recorder: STATUS, ROAD_EVENT, BEV_ROAD, LANE_MAP, POSE), optionally
// with the drive log that was played (what was published). lanemap-graph-report prints it
// (scripts/demo.sh, tools/bench/live_graph.sh); tests/mapping/live_graph_test.cc asserts on it.
//
// - Drive window: the receive times of the first and last POSE in the recording (the player's
//   start and end, to within a pose period; lcm-logger itself may miss a few when the machine is
//   loaded, which the print says).
// - Per process (by STATUS.process): its last STATUS counters; CPU share (status_t.cpu_fraction,
//   of one core) mean and max over the STATUS messages that cover the drive; latency p50/p99 of its
//   last STATUS that has any (each process's window of its last 500 events, see its header) and
//   the worst p99 any STATUS reported; restarts (distinct pids - 1).
// - Frame losses: every frame-dropping counter of every process (segmenter frames_dropped, ...,
//   bev_builder frames_queue_full, frames_late, frames_out_of_order, ...), the frames received
//   but neither projected nor counted (still pending at the end), and the hand-overs that lost
//   frames on the bus (published by one side, not received by the other: an LCM subscription
//   queue or a socket buffer overflowed; LCM counts neither).
// - Other losses: poses, LIDAR sweeps (sweeps_replaced: the mesh worker was busy; the frames then
//   use an older mesh or the flat plane), roads.
// - Map complete: the last LANE_MAP's receive time after the drive's end (lane_mapper writes
//   lane_map.osm just before it publishes). Negative when the last road closed before the drive's
//   end: the road the car is on when the drive ends never closes, live or offline.
// - Road to map: per closed road, from its ROAD_EVENT "reached intersection" to its first LANE_MAP
//   after it (the bev_builder's close delay, the grid written, lane exploration, the map written).
#pragma once

#include "lanemap/status_t.hpp"
#include "processes/framework/channels.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

namespace lanemap {

struct ProcessHealth {
  std::string name;
  std::map<std::string, int64_t> counters;  // of its last STATUS
  std::string state;                        // of its last STATUS
  int statuses = 0;
  std::set<int32_t> pids;
  double cpu_mean = std::nan(""), cpu_max = std::nan("");  // fraction of one core, over the drive
  double latency_p50_ms = std::nan(""), latency_p99_ms = std::nan("");  // last STATUS with samples
  double latency_p99_worst_ms = std::nan("");                           // any STATUS

  // A counter of the last STATUS; -1 when the process never reported it.
  int64_t counter(const std::string& name) const;
  bool has(const std::string& name) const { return counters.count(name) > 0; }
};

struct GraphLoss {
  std::string what;   // "bev_builder frames_late", "SEMANTIC_FRONT segmenter -> bev_builder", ...
  int64_t count = 0;  // >= 0: frames (or poses, sweeps, roads) lost
};

struct GraphReport {
  std::map<std::string, ProcessHealth> processes;
  int64_t drive_start_utime = 0, drive_end_utime = 0;  // first / last POSE received; 0: none
  int64_t poses_recorded = 0, road_events = 0, bev_roads = 0, lane_maps = 0;
  int64_t last_lane_map_utime = 0;
  // Closed roads in order: road id and seconds from "reached intersection" to its LANE_MAP (NaN:
  // never mapped while recording).
  std::vector<std::pair<int64_t, double>> road_to_map_s;
  // Messages per channel of the drive log that was played ({} when not given).
  std::map<std::string, int64_t> published;
  // The channel the bev_builder projects (its semantic channel).
  std::string labels_channel = channels::kSemanticFront;

  const ProcessHealth* process(const std::string& name) const;
  double driveSeconds() const { return (drive_end_utime - drive_start_utime) * 1e-6; }
  // Seconds from the drive's end to the last LANE_MAP; NaN when there is none after the start.
  double mapCompleteAfterS() const;
  // Every frame-loss figure (zeros included, so a reader sees what was checked).
  std::vector<GraphLoss> frameLosses() const;
  std::vector<GraphLoss> otherLosses() const;
  int64_t framesLost() const;
};

// Messages per channel of an LCM log; throws std::runtime_error when it cannot be read.
std::map<std::string, int64_t> countLogChannels(const std::string& path);

// Reads the recording; `drive_log` (may be empty) is the log that was played.
GraphReport readGraphReport(const std::string& graph_log, const std::string& drive_log = "",
                            const std::string& labels_channel = channels::kSemanticFront);

void printGraphReport(const GraphReport& report, std::ostream& out);

}  // namespace lanemap
