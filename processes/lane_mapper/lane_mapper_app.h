// lanemap-lane-mapper: runs lane exploration (core/lanes/explorer.h) on every closed atomic road
// announced on BEV_ROAD, on a worker thread (a long road does not stall LCM handling), stores the
// road's lanes in the map store atomically (<store>/lanes/road_<id>.osm, Lanelet2, plus the whole
// <store>/lane_map.osm) and publishes LANE_MAP. On start it reloads the store and republishes it, so
// a restart loses no finished road, and maps the roads whose BEV grid is newer than their lanes
// (announced while it was down: STATUS roads_caught_up).
//
// A partial road (the road a drive ended on; BEV_ROAD's path is its bev/partial/ grid, whose JSON
// says how far it was driven: bev_store.h partialRoad) is explored as far as it was driven and its
// lanelets are tagged partial (core/mapping/partial_road.h; STATUS roads_partial); one driven too
// little to map is counted (partial_roads_too_short). A later BEV_ROAD of the road's own grid (a
// drive closed it, its partial evidence merged in) maps it again, complete. A lanelet Lanelet2
// would misread (its bounds against its driving direction) is left out of the road's lanes and
// said (STATUS lanelets_dropped; core/mapping/road_lanes.h): the rest of the road is mapped.
//
// The whole map (core/mapping/map_assembler.h) is kept between roads: a road's lanes rebuild the
// two intersections at its ends only, whatever the store's size. lane_map.osm, every road and
// intersection, is written after every road (export_interval_s 0, LANE_MAP after it) or at most
// once per export_interval_s, the last change always within it and when the process stops
// (STATUS map_exports, export_ms_max). On start it is written again when a road file is newer.
//
// The car's path through each intersection (core/tracking/passage_recorder.h, from POSE and the
// road tracker's ROAD_EVENT) shapes the connections of the road pair it drove
// (core/intersections/driven_passage.h), as lanemap-offline's do. Each is kept in the store
// (<store>/passages/passage_<from>_<to>_<k>.json, atomically) and read back on start, so a restart
// keeps the junctions' shape (STATUS passages_recorded, passages_loaded).
//
// STATUS latency (per road): from the BEV_ROAD message's receive time (lcm::ReceiveBuffer::recv_utime)
// to its LANE_MAP published: the wait behind other roads, loading the grid, lane exploration and
// (export_interval_s 0) rewriting lane_map.osm. map_road_ms_max: exploring one road, writing its
// file and rebuilding its intersections, the worst road.
//
//   lanemap-lane-mapper --config config/lane_mapper.yaml [--osm FILE] [--store DIR]
#pragma once

#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/io/store_lock.h"
#include "core/intersections/regulatory.h"
#include "core/io/lanelet2.h"
#include "core/io/passage_json.h"
#include "core/io/speed_limits.h"
#include "core/lanes/explorer.h"
#include "core/lanes/stop_lines.h"
#include "core/mapping/carried_lanes.h"
#include "core/mapping/map_assembler.h"
#include "core/mapping/partial_road.h"
#include "core/mapping/road_lanes.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/passage_recorder.h"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/lane_map_message.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>

namespace lanemap::lane_mapper_app {


namespace fs = std::filesystem;
using namespace lanemap;

class LaneMapperApp {
 public:
  LaneMapperApp(Process& process, std::unique_ptr<skeleton::Skeleton> sk, lanes::ExplorerOptions options,
                std::string store, const std::string& channel, int queue,
                intersections::IntersectionOptions intersection_options, std::vector<osm::Restriction> restrictions,
                double export_interval_s = 0.0)
      : process_(process), sk_(std::move(sk)), options_(options), store_(std::move(store)),
        export_interval_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(export_interval_s))) {
    assembler_ = std::make_unique<mapping::MapAssembler>(*sk_, std::move(intersection_options), std::move(restrictions));
    last_export_ = Clock::now() - export_interval_;  // the first export is due at once (not one interval after boot)
    write_options_.speed_limit_kmh_by_road = io::speedLimitsKmh(*sk_);  // OSM maxspeed
    io::createDirectories((fs::path(store_) / "lanes").string());
    reloadStore();
    // Subscribed before the store is searched for roads announced while it was down: a road
    // announced between the two is then queued twice (mapped once: onBevRoad), never missed.
    auto* sub = process_.lcm().subscribe(channel, &LaneMapperApp::onBevRoad, this);
    sub->setQueueCapacity(queue);
    process_.lcm().subscribe(channels::kPose, &LaneMapperApp::onPose, this)->setQueueCapacity(kPoseQueue);
    process_.lcm().subscribe(channels::kRoadEvent, &LaneMapperApp::onRoadEvent, this)->setQueueCapacity(kRoadEventQueue);
    catchUp();
    worker_ = std::thread([this] { work(); });
    process_.setIdleCheck([this] {  // process replay: wait for the worker after each input
      std::lock_guard<std::mutex> lock(mutex_);
      return jobs_.empty() && !busy_ && !export_pending_;
    });
    process_.setState("ready");
  }
  ~LaneMapperApp() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    worker_.join();
    if (export_pending_) {  // the last roads' changes (export_interval_s > 0)
      try {
        exportWholeMap();
      } catch (const std::exception& e) {
        std::cerr << "lane_mapper: writing " << wholeMapFile() << " at exit: " << e.what() << "\n";
      }
    }
  }

 private:
  static constexpr int kPoseQueue = 1000;     // POSE comes at up to 100 Hz
  static constexpr int kRoadEventQueue = 100;

  // The car's positions and the road tracker's events: each completed passage shapes its
  // intersection (rebuilt with the next road mapped there, or the next export) and is stored.
  void onPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* msg) {
    passage_recorder_.addPosition(toEnuPose(*msg, sk_->frame()).position.head<2>());
  }
  void onRoadEvent(const lcm::ReceiveBuffer*, const std::string&, const road_event_t* msg) {
    tracking::RoadEvent e;
    e.type = static_cast<tracking::RoadEventType>(msg->type);
    e.utime = msg->utime;
    e.road_id = msg->road_id;
    e.from_node = msg->from_node;
    e.to_node = msg->to_node;
    e.previous_road_id = msg->previous_road_id;
    e.intersection_id = msg->intersection_id;
    const auto passage = passage_recorder_.onEvent(e);
    if (!passage) return;
    bool added = false;
    {
      std::lock_guard<std::mutex> lock(roads_mutex_);
      added = assembler_->addPassage(*passage);
    }
    if (!added) return;  // roads that do not meet at an intersection of the skeleton
    const std::string file = passageFile(passage->from_road, passage->to_road);
    try {
      io::writePassageJson(*passage, file);
    } catch (const std::exception& ex) {
      std::cerr << "lane_mapper: writing " << file << ": " << ex.what() << " (the junction is still shaped by it)\n";
    }
    process_.counters().add("passages_recorded");
    {
      std::lock_guard<std::mutex> lock(mutex_);
      export_pending_ = true;
    }
    cv_.notify_one();
  }
  // A new file for a passage from road `from` to road `to`: the next free number.
  std::string passageFile(int64_t from, int64_t to) {
    const fs::path dir = fs::path(store_) / "passages";
    std::error_code ec;
    fs::create_directories(dir, ec);
    for (int k = 0;; ++k) {
      const fs::path f = dir / ("passage_" + std::to_string(from) + "_" + std::to_string(to) + "_" + std::to_string(k) + ".json");
      if (!fs::exists(f, ec)) return f.string();
    }
  }

  void onBevRoad(const lcm::ReceiveBuffer* rbuf, const std::string&, const bev_road_t* msg) {
    process_.counters().add("bev_roads_received");
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const bool queued = std::any_of(jobs_.begin(), jobs_.end(), [&](const Job& j) {
        return j.road.road_id == msg->road_id && j.road.path == msg->path;  // caught up at the start, not mapped yet
      });
      if (queued) return;
      jobs_.push_back(Job{*msg, rbuf->recv_utime});
      process_.counters().set("queue_length", static_cast<int64_t>(jobs_.size()));
    }
    cv_.notify_one();
  }

  void work() {
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        const auto ready = [this] { return stop_ || !jobs_.empty(); };
        if (export_pending_) {
          cv_.wait_until(lock, last_export_ + export_interval_, ready);
        } else {  // also woken by a change with no road to map (a driven passage shaped a junction)
          cv_.wait(lock, [&] { return ready() || export_pending_; });
        }
        if (stop_) return;
        if (jobs_.empty()) {  // the export interval is over: the changes since are written
          if (!export_pending_ || Clock::now() < last_export_ + export_interval_) continue;  // not yet: wait for it
          busy_ = true;
          lock.unlock();
          exportOrSay();
          lock.lock();
          busy_ = false;
          continue;
        }
        job = jobs_.front();
        jobs_.pop_front();
        busy_ = true;
        process_.counters().set("queue_length", static_cast<int64_t>(jobs_.size()));
      }
      try {
        mapRoad(job.road);
        process_.latency().add(static_cast<double>(geo::wallUtime() - job.recv_utime) * 1e-3);
      } catch (const std::exception& e) {
        process_.counters().add("roads_failed");
        std::cerr << "lane_mapper: road " << job.road.road_id << ": " << e.what() << "\n";
      }
      if (export_pending_ && Clock::now() >= last_export_ + export_interval_) exportOrSay();
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
  }

  void mapRoad(const bev_road_t& job) {
    const skeleton::AtomicRoad* road = sk_->road(job.road_id);
    if (!road) throw std::runtime_error("unknown road id " + std::to_string(job.road_id));
    std::optional<bev::PartialRoadInfo> partial;
    if (fs::path(job.path) == fs::path(bev::partialGridPath(store_, job.road_id))) {
      partial = bev::partialRoad(store_, job.road_id);
      if (!partial) return;  // completed since (its own BEV_ROAD follows) or its station unknown
    }
    const bev::BevGrid grid = bev::BevGrid::load(job.path);
    const auto t0 = std::chrono::steady_clock::now();
    lanes::RoadGeometry geometry = lanes::RoadGeometry::fromSkeleton(*road);
    if (partial) {
      try {
        geometry = mapping::drivenStretch(*road, partial->station_m, options_);
      } catch (const lanes::LanesError& e) {
        process_.counters().add("partial_roads_too_short");
        std::cerr << "lane_mapper: " << e.what() << "\n";
        return;
      }
    }
    const std::optional<map::PartialRoad> driven_to =
        partial ? std::optional<map::PartialRoad>(map::PartialRoad{partial->station_m, partial->road_length_m}) : std::nullopt;
    std::vector<lanes::CarriedLane> carried;  // a short road's lanes may run on from the road before
    int64_t carried_from = -1;                 // that road; the road itself: its OSM way's lanes
    {
      std::lock_guard<std::mutex> lock(roads_mutex_);
      carried = mapping::lanesRunningThrough(*sk_, *road, assembler_->roads(), options_, &carried_from);
    }
    auto [res, m, dropped, carried_in, apart, carried_added] =
        mapping::exploreRoadLanes(grid, geometry, driven_to, options_, sk_->frame().origin(), carried);
    const bool from_osm_way = carried_in && carried_from == road->id;
    if (carried_in) process_.counters().add(from_osm_way ? "roads_lanes_from_osm_way" : "roads_lanes_carried");
    process_.counters().add("lanes_apart_from_carried", apart);
    process_.counters().add("lanes_added_from_carried", carried_added);
    for (const auto& why : dropped) std::cerr << "lane_mapper: road " << job.road_id << ": lanelet left out, " << why << "\n";
    process_.counters().add("lanelets_dropped", static_cast<int64_t>(dropped.size()));
    if (partial) process_.counters().add("roads_partial");
    int64_t next_id = 1;
    for (const auto& l : m.lines) next_id = std::max(next_id, l.id + 1);
    for (const auto& l : m.lanelets) next_id = std::max(next_id, l.id + 1);
    m.crosswalks = lanes::findCrosswalks(grid, m, next_id);  // kept with the road's file
    io::writeLanelet2(m, roadFile(job.road_id), write_options_);  // atomic: a crash leaves the old file or the new one
    {
      std::lock_guard<std::mutex> lock(roads_mutex_);
      assembler_->setRoad(job.road_id, m);
      assembler_->update();  // the intersections at the road's two ends
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      export_pending_ = true;
    }
    const double map_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    map_road_ms_max_ = std::max(map_road_ms_max_, map_ms);
    process_.counters().set("map_road_ms_max", static_cast<int64_t>(map_road_ms_max_ + 0.5));
    process_.counters().add("roads_mapped");
    process_.counters().add("lanes_found", static_cast<int64_t>(res.lanes.size()));
    if (export_interval_ == Clock::duration::zero()) exportWholeMap();  // before LANE_MAP: its map_path holds the road
    publish(job.road_id, m, job.utime);
    // Lanes from the road's own OSM way stand in until a road meeting it gets lanes to carry.
    awaitLanes(*road, job.path, !res.lanes.empty() && !from_osm_way, partial.has_value());
  }

  // A short road mapped with no lane (nothing explored, no mapped road beside it to carry from;
  // or only its OSM way's lanes) waits with its grid's path; when a road meeting it gets lanes it
  // is mapped again from that grid (core/mapping/carried_lanes.h). (After a restart only a road
  // with no lane waits again.)
  void awaitLanes(const skeleton::AtomicRoad& road, const std::string& grid, bool has_lanes, bool partial) {
    if (!has_lanes) {
      if (!partial && mapping::isShortRoad(road, options_)) awaiting_[road.id] = grid;
      return;
    }
    awaiting_.erase(road.id);
    std::set<int64_t> ids;
    for (const auto& [id, path] : awaiting_) ids.insert(id);
    const auto again = mapping::roadsAwaitingLanesFrom(*sk_, road.id, ids);
    if (again.empty()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    for (int64_t id : again) {
      Job job;
      job.road.road_id = id;
      job.road.path = awaiting_.at(id);
      job.road.utime = geo::wallUtime();
      job.recv_utime = geo::wallUtime();
      jobs_.push_back(job);
      process_.counters().add("roads_mapped_again");
    }
  }

  std::string roadFile(int64_t id) const { return (fs::path(store_) / "lanes" / ("road_" + std::to_string(id) + ".osm")).string(); }
  std::string wholeMapFile() const { return (fs::path(store_) / "lane_map.osm").string(); }

  // lane_map.osm: the roads plus the intersections between them as kept (core/mapping, as the
  // offline runner writes them), the OSM junction controls and the crosswalks.
  void exportWholeMap() {
    const auto t0 = Clock::now();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      export_pending_ = false;  // a road mapped while this runs sets it again
      last_export_ = t0;
    }
    map::LaneMap all;
    std::vector<std::string> failures;
    std::vector<map::Crosswalk> crosswalks;
    {
      std::lock_guard<std::mutex> lock(roads_mutex_);
      all = assembler_->map(&failures);
      for (const auto& [id, m] : assembler_->roads()) crosswalks.insert(crosswalks.end(), m.crosswalks.begin(), m.crosswalks.end());
    }
    intersections::addRegulatoryElements(all, *sk_, controls_);  // OSM stop / give way / signals
    lanes::addCrosswalks(all, std::move(crosswalks));  // both directions of a crossing merged
    for (const auto& f : failures) std::cerr << "lane_mapper: " << f << " failed, the rest is mapped\n";
    process_.counters().set("intersections_failed", static_cast<int64_t>(failures.size()));
    if (!all.lanelets.empty()) io::writeLanelet2(all, wholeMapFile(), write_options_);
    export_ms_max_ = std::max(export_ms_max_, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    process_.counters().set("export_ms_max", static_cast<int64_t>(export_ms_max_ + 0.5));
    process_.counters().add("map_exports");
  }
  void exportOrSay() {
    try {
      exportWholeMap();
    } catch (const std::exception& e) {
      process_.counters().add("map_exports_failed");
      std::cerr << "lane_mapper: writing " << wholeMapFile() << ": " << e.what() << "\n";
    }
  }

  void reloadStore() {
    const auto& o = sk_->frame().origin();
    io::Lanelet2ReadOptions ro;
    ro.origin_alt = o.alt;
    std::error_code ec;
    const auto map_time = fs::last_write_time(wholeMapFile(), ec);
    const bool have_map = !ec;
    for (const auto& [id, path] : bev::roadFiles((fs::path(store_) / "lanes").string(), ".osm")) {
      try {
        auto lanes = io::readLanelet2(path, o.lat, o.lon, ro);
        const skeleton::AtomicRoad* road = sk_->road(id);
        if (road && lanes.lanelets.empty() && mapping::isShortRoad(*road, options_) && fs::exists(bev::roadGridPath(store_, id), ec)) {
          awaiting_[id] = bev::roadGridPath(store_, id);  // mapped with no lane before the restart: still waits
        }
        assembler_->setRoad(id, std::move(lanes));
        process_.counters().add("roads_loaded");
        if (!have_map || fs::last_write_time(path, ec) > map_time) export_pending_ = true;  // lane_map.osm lacks it
      } catch (const std::exception& e) {
        std::cerr << "lane_mapper: skipping " << path << ": " << e.what() << "\n";
      }
    }
    const fs::path passages = fs::path(store_) / "passages";
    if (fs::is_directory(passages, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(passages, ec)) {
        if (e.path().extension() == ".json" && e.path().filename().string().rfind("passage_", 0) == 0) files.push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      for (const auto& f : files) {
        try {
          if (assembler_->addPassage(io::readPassageJson(f.string()))) process_.counters().add("passages_loaded");
        } catch (const std::exception& e) {
          std::cerr << "lane_mapper: skipping " << f.string() << ": " << e.what() << "\n";
        }
      }
    }
    assembler_->update();
    for (const auto& [id, m] : assembler_->roads()) publish(id, m, geo::wallUtime());
  }

  // A road whose BEV grid is in the store but whose lanes are missing or older (its BEV_ROAD came
  // while this process was down, e.g. killed and restarted): mapped now, as if announced.
  void catchUp() {
    std::error_code ec;
    for (const auto& [id, path] : bev::roadFiles((fs::path(store_) / "bev").string(), ".bev")) {
      const std::string lanes = roadFile(id);
      if (fs::exists(lanes, ec) && fs::last_write_time(lanes, ec) >= fs::last_write_time(path, ec)) continue;
      Job job;
      job.road.road_id = id;
      job.road.path = path;
      job.road.utime = geo::wallUtime();
      job.recv_utime = geo::wallUtime();
      jobs_.push_back(job);
      process_.counters().add("roads_caught_up");
      std::cerr << "lane_mapper: road " << id << " has a BEV grid but no lanes newer than it: mapping it now\n";
    }
    for (const auto& [id, p] : bev::partialRoads(store_)) {  // roads a drive ended on
      const std::string lanes = roadFile(id);
      if (fs::exists(bev::roadGridPath(store_, id), ec)) continue;  // complete (the loop above)
      if (fs::exists(lanes, ec) && fs::last_write_time(lanes, ec) >= fs::last_write_time(p.path, ec)) continue;
      Job job;
      job.road.road_id = id;
      job.road.path = p.path;
      job.road.utime = geo::wallUtime();
      job.recv_utime = geo::wallUtime();
      jobs_.push_back(job);
      process_.counters().add("roads_caught_up");
      std::cerr << "lane_mapper: partial road " << id << " has no lanes newer than its BEV grid: mapping it now\n";
    }
  }

  void publish(int64_t road_id, const map::LaneMap& m, int64_t utime) {
    const lane_map_t msg = toMessage(road_id, m, utime, wholeMapFile());
    std::lock_guard<std::mutex> lock(publish_mutex_);
    process_.lcm().publish(channels::kLaneMap, &msg);
    process_.counters().add("lane_maps_published");
  }

  Process& process_;
  std::unique_ptr<skeleton::Skeleton> sk_;
  lanes::ExplorerOptions options_;
  std::string store_;
  std::mutex mutex_, roads_mutex_, publish_mutex_;
  std::condition_variable cv_;
  struct Job {
    bev_road_t road;
    int64_t recv_utime = 0;  // when LCM received the BEV_ROAD (wall clock)
  };
  std::deque<Job> jobs_;
  double map_road_ms_max_ = 0.0;  // worker thread only
  std::map<int64_t, std::string> awaiting_;  // short roads mapped with no lane -> their grid (awaitLanes; worker thread, and the constructor)
  double export_ms_max_ = 0.0;    // worker thread, then the destructor
  bool stop_ = false;
  bool busy_ = false;  // the worker is mapping a job or exporting (under mutex_)
  using Clock = std::chrono::steady_clock;
  Clock::duration export_interval_;
  Clock::time_point last_export_;  // under mutex_
  bool export_pending_ = false;      // roads changed since lane_map.osm was written (under mutex_)
  std::unique_ptr<mapping::MapAssembler> assembler_;  // every road's lanes, the intersections as built (under roads_mutex_)
  std::unordered_map<int64_t, intersections::ControlNode> controls_;  // set before spin()
  tracking::PassageRecorder passage_recorder_;  // LCM thread only

 public:
  void setControls(std::unordered_map<int64_t, intersections::ControlNode> c) { controls_ = std::move(c); }

 private:
  io::Lanelet2WriteOptions write_options_;
  std::thread worker_;
};

}  // namespace lanemap::lane_mapper_app
