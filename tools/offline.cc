// lanemap-offline: maps a recorded drive without LCM networking. Reads the log directly and runs
// the same core stages as the live graph (road tracker -> BEV builder -> lane exploration ->
// intersections -> map assembly) in one process, as fast as the CPU allows. Deterministic: the LIDAR meshes are built in
// a worker thread that never drops a sweep (the live bev_builder drops the oldest when it falls
// behind), and each frame's mesh is chosen by time, so the map does not depend on the CPU's load;
// --mesh-in-main-thread builds them in this thread (one core, the same map).
//
//   lanemap-offline --log drive.lcmlog --osm roads.osm --out DIR
//       [--oracle | --semantic-channel CHANNEL] [--model FILE.onnx] [--no-lidar]
// writes DIR/map.osm (Lanelet2), DIR/map.geojson, DIR/map.png, DIR/summary.json and
// DIR/bev/road_<id>.bev.
//
// Several drives of one area: --log A --log B ... maps them in that order into one map. Each drive
// has its own road tracker and BEV builder; a road that an earlier drive closed gets this drive's
// BEV aligned to the earlier evidence and merged (bev::mergeAligned: both onto the traversals' mean),
// then is explored again (summary.json "drives": every merge, its shift and rotation). --no-align merges as
// it comes, to show what alignment removes.
//
// Labels: by default every CAMERA_FRONT frame is segmented with the configured model
// (config/segmenter.yaml, as lanemap-segmenter does), so a real recording needs nothing else;
// --oracle takes the simulator's SEMANTIC_FRONT_TRUTH instead, --semantic-channel any label
// channel already in the log (SEMANTIC_FRONT of a log lanemap-segmenter --log-out wrote).
//
// Config: the same files and readers as the live processes (processes/framework/process_configs.h):
// --lanes-config (config/lane_mapper.yaml) gives the explorer options and names the map block
// (`map:`, config/map.yaml: skeleton options, origin) and the intersections block
// (`intersections:`, config/intersections.yaml), as the lane mapper reads them; --tracker-config
// and --bev-config are the road tracker's and the BEV builder's files. --osm is required here.
//
// In two halves (lanemap-city runs them on several cores or Slurm nodes): `--log D --project-only
// DIR` projects one drive and keeps what its BEV builder hands over (DriveProjection), `--traversals
// DIR ...` maps projected drives in the order given, as their logs would have been mapped. The
// second half in shards of roads: `--drive-offsets --offsets-out F` solves the drives' offsets
// once; `--shard K/N --offsets-in F --out SK` fuses and explores the roads whose id is K modulo N
// (no lane carried in from a neighbour: it may be another shard's), keeping each road's lanes
// (roads/road_<id>.json, core/io/lane_map_json.h: lossless) and grids; `--assemble S0 ... --out
// DIR` takes every shard's roads, carries lanes into the short roads left with none, builds the
// junctions and writes the map one process would have written.
//
// The car's path through each junction it drove (core/tracking/passage_recorder.h, cut from the
// poses by the road tracker's events) shapes the connections of that road pair and corrects their
// pairing (core/intersections/driven_passage.h): kept in a projection's projection.json and a
// shard's shard.json (`passages`), counted in summary.json.
//
// The road being driven when a log ends never closed: it is explored on what was driven, as far as
// the car's last pose (core/mapping/partial_road.h), and its lanelets are tagged partial with that
// station and the road's length (the map's sidecar and GeoJSON; summary.json roads[].partial). Its
// grid is kept in bev/partial/; a later --log that closes the road merges that evidence (aligned)
// and explores it again, complete (drives[].merged[].completed_partial).
//
// One road's trouble never costs the map: a road whose exploration fails is named on stderr and in
// summary.json (roads_failed, with the reason), and every other road is still mapped.
#include "core/bev/bev_align.h"
#include "core/bev/bev_builder.h"
#include "core/bev/bev_store.h"
#include "core/bev/drive_offsets.h"
#include "core/camera/camera_model.h"
#include "core/config/vehicle_config.h"
#include "core/io/geojson.h"
#include "core/intersections/regulatory.h"
#include "core/io/lanelet2.h"
#include "core/io/lane_map_json.h"
#include "core/io/passage_json.h"
#include "core/lanes/stop_lines.h"
#include "core/io/map_png.h"
#include "core/io/speed_limits.h"
#include "core/lanes/explorer.h"
#include "core/lanes/options.h"
#include "core/mapping/carried_lanes.h"
#include "core/mapping/map_assembler.h"
#include "core/mapping/partial_road.h"
#include "core/mapping/road_lanes.h"
#include "core/osm/osm_data.h"
#include "core/seg/segmenter.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/passage_recorder.h"
#include "core/tracking/road_tracker.h"
#include "core/io/atomic_file.h"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/pose_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/log_reader.h"
#include "processes/framework/process_configs.h"
#include "processes/framework/share_dir.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <set>
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;
using namespace lanemap;

namespace {

struct Options {
  std::vector<std::string> logs;  // one drive each, mapped in this order into one map
  std::string project_only;       // the one drive's traversals saved to this folder, not mapped
  std::vector<std::string> traversals;  // drives projected before (--project-only folders), mapped in this order
  bool no_align = false;          // merge later drives' BEV unaligned (to measure what alignment does)
  bool align_rotation = false;    // search a small rotation too when aligning (bev_align.h)
  bool drive_offsets = false;     // --traversals: each drive's offset solved over the roads drives share first
  std::string offsets_out;        // --drive-offsets: write the solved offsets here and stop (a sharded fusion's first task)
  std::string offsets_in;         // --traversals: the drives' offsets from this file (--offsets-out), not solved
  std::string shard;              // "K/N": fuse and explore only the roads with id % N == K (no junctions, no map)
  std::vector<std::string> assemble;  // the shards' folders: their roads into one map (junctions, export)
  std::string osm, out;
  std::string semantic_channel;  // empty: segment CAMERA_FRONT with the model
  bool oracle = false;
  std::string segmenter_config = "config/segmenter.yaml";
  std::string model;             // overrides the segmenter config's model.path
  std::string autoware;          // also write Autoware's map folder (lanelet2_map.osm, map_projector_info.yaml) here
  std::string vehicle = "config/vehicle.yaml";
  std::string bev_config = "config/bev_builder.yaml";
  std::string lanes_config = "config/lane_mapper.yaml";
  std::string tracker_config = "config/road_tracker.yaml";
  std::string intersections_config;  // "": the lanes config's `intersections:` (as the lane mapper)
  std::string map_config;            // "": the lanes config's `map:` (as the lane mapper)
  bool no_lidar = false, quiet = false, mesh_in_main_thread = false;
};

// What the live processes read from the same files, through the same functions
// (processes/framework/process_configs.h): the skeleton and intersections exactly as the lane
// mapper builds them, the tracker's and the BEV builder's options as theirs.
struct OfflineConfig {
  LaneMapperSettings lanes;
  RoadTrackerSettings tracker;
  BevBuilderSettings bev;
  config::VehicleConfig vehicle;  // --vehicle, read whole as the BEV builder reads it
};

OfflineConfig loadConfig(const Options& o) {
  OfflineConfig c{LaneMapperSettings::fromYamlFile(o.lanes_config), RoadTrackerSettings::fromYamlFile(o.tracker_config),
                  BevBuilderSettings::fromYamlFile(o.bev_config), config::VehicleConfig::fromYamlFile(o.vehicle)};
  if (!o.map_config.empty()) c.lanes.map = config::MapConfig::fromYamlFile(o.map_config);
  if (!o.intersections_config.empty()) c.lanes.intersections = intersectionsFromFile(o.intersections_config);
  return c;
}

int64_t g_undecodable = 0;  // messages of a mapped channel that do not decode (a corrupt log)

template <typename T>
bool decode(const lcm::LogEvent& ev, T& msg) {
  if (msg.decode(ev.data, 0, static_cast<int>(ev.datalen)) >= 0) return true;
  ++g_undecodable;
  return false;
}

// A drive projected and not mapped (--project-only DIR): the traversals its BEV builder handed
// over, in order, each a grid file, and the road it ended on with its last position, beside a
// manifest (projection.json, written last: a folder without one is an interrupted projection).
// --traversals DIR maps them as --log would have at that point: the same roads, grids and order,
// so drives projected apart (lanemap-city: on several cores or machines) fuse into the same map.
constexpr int kProjectionFormat = 1;

class DriveProjection {
 public:
  explicit DriveProjection(std::string dir) : dir_(std::move(dir)) {
    fs::create_directories(dir_);
    manifest_ = {{"lanemap_projection", kProjectionFormat}, {"closed", nlohmann::json::array()}, {"open", nullptr},
                 {"passages", nlohmann::json::array()}};
  }
  // The car's path through an intersection (optional in the format: a projection without any maps
  // its junctions with Bezier curves only).
  void passage(const intersections::DrivenPassage& p) { manifest_["passages"].push_back(io::passageToJson(p)); }
  void closed(const bev::RoadBev& road) {
    const std::string file = "traversal_" + std::to_string(manifest_["closed"].size()) + ".bev";
    road.grid.save((fs::path(dir_) / file).string());
    manifest_["closed"].push_back({{"road_id", road.road_id}, {"file", file}});
  }
  void open(const bev::RoadBev& road, const Eigen::Vector2d& last_position) {
    road.grid.save((fs::path(dir_) / "open.bev").string());
    manifest_["open"] = {{"road_id", road.road_id}, {"file", "open.bev"}, {"last_position", {last_position.x(), last_position.y()}}};
  }
  // The drive's figures (summary.json's), then the manifest.
  void finish(const nlohmann::json& figures) {
    for (const auto& [k, v] : figures.items()) manifest_[k] = v;
    io::writeFileAtomically((fs::path(dir_) / "projection.json").string(), manifest_.dump(2) + "\n");
  }

 private:
  std::string dir_;
  nlohmann::json manifest_;
};

// A projection folder's manifest, checked (a clear error for a folder that is not one, or one of
// another format).
nlohmann::json readProjection(const std::string& dir) {
  const fs::path path = fs::path(dir) / "projection.json";
  if (!fs::exists(path)) throw std::runtime_error(dir + ": not a drive projection (no projection.json; interrupted?)");
  std::ifstream in(path);
  nlohmann::json m = nlohmann::json::parse(in, nullptr, false);
  if (m.is_discarded() || !m.is_object()) throw std::runtime_error(path.string() + ": not JSON");
  if (m.value("lanemap_projection", 0) != kProjectionFormat) {
    throw std::runtime_error(path.string() + ": projection format " + m.value("lanemap_projection", nlohmann::json(nullptr)).dump() +
                             ", this lanemap reads " + std::to_string(kProjectionFormat) + ": project the drive again");
  }
  return m;
}

// --drive-offsets: each projected drive's offset (core/bev/drive_offsets.h), solved over every road
// two or more of the drives saw (a drive's traversals of a road merged, its open road included).
bev::DriveOffsets solveDriveOffsets(const std::vector<std::string>& dirs, const std::vector<nlohmann::json>& manifests) {
  std::map<int64_t, std::map<size_t, std::vector<std::string>>> files;  // road -> drive -> grid files
  for (size_t d = 0; d < manifests.size(); ++d) {
    for (const auto& c : manifests[d].at("closed")) {
      files[c.at("road_id").get<int64_t>()][d].push_back((fs::path(dirs[d]) / c.at("file").get<std::string>()).string());
    }
    if (const auto& open = manifests[d].at("open"); !open.is_null()) {
      files[open.at("road_id").get<int64_t>()][d].push_back((fs::path(dirs[d]) / open.at("file").get<std::string>()).string());
    }
  }
  bev::DriveOffsetSolver solver(manifests.size());
  for (const auto& [road, by_drive] : files) {
    if (by_drive.size() < 2) continue;
    std::vector<bev::BevGrid> grids;  // one per drive, loaded for this road only
    grids.reserve(by_drive.size());
    for (const auto& [d, paths] : by_drive) {
      grids.emplace_back();
      for (const auto& p : paths) bev::mergeGrid(bev::BevGrid::load(p), grids.back());
    }
    std::vector<std::pair<size_t, const bev::BevGrid*>> in;
    size_t k = 0;
    for (const auto& [d, paths] : by_drive) in.push_back({d, &grids[k++]});
    solver.addRoad(in);
  }
  return solver.solve();
}

// Folders as one spelling (absolute, normalised), so a file naming them can be checked against
// the command line that reads it.
std::vector<std::string> canonicalPaths(const std::vector<std::string>& dirs) {
  std::vector<std::string> out;
  for (const auto& d : dirs) out.push_back(fs::weakly_canonical(fs::absolute(d)).string());
  return out;
}

// --offsets-out / --offsets-in: the drives' solved offsets, named by the traversals they were
// solved over (a file solved over other drives is refused).
void writeDriveOffsets(const std::string& path, const std::vector<std::string>& traversals, const bev::DriveOffsets& off) {
  nlohmann::json j = {{"traversals", canonicalPaths(traversals)}, {"offset_m", nlohmann::json::array()},
                      {"measurements", off.measurements}, {"component", off.component}};
  for (const auto& v : off.offset_m) j["offset_m"].push_back({v.x(), v.y()});
  io::writeFileAtomically(path, j.dump(1) + "\n");
}
bev::DriveOffsets readDriveOffsets(const std::string& path, const std::vector<std::string>& traversals) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the drives' offsets " + path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.contains("traversals") || !j.contains("offset_m")) {
    throw std::runtime_error(path + " is not a file of drive offsets (lanemap-offline --offsets-out)");
  }
  if (j.at("traversals").get<std::vector<std::string>>() != canonicalPaths(traversals)) {
    throw std::runtime_error(path + " holds the offsets of other drives than these --traversals");
  }
  bev::DriveOffsets off;
  for (const auto& v : j.at("offset_m")) off.offset_m.emplace_back(v.at(0).get<double>(), v.at(1).get<double>());
  off.measurements = j.at("measurements").get<std::vector<int>>();
  off.component = j.at("component").get<std::vector<int>>();
  return off;
}

// Entries with a "road_id" (summary.json's roads, merges, partial roads) in road order, each
// road's entries in their order: a sharded fusion's summary, whatever the shards' order.
void sortByRoad(nlohmann::json& entries) {
  std::stable_sort(entries.begin(), entries.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
    return a.at("road_id").get<int64_t>() < b.at("road_id").get<int64_t>();
  });
}

// "K/N" with 0 <= K < N.
std::pair<int, int> parseShard(const std::string& text) {
  int k = -1, n = 0;
  char slash = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d %c %d %c", &k, &slash, &n, &extra) != 3 || slash != '/' || n < 1 || k < 0 || k >= n) {
    throw std::runtime_error("--shard takes K/N with 0 <= K < N (e.g. 0/4), not '" + text + "'");
  }
  return {k, n};
}

// --assemble: each shard folder's shard.json, checked: shards of these traversals, K/N of one N,
// every K once.
std::vector<std::pair<std::string, nlohmann::json>> readShards(const std::vector<std::string>& dirs,
                                                               const std::vector<std::string>& traversals) {
  std::vector<std::pair<std::string, nlohmann::json>> out;
  std::set<int> ks;
  int n_all = 0;
  for (const auto& dir : dirs) {
    std::ifstream in(fs::path(dir) / "shard.json");
    const nlohmann::json j = in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
    if (j.is_discarded() || !j.is_object() || !j.contains("shard")) {
      throw std::runtime_error(dir + " holds no finished shard (its shard.json is written last, by lanemap-offline --shard)");
    }
    if (j.at("traversals").get<std::vector<std::string>>() != canonicalPaths(traversals)) {
      throw std::runtime_error(dir + " is a shard of other drives than these --traversals");
    }
    const auto [k, n] = parseShard(j.at("shard").get<std::string>());
    if (n_all != 0 && n != n_all) throw std::runtime_error(dir + " is shard " + std::to_string(k) + " of " + std::to_string(n) + ", not of " + std::to_string(n_all));
    n_all = n;
    if (!ks.insert(k).second) throw std::runtime_error(dir + ": shard " + std::to_string(k) + " is given twice");
    out.emplace_back(dir, j);
  }
  for (int k = 0; k < n_all; ++k) {
    if (!ks.count(k)) throw std::runtime_error("shard " + std::to_string(k) + "/" + std::to_string(n_all) + " is missing: its roads would be lost");
  }
  return out;
}

class OfflineMapper {
 public:
  OfflineMapper(const Options& o, const OfflineConfig& c, const skeleton::Skeleton& sk,
                const std::vector<osm::Restriction>& restrictions, std::unique_ptr<seg::Segmenter> model)
      : o_(o), c_(c), model_(std::move(model)), sk_(sk), explorer_(c.lanes.explorerOptions()),
        assembler_(sk, c.lanes.intersections, restrictions) {
    for (const auto& r : sk.roads()) {
      for (const auto& p : r.polyline) network_box_.extend(p);
    }
    startDrive();
  }

  // Each drive (log) gets its own road tracker and BEV builder; the roads' evidence and lanes carry
  // over. A road's BEV from this drive is merged unaligned within the drive (one pose error) and,
  // when the road closes, merged aligned into what the earlier drives gave (bev::mergeAligned).
  void startDrive() {
    tracker_ = std::make_unique<tracking::RoadTracker>(sk_, c_.tracker.tracker);
    passages_ = tracking::PassageRecorder{};
    last_position_.reset();
    reach_ = DriveReach{};
    builder_ = std::make_unique<bev::BevBuilder>(sk_, c_.vehicle.camera, bevOptions(o_, c_));
    drive_log_ = nlohmann::json::array();
  }
  // After finish(): this drive's roads join the earlier drives' evidence. Returns the drive's
  // alignments (one per road merged onto earlier drives).
  nlohmann::json endDrive() {
    const auto s = builder_->stats();
    frames_projected_ += s.frames_projected;
    frames_mesh_ += s.frames_mesh;
    // Every road this drive closed: its saved file is now the earlier drives' evidence.
    for (int64_t id : fused_) {
      prior_.erase(id);
      prior_saved_.insert(id);
      ++traversals_[id];
    }
    for (int64_t id : drive_saved_) {
      prior_saved_.insert(id);
      ++traversals_[id];
    }
    drive_grids_.clear();
    drive_saved_.clear();
    fused_.clear();
    ++drives_;
    return std::move(drive_log_);
  }

  void onEvent(const lcm::LogEvent& ev) {
    if (ev.channel == channels::kPose) {
      pose_t m;
      if (decode(ev, m)) onPose(m);
    } else if (!model_ && ev.channel == o_.semantic_channel) {
      label_image_t m;
      if (decode(ev, m)) builder_->addEncodedFrame(m.utime, static_cast<bev::LabelEncoding>(m.encoding), m.data, m.width, m.height);
    } else if (model_ && ev.channel == channels::kCameraFront) {
      image_t m;
      if (!decode(ev, m)) {
        ++frames_failed_;
        return;
      }
      try {
        builder_->addFrame(m.utime, model_->segment(seg::decodeFrame(m.pixelformat, m.width, m.height, m.row_stride,
                                                                     m.data.data(), m.data.size())));
        ++frames_segmented_;
      } catch (const seg::FrameError& e) {
        if (frames_failed_++ < 10) std::fprintf(stderr, "lanemap-offline: camera frame %lld skipped: %s\n", static_cast<long long>(m.seq), e.what());
      }
    } else if (ev.channel == channels::kLidarPackets && !o_.no_lidar) {
      lidar_packets_t m;
      if (decode(ev, m)) builder_->addSweep(bev::SweepData{m.utime, m.packet_utime, m.data});
    }
    mapClosedRoads();
  }

  // End of the drive's log: roads still closing are handed over, and the road being driven is
  // mapped as far as it was driven.
  void finish() {
    builder_->finish();
    mapClosedRoads();
    mapPartialRoad();
  }

  // --project-only: what the drive's BEV builder hands over goes to `p`, nothing is mapped.
  void projectInto(DriveProjection* p) { projection_ = p; }

  // --shard K/N: only the roads with id % N == K are fused and explored, each on its own evidence
  // (no lanes carried in from a neighbour: those may be another shard's); writeShard() then keeps
  // them for --assemble, which carries lanes into the short roads left with none and builds the
  // junctions. A road's evidence is fused from its own traversals only, so every shard fuses its
  // roads exactly as one process fusing all of them would.
  void setShard(int k, int n) {
    shard_k_ = k;
    shard_n_ = n;
  }
  bool inShard(int64_t road_id) const { return shard_n_ <= 0 || ((road_id % shard_n_) + shard_n_) % shard_n_ == shard_k_; }

  // The shard's roads into `dir` (the --out folder, whose bev/ already holds their grids):
  // roads/road_<id>.json (core/io/lane_map_json.h, lossless: the lanes and the crosswalks the
  // road's BEV showed) and shard.json (what the summary takes from each road, and the short roads left
  // with no lane, for --assemble to carry lanes into).
  void writeShard(const std::string& dir, nlohmann::json header, const nlohmann::json& drives) const {
    const fs::path roads = fs::path(dir) / "roads";
    fs::create_directories(roads);
    for (const auto& [id, lanes] : assembler_.roads()) {
      map::LaneMap m = lanes;
      if (auto c = crosswalks_.find(id); c != crosswalks_.end()) m.crosswalks = c->second;
      io::writeLaneMapJson(m, (roads / ("road_" + std::to_string(id) + ".json")).string());
    }
    nlohmann::json awaiting = nlohmann::json::array();
    for (const auto& [id, g] : awaiting_) awaiting.push_back(id);
    header["roads"] = road_log_;
    header["roads_mapped"] = roads_mapped_;
    header["roads_failed"] = roads_failed_;
    header["partial_not_mapped"] = partial_not_mapped_;
    header["awaiting_lanes"] = awaiting;
    nlohmann::json passages = nlohmann::json::array();
    for (const auto& p : assembler_.passages()) passages.push_back(io::passageToJson(p));
    header["passages"] = passages;
    header["drives"] = drives;
    io::writeFileAtomically((fs::path(dir) / "shard.json").string(), header.dump(1) + "\n");
  }

  // --assemble: one shard's roads (writeShard's folder) into this map; its grids move into this
  // map's bev/. Returns the shard's drives (each drive's merges of the shard's roads).
  nlohmann::json takeShard(const std::string& dir, const nlohmann::json& shard) {
    for (const auto& [id, path] : bev::roadFiles((fs::path(dir) / "roads").string(), ".json")) {
      map::LaneMap lanes = io::readLaneMapJson(path);
      crosswalks_[id] = std::move(lanes.crosswalks);
      lanes.crosswalks.clear();
      assembler_.setRoad(id, std::move(lanes));
    }
    for (const char* sub : {"bev", "bev/partial"}) {
      const fs::path from = fs::path(dir) / sub, to = fs::path(o_.out) / sub;
      if (!fs::is_directory(from)) continue;
      fs::create_directories(to);
      for (const auto& e : fs::directory_iterator(from)) {
        if (e.is_regular_file()) fs::rename(e.path(), to / e.path().filename());
      }
    }
    for (const auto& e : shard.at("roads")) road_log_.push_back(e);
    for (const auto& e : shard.at("partial_not_mapped")) partial_not_mapped_.push_back(e);
    roads_mapped_ += shard.at("roads_mapped").get<int>();
    roads_failed_ += shard.at("roads_failed").get<int>();
    if (shard.contains("passages")) {
      for (const auto& p : shard.at("passages")) assembler_.addPassage(io::passageFromJson(p));
    }
    for (const auto& id : shard.at("awaiting_lanes")) {
      awaiting_.insert_or_assign(id.get<int64_t>(), bev::BevGrid::load(bev::roadGridPath(o_.out, id.get<int64_t>())));
    }
    return shard.at("drives");
  }

  // --assemble, after every shard: the road log in road order, and the short roads the shards
  // left with no lane mapped again now that every road's lanes are known (in road order; one that
  // takes lanes gives them on to the roads awaiting it, as in one process).
  void finishAssembly(int last_drive) {
    drives_ = std::max(0, last_drive);  // what the roads mapped again now are mapped on
    sortByRoad(road_log_);
    sortByRoad(partial_not_mapped_);
    std::vector<int64_t> ids;
    for (const auto& [id, g] : awaiting_) ids.push_back(id);
    for (int64_t id : ids) {
      auto it = awaiting_.find(id);
      if (it == awaiting_.end()) continue;  // given lanes by one mapped before it
      const bev::BevGrid g = it->second;
      exploreAndSet(id, g, std::nullopt, true);
    }
  }
  // A projection's frame counts alone (--assemble: the shards fused its roads).
  void countProjection(const nlohmann::json& m) {
    frames_projected_ += m.value("frames_projected", int64_t{0});
    frames_mesh_ += m.value("frames_mesh", int64_t{0});
    frames_segmented_ += m.value("frames_segmented", int64_t{0});
    frames_failed_ += m.value("frames_failed", int64_t{0});
  }
  // --traversals: one drive's projection, mapped as its log would have been; with --drive-offsets
  // every grid first moved by -offset_m (whole cells: the drive's offset undone).
  void mapProjection(const std::string& dir, const nlohmann::json& m, const Eigen::Vector2d& offset_m = Eigen::Vector2d::Zero()) {
    Eigen::Vector2d moved = Eigen::Vector2d::Zero();
    auto traversal = [&](const nlohmann::json& entry) {  // {"road_id", "file"}
      bev::RoadBev road;
      road.road_id = entry.at("road_id").get<int64_t>();
      road.grid = bev::BevGrid::load((fs::path(dir) / entry.at("file").get<std::string>()).string());
      const Eigen::Vector2i cells = bev::correctionCells(offset_m, road.grid.resolution());
      if (cells != Eigen::Vector2i::Zero()) road.grid = bev::shiftedGrid(road.grid, cells);
      moved = cells.cast<double>() * road.grid.resolution();
      return road;
    };
    for (const auto& c : m.at("closed")) {
      if (inShard(c.at("road_id").get<int64_t>())) mapTraversal(traversal(c));
    }
    // The car's paths through intersections (a shard keeps those leaving its roads for the
    // assembly, which builds the junctions). Not moved by the drive's offset: a path is matched
    // to the lane ends it passes, and its offset from them there is taken off.
    if (m.contains("passages")) {
      for (const auto& p : m.at("passages")) {
        if (inShard(p.at("from_road").get<int64_t>())) assembler_.addPassage(io::passageFromJson(p));
      }
    }
    if (const auto& open = m.at("open"); !open.is_null() && inShard(open.at("road_id").get<int64_t>())) {
      const auto& p = open.at("last_position");
      const bev::RoadBev road = traversal(open);
      mapOpenRoad(road, Eigen::Vector2d(p.at(0).get<double>(), p.at(1).get<double>()) + moved);
    }
    frames_projected_ += m.value("frames_projected", int64_t{0});
    frames_mesh_ += m.value("frames_mesh", int64_t{0});
    frames_segmented_ += m.value("frames_segmented", int64_t{0});
    frames_failed_ += m.value("frames_failed", int64_t{0});
  }
  // Why this drive (after finish()) cannot have mapped anything of the OSM data, or nothing: no
  // pose at all, or none within kNearRoadM of a road (a drive of another area, or the wrong --osm).
  std::optional<std::string> offTheNetwork() const {
    if (reach_.poses == 0) return "the log holds no usable " + std::string(channels::kPose) + " message (the car's position)";
    if (reach_.near_road) return std::nullopt;
    char where[96];
    if (reach_.nearest_box_m > 0.0) {
      std::snprintf(where, sizeof where, "the nearest is %.1f km from the area its roads cover", reach_.nearest_box_m / 1000.0);
    } else {
      std::snprintf(where, sizeof where, "some lie within the area its roads cover, off its roads");
    }
    char what[384];
    std::snprintf(what, sizeof what,
                  "none of the drive's %lld poses comes within %.0f m of a road of the OSM data (%s): a drive of another "
                  "area, or the wrong --osm?",
                  static_cast<long long>(reach_.poses), kNearRoadM, where);
    return std::string(what);
  }

  // This drive's frames (a projection's figures): its BEV builder's, before endDrive().
  nlohmann::json driveFrames() const {
    const auto s = builder_->stats();
    return {{"frames_projected", s.frames_projected}, {"frames_mesh", s.frames_mesh}};
  }

  mapping::MapAssembler& assembler() { return assembler_; }
  int roadsMapped() const { return roads_mapped_; }
  int64_t framesSegmented() const { return frames_segmented_; }
  int64_t framesFailed() const { return frames_failed_; }
  // Per road explored: lanes found, or why it failed.
  const nlohmann::json& roadLog() const { return road_log_; }
  // Roads a drive ended on too early to map (under min_lane_length_m past their start), with why.
  const nlohmann::json& partialNotMapped() const { return partial_not_mapped_; }
  int roadsFailed() const { return roads_failed_; }
  int64_t framesProjected() const { return frames_projected_; }
  int64_t framesMesh() const { return frames_mesh_; }

 private:
  static bev::BevBuilderOptions bevOptions(const Options& o, const OfflineConfig& c) {
    bev::BevBuilderOptions b = c.bev.options;
    // Meshes on a second core; the caller waits for the worker rather than drop a sweep, and a
    // frame's mesh is chosen by time: the same map as building them in this thread (tested).
    b.async_mesh = !o.mesh_in_main_thread;
    b.offline_pipeline = true;
    b.use_lidar = b.use_lidar && !o.no_lidar;
    if (b.use_lidar) b.lidar_to_vehicle = c.vehicle.lidarToVehicle();
    return b;
  }

  void onPose(const pose_t& m) {
    const EnuPose p = toEnuPose(m, sk_.frame());
    if (p.position.allFinite()) {
      last_position_ = p.position.head<2>();
      ++reach_.poses;
      if (!reach_.near_road) {  // one pose near a road is enough: no query per pose after it
        const double from_box = network_box_.exteriorDistance(*last_position_);
        reach_.near_road = from_box <= kNearRoadM && !sk_.nearestRoads(*last_position_, kNearRoadM).empty();
        reach_.nearest_box_m = std::min(reach_.nearest_box_m, from_box);
      }
    }
    builder_->addPose(toTimedPose(p));
    passages_.addPosition(p.position.head<2>());
    for (const auto& e : tracker_->update(toPoseInput(p))) {
      if (auto passage = passages_.onEvent(e)) {
        if (projection_) {
          projection_->passage(*passage);
        } else {
          assembler_.addPassage(std::move(*passage));
        }
      }
      switch (e.type) {
        case tracking::RoadEventType::kEnteredRoad: builder_->roadEntered(e.road_id, e.utime); break;
        case tracking::RoadEventType::kReachedIntersection: builder_->roadClosed(e.road_id, e.utime); break;
        case tracking::RoadEventType::kLeftMap:
        case tracking::RoadEventType::kPoseLost: builder_->roadsAbandoned(e.utime); break;
        default: break;
      }
    }
  }

  void mapClosedRoads() {
    for (auto& road : builder_->takeClosed()) {
      if (projection_) {
        projection_->closed(road);
      } else {
        mapTraversal(road);
      }
    }
  }

  // A traversal of a road that is (now) complete: this drive's evidence of the road accumulates,
  // it is aligned onto the earlier drives' (an earlier drive's partial evidence of the road
  // included: the road is complete now), and the road is explored again on everything seen.
  //
  // Memory: the grids of closed roads live in their files (bev/road_<id>.bev, what the road was
  // explored on), not in memory: a road's file is read back when the road is driven again. Kept in
  // memory are only the grids of roads that this drive and an earlier one both closed (this
  // drive's own evidence and the earlier drives', to fuse again; the file holds the fused grid).
  void mapTraversal(const bev::RoadBev& road) {
    const int64_t id = road.road_id;
    const std::string path = bev::roadGridPath(o_.out, id);
    if (drive_saved_.erase(id)) drive_grids_.emplace(id, bev::BevGrid::load(path));  // closed before in this drive
    auto [it, fresh] = drive_grids_.try_emplace(id, road.grid);
    if (!fresh) bev::mergeGrid(road.grid, it->second);
    bool completed_partial = false;
    if (prior_saved_.erase(id)) prior_.emplace(id, bev::BevGrid::load(path));  // the file becomes the fused grid below
    if (auto p = partial_.find(road.road_id); p != partial_.end() && !prior_.count(road.road_id)) {
      prior_[road.road_id] = std::move(p->second.grid);  // an earlier drive ended on it: its evidence, aligned below
      traversals_[road.road_id] = p->second.traversals;
      partial_.erase(p);
      std::error_code ec;
      fs::remove(bev::partialGridPath(o_.out, road.road_id), ec);
      completed_partial = true;
    }
    if (const auto prior = prior_.find(road.road_id); prior != prior_.end()) {  // driven in an earlier drive
      bev::BevGrid fused = prior->second;
      const bev::Alignment a = bev::mergeAligned(it->second, fused, !o_.no_align, alignOptions());
      drive_log_.push_back({{"road_id", road.road_id}, {"traversals_before", traversals_[road.road_id]},
                            {"aligned", a.ok}, {"shift_m", {a.shift_m.x(), a.shift_m.y()}},
                            {"rotation_deg", a.rotation_rad * 180.0 / M_PI}, {"correlation", a.correlation},
                            {"overlap_cells", a.overlap_cells}, {"why", a.why},
                            {"completed_partial", completed_partial}});
      fused.save(path);
      fused_.insert(id);
      exploreAndSet(id, fused, std::nullopt);
      return;
    }
    it->second.save(path);
    exploreAndSet(id, it->second, std::nullopt);
    drive_grids_.erase(it);  // this drive's evidence is the file's
    drive_saved_.insert(id);
  }

  bev::AlignOptions alignOptions() const {
    bev::AlignOptions a;
    if (o_.align_rotation) a.max_rotation_deg = bev::AlignOptions::kRotationSearchDeg;
    return a;
  }

  // After the log: the road the car is on (opened, never closed) explored as far as the last pose.
  // A road complete already (this drive or an earlier one closed it) takes the traversal as any
  // other; otherwise the road is partial: its evidence (with an earlier drive's partial evidence of
  // it, aligned) waits in partial_ for a drive that closes it.
  void mapPartialRoad() {
    std::optional<bev::RoadBev> open;
    builder_->withOpenRoad([&](const bev::RoadBev& r) {
      if (r.grid.frames() > 0) open = r;  // a copy
    });
    if (!open || !last_position_) return;
    if (projection_) {
      projection_->open(*open, *last_position_);
      return;
    }
    mapOpenRoad(*open, *last_position_);
  }

  // The road a drive ended on, with the drive's last position (mapPartialRoad, or a projection).
  void mapOpenRoad(const bev::RoadBev& open, const Eigen::Vector2d& last_position) {
    const auto* r = sk_.road(open.road_id);
    if (!r) return;
    if (drive_grids_.count(r->id) || drive_saved_.count(r->id) || prior_.count(r->id) || prior_saved_.count(r->id)) {
      mapTraversal(open);
      return;
    }
    const double station = mapping::roadStation(*r, last_position, explorer_);
    auto [it, fresh] = partial_.try_emplace(r->id, Partial{open.grid, station, 1});
    if (!fresh) {  // another drive ended on it too
      const bev::Alignment a = bev::mergeAligned(open.grid, it->second.grid, !o_.no_align, alignOptions());
      drive_log_.push_back({{"road_id", r->id}, {"traversals_before", it->second.traversals}, {"aligned", a.ok},
                            {"shift_m", {a.shift_m.x(), a.shift_m.y()}}, {"rotation_deg", a.rotation_rad * 180.0 / M_PI},
                            {"correlation", a.correlation},
                            {"overlap_cells", a.overlap_cells}, {"why", a.why}, {"partial", true}});
      it->second.station_m = std::max(it->second.station_m, station);
      ++it->second.traversals;
    }
    fs::create_directories(fs::path(bev::partialGridPath(o_.out, r->id)).parent_path());
    it->second.grid.save(bev::partialGridPath(o_.out, r->id));
    exploreAndSet(r->id, it->second.grid,
                  map::PartialRoad{it->second.station_m, mapping::roadFrameLength(*r, explorer_)});
  }

  // Explores one road's evidence (as far as partial->station_m when given) and sets its lanes.
  // A short road left with no lane waits (awaiting_) for a road meeting it to get lanes, and is
  // mapped again then (`again`: its summary entry replaced, not counted twice).
  void exploreAndSet(int64_t road_id, const bev::BevGrid& grid, const std::optional<map::PartialRoad>& partial, bool again = false) {
    const auto* r = sk_.road(road_id);
    if (!r) return;
    nlohmann::json entry = {{"road_id", road_id}, {"from", r->from}, {"to", r->to}, {"drive", drives_}};
    bool has_lanes = false;
    if (partial) entry["partial"] = {{"station_m", partial->station_m}, {"road_length_m", partial->road_length_m}};
    try {
      const auto geometry = partial ? mapping::drivenStretch(*r, partial->station_m, explorer_) : lanes::RoadGeometry::fromSkeleton(*r);
      int64_t before = -1;
      // (A shard carries nothing: the roads meeting this one may be another shard's.)
      const auto carried = shard_n_ > 0 ? std::vector<lanes::CarriedLane>{}
                                        : mapping::lanesRunningThrough(sk_, *r, assembler_.roads(), explorer_, &before);
      auto [res, lanes_of_road, dropped, carried_in, apart, carried_added] =
          mapping::exploreRoadLanes(grid, geometry, partial, explorer_, sk_.frame().origin(), carried);
      if (apart > 0) entry["lanes_apart_from_carried"] = apart;
      if (carried_added > 0) entry["lanes_added_from_carried"] = carried_added;
      // Lanes from the road's own OSM way stand in until a road meeting it gets lanes to carry.
      const bool from_osm_way = carried_in && before == road_id;
      if (carried_in) entry[from_osm_way ? "lanes_from_osm_way" : "lanes_carried_from"] = from_osm_way ? nlohmann::json(true) : nlohmann::json(before);
      for (const auto& why : dropped) std::fprintf(stderr, "\rlanemap-offline: road %lld: lanelet left out, %s\n", static_cast<long long>(road_id), why.c_str());
      if (!dropped.empty()) entry["lanes_dropped"] = dropped;
      crosswalks_[road_id] = lanes::findCrosswalks(grid, lanes_of_road, 1);
      assembler_.setRoad(road_id, std::move(lanes_of_road));
      has_lanes = !res.lanes.empty() && !from_osm_way;
      if (!partial && !has_lanes && mapping::isShortRoad(*r, explorer_)) {
        awaiting_.insert_or_assign(road_id, grid);
      } else {
        awaiting_.erase(road_id);
      }
      if (!again) ++roads_mapped_;
      entry["lanes"] = res.lanes.size();
      if (!o_.quiet) {
        std::fprintf(stderr, "\rlanemap-offline: road %lld: %zu lanes%s%20s\n", static_cast<long long>(road_id), res.lanes.size(),
                     partial ? (" (partial, to " + std::to_string(static_cast<int>(partial->station_m)) + " m of " +
                                std::to_string(static_cast<int>(partial->road_length_m)) + " m)").c_str() : "", "");
      }
    } catch (const lanes::LanesError& e) {
      if (!partial) return fail(road_id, entry, e);
      // Too little of it driven: not mapped, and said; an earlier drive's lanes of it stay.
      partial_not_mapped_.push_back({{"road_id", road_id}, {"why", e.what()}});
      return;
    } catch (const std::exception& e) {
      return fail(road_id, entry, e);
    }
    auto logged = std::find_if(road_log_.rbegin(), road_log_.rend(), [&](const nlohmann::json& e) { return e.at("road_id") == road_id; });
    if (again && logged != road_log_.rend()) {
      *logged = std::move(entry);
    } else {
      road_log_.push_back(std::move(entry));
    }
    if (!has_lanes || shard_n_ > 0) return;
    std::set<int64_t> awaiting;
    for (const auto& [id, g] : awaiting_) awaiting.insert(id);
    for (int64_t id : mapping::roadsAwaitingLanesFrom(sk_, road_id, awaiting)) {
      auto it = awaiting_.find(id);
      if (it == awaiting_.end()) continue;  // given lanes by one mapped again before it
      const bev::BevGrid g = it->second;
      exploreAndSet(id, g, std::nullopt, true);
    }
  }

  void fail(int64_t road_id, nlohmann::json& entry, const std::exception& e) {
    // The road keeps its BEV (bev/road_<id>.bev) and its previous lanes, if any.
    ++roads_failed_;
    entry["error"] = e.what();
    std::fprintf(stderr, "\rlanemap-offline: road %lld failed, the rest is mapped: %s\n", static_cast<long long>(road_id), e.what());
    road_log_.push_back(std::move(entry));
  }

  const Options& o_;
  const OfflineConfig& c_;
  std::unique_ptr<seg::Segmenter> model_;  // null: labels from o_.semantic_channel
  const skeleton::Skeleton& sk_;
  std::unique_ptr<tracking::RoadTracker> tracker_;  // this drive's
  tracking::PassageRecorder passages_;              // this drive's paths through intersections
  std::unique_ptr<bev::BevBuilder> builder_;        // this drive's
  lanes::ExplorerOptions explorer_;
  mapping::MapAssembler assembler_;
  // The evidence per road (see mapTraversal): in memory, or the road's saved file.
  std::map<int64_t, bev::BevGrid> drive_grids_;  // this drive's, of roads earlier drives closed too
  std::set<int64_t> drive_saved_;                // this drive's, of the other roads it closed: the file
  std::map<int64_t, bev::BevGrid> prior_;        // the earlier drives' (fused), of roads this drive closed too
  std::set<int64_t> prior_saved_;                // the earlier drives' (fused), of the other roads: the file
  std::map<int64_t, int> traversals_;            // drives in the earlier evidence per road
  std::set<int64_t> fused_;                      // roads in both, the earlier evidence + this drive's aligned: the file
  struct Partial {
    bev::BevGrid grid;       // the evidence of the drives that ended on it (aligned)
    double station_m = 0.0;  // the furthest any of them reached
    int traversals = 0;
  };
  std::map<int64_t, Partial> partial_;            // roads drives ended on, none closed yet
  std::optional<Eigen::Vector2d> last_position_;  // this drive's newest pose (ENU)
  // Whether this drive came near the OSM data's roads at all (offTheNetwork).
  static constexpr double kNearRoadM = 50.0;
  struct DriveReach {
    int64_t poses = 0;
    bool near_road = false;  // a pose came within kNearRoadM of a road
    double nearest_box_m = std::numeric_limits<double>::infinity();  // of the poses, from network_box_
  };
  DriveReach reach_;
  Eigen::AlignedBox2d network_box_;  // every road polyline point
  DriveProjection* projection_ = nullptr;         // --project-only: the drive's traversals go there
  int shard_k_ = 0, shard_n_ = 0;                 // --shard K/N (n 0: every road)
  nlohmann::json partial_not_mapped_ = nlohmann::json::array();
  nlohmann::json drive_log_ = nlohmann::json::array();
  int drives_ = 0;
  int64_t frames_projected_ = 0, frames_mesh_ = 0;
  std::map<int64_t, std::vector<map::Crosswalk>> crosswalks_;  // by road, from its BEV
  std::map<int64_t, bev::BevGrid> awaiting_;  // short roads mapped with no lane, their evidence (exploreAndSet)

 public:
  std::vector<map::Crosswalk> crosswalks() const {
    std::vector<map::Crosswalk> all;
    for (const auto& [id, c] : crosswalks_) all.insert(all.end(), c.begin(), c.end());
    return all;
  }

 private:
  int roads_mapped_ = 0, roads_failed_ = 0;
  int64_t frames_segmented_ = 0, frames_failed_ = 0;
  nlohmann::json road_log_ = nlohmann::json::array();
};

// The configured segmentation model (config/segmenter.yaml's model block, --model overriding its
// path), as lanemap-segmenter loads it.
std::unique_ptr<seg::Segmenter> loadModel(const Options& o) {
  const SegmenterSettings s = SegmenterSettings::fromYamlFile(o.segmenter_config, o.model);
  if (s.threads > 0) cv::setNumThreads(s.threads);
  if (!s.model) throw std::runtime_error(o.segmenter_config + ": no model block (give --model FILE.onnx)");
  return std::make_unique<seg::Segmenter>(*s.model);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"Maps a recorded drive offline: the live graph's core stages on an LCM log, as fast as the CPU allows.\n"
               "Several --log: drives of one area mapped in that order into one map; a road driven in an earlier\n"
               "drive gets the new drive's BEV aligned to its evidence (core/bev/bev_align.h) and is explored again."};
  auto* logs = app.add_option("--log", o.logs, "LCM log of the drive (lanemap-sim's drive.lcmlog or an lcm-logger recording); repeatable");
  auto* traversals = app.add_option("--traversals", o.traversals,
                 "a drive projected before with --project-only (its folder), mapped in place of its log; repeatable, "
                 "in the order the drives are to be fused (lanemap-city)")->excludes(logs);
  app.add_option("--project-only", o.project_only,
                 "project the one --log drive and save what it hands over per road into this folder (grids and "
                 "projection.json), without mapping (lanemap-city's first stage; --out gets nothing)")->needs(logs)->excludes(traversals);
  app.add_flag("--no-align", o.no_align, "merge later drives' BEV as it comes, unaligned (shows the blur alignment removes)");
  app.add_flag("--align-rotation", o.align_rotation,
               "align later drives' BEV by a shift and a small rotation (up to 0.5 degrees; core/bev/bev_align.h), "
               "not by a shift only")
      ->excludes("--no-align");
  app.add_flag("--drive-offsets", o.drive_offsets,
               "--traversals: first solve each drive's own pose offset over the roads drives share and undo it in all "
               "its roads, those driven once too (core/bev/drive_offsets.h)")->needs(traversals)->excludes("--no-align");
  app.add_option("--offsets-out", o.offsets_out,
                 "with --drive-offsets: write the solved offsets to this JSON file and stop (a sharded fusion's first "
                 "step, lanemap-city --shards)")->needs("--drive-offsets");
  app.add_option("--offsets-in", o.offsets_in,
                 "--traversals: undo the drives' offsets read from this file (--offsets-out of the same traversals), "
                 "not solved again")->needs(traversals)->excludes("--drive-offsets")->excludes("--no-align");
  app.add_option("--shard", o.shard,
                 "K/N: fuse and explore only the roads whose id is K modulo N, into --out's bev/, roads/ and shard.json "
                 "(no junctions, no map: --assemble builds them from every shard)")->needs(traversals);
  app.add_option("--assemble", o.assemble,
                 "the folders of every --shard K/N run of these --traversals (repeatable): their roads into one map in "
                 "--out, the short roads left with no lane given their neighbours' lanes, the junctions built")
      ->needs(traversals)->excludes("--shard")->excludes("--drive-offsets");
  app.add_option("--osm", o.osm, "road-level OSM file of the area (.osm or .osm.pbf)")->required();
  auto* out = app.add_option("--out", o.out, "output folder (created): map.osm, map.geojson, map.png, summary.json, bev/");
  auto* oracle = app.add_flag("--oracle", o.oracle, "map on the simulator's truth labels (SEMANTIC_FRONT_TRUTH), no model");
  app.add_option("--semantic-channel", o.semantic_channel,
                 "map on the labels of this channel of the log (e.g. SEMANTIC_FRONT from lanemap-segmenter --log-out), no model")
      ->excludes(oracle);
  app.add_option("--segmenter-config", o.segmenter_config, "segmentation model config (its model block)")->capture_default_str();
  app.add_option("--model", o.model, "ONNX model, instead of the segmenter config's model.path");
  app.add_flag("--no-lidar", o.no_lidar, "no LIDAR mesh: project on the flat plane under the car (or the road's crown, with the BEV config's projection.crown_slope > 0)");
  app.add_flag("--mesh-in-main-thread", o.mesh_in_main_thread,
               "build the LIDAR meshes in the main thread (one core; the same map, slower)");
  app.add_option("--autoware", o.autoware,
                 "also write the map in Autoware's layout into this folder (lanelet2_map.osm with turn_direction and "
                 "stop-line road_marking elements, map_projector_info.yaml)");
  app.add_option("--vehicle", o.vehicle, "camera and LIDAR calibration")->capture_default_str();
  app.add_option("--bev-config", o.bev_config, "BEV builder options")->capture_default_str();
  app.add_option("--lanes-config", o.lanes_config, "lane exploration options")->capture_default_str();
  app.add_option("--tracker-config", o.tracker_config, "road tracker options")->capture_default_str();
  app.add_option("--intersections-config", o.intersections_config,
                 "intersection options (default: the file the lanes config names in `intersections:`, as the lane mapper)");
  app.add_option("--map-config", o.map_config,
                 "skeleton options and origin (default: the file the lanes config names in `map:`, as the lane mapper); "
                 "--osm overrides its osm");
  app.add_flag("-q,--quiet", o.quiet, "no progress");
  CLI11_PARSE(app, argc, argv);
  if (o.logs.empty() == o.traversals.empty()) {
    std::cerr << "lanemap-offline: give the drives as --log (one or more) or as --traversals (one or more)\n";
    return 2;
  }
  if (!o.project_only.empty() && o.logs.size() != 1) {
    std::cerr << "lanemap-offline: --project-only projects one drive: give one --log\n";
    return 2;
  }
  if (o.project_only.empty() && o.offsets_out.empty() && !out->count()) {
    std::cerr << "lanemap-offline: --out is required (the map's folder)\n";
    return 2;
  }

  try {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::string* f : {&o.segmenter_config, &o.vehicle, &o.bev_config, &o.lanes_config, &o.tracker_config}) {
      *f = resolveShippedFile(*f);  // a relative name: the current folder, else the shipped configs
    }
    for (const auto& l : o.logs) {
      if (!fs::exists(l)) throw std::runtime_error("no such log file: " + l);
    }
    std::vector<nlohmann::json> projections;  // --traversals: each folder's manifest, read before any work
    for (const auto& t : o.traversals) projections.push_back(readProjection(t));
    if (!o.project_only.empty()) o.out = o.project_only;  // a projection writes only its folder
    const OfflineConfig config = loadConfig(o);
    const osm::OsmData osm_data = osm::readOsm(o.osm);
    const auto sk = skeleton::Skeleton::build(osm_data, config.lanes.map.skeleton);
    if (o.oracle) o.semantic_channel = channels::kSemanticFrontTruth;
    std::unique_ptr<seg::Segmenter> model;
    if (o.semantic_channel.empty() && o.traversals.empty()) model = loadModel(o);
    std::string labels = model ? "model " + model->name() + " on " + channels::kCameraFront : o.semantic_channel;
    if (!projections.empty()) labels = projections.front().value("labels", std::string());
    for (size_t d = 1; d < projections.size(); ++d) {
      if (projections[d].value("labels", std::string()) != labels) {
        throw std::runtime_error(o.traversals[d] + " was projected on other labels (" + projections[d].value("labels", std::string()) +
                                 ") than " + o.traversals.front() + " (" + labels + ")");
      }
    }
    // A projection's road ids are those of the OSM it was projected on: fused on another, wrong.
    for (size_t d = 0; d < projections.size(); ++d) {
      const auto& m = projections[d];
      if (m.value("osm_bytes", int64_t{-1}) != static_cast<int64_t>(fs::file_size(o.osm)) ||
          m.value("atomic_roads", size_t{0}) != sk.roads().size()) {
        throw std::runtime_error(o.traversals[d] + " was projected on another OSM file (" + m.value("osm", std::string("?")) + ", " +
                                 std::to_string(m.value("atomic_roads", size_t{0})) + " atomic roads) than --osm " + o.osm + " (" +
                                 std::to_string(sk.roads().size()) + ")");
      }
    }
    if (o.project_only.empty() && o.offsets_out.empty()) fs::create_directories(fs::path(o.out) / "bev");
    OfflineMapper mapper(o, config, sk, osm_data.restrictions, std::move(model));
    std::optional<DriveProjection> projection;
    if (!o.project_only.empty()) {
      projection.emplace(o.project_only);
      mapper.projectInto(&*projection);
    }
    nlohmann::json log_read = {{"events", 0}, {"bytes", 0}, {"bytes_skipped", 0}, {"bytes_unread", 0}};
    bool damaged = false;
    nlohmann::json drives = nlohmann::json::array();
    int64_t undecodable = 0;
    // --traversals: the drives projected before, fused in the order given.
    std::optional<bev::DriveOffsets> offsets;
    if (o.drive_offsets) offsets = solveDriveOffsets(o.traversals, projections);
    if (!o.offsets_out.empty()) {  // a sharded fusion's first step: the offsets, for every shard
      writeDriveOffsets(o.offsets_out, o.traversals, *offsets);
      std::printf("lanemap-offline: the offsets of %zu drives written to %s\n", o.traversals.size(), o.offsets_out.c_str());
      return 0;
    }
    if (!o.offsets_in.empty()) offsets = readDriveOffsets(o.offsets_in, o.traversals);
    if (!o.shard.empty()) {
      const auto [k, n] = parseShard(o.shard);
      mapper.setShard(k, n);
    }
    // --assemble: every shard's drives (each drive's merges of the shard's roads), by drive.
    std::vector<nlohmann::json> shard_drives(projections.size(), nlohmann::json::array());
    if (!o.assemble.empty()) {
      for (const auto& [dir, shard] : readShards(o.assemble, o.traversals)) {
        const nlohmann::json drives_of_shard = mapper.takeShard(dir, shard);
        for (size_t d = 0; d < projections.size(); ++d) {
          for (const auto& e : drives_of_shard.at(d).at("merged")) shard_drives[d].push_back(e);
        }
      }
      for (auto& merged : shard_drives) sortByRoad(merged);
    }
    for (size_t d = 0; d < projections.size(); ++d) {
      const nlohmann::json& m = projections[d];
      if (!o.assemble.empty()) {
        mapper.countProjection(m);
      } else {
        if (d > 0) mapper.startDrive();
        mapper.mapProjection(o.traversals[d], m, offsets ? offsets->offset_m[d] : Eigen::Vector2d::Zero());
      }
      for (const char* k : {"events", "bytes", "bytes_skipped", "bytes_unread"}) {
        log_read[k] = log_read[k].get<int64_t>() + m.at("log_read").value(k, int64_t{0});
      }
      undecodable += m.at("log_read").value("messages_undecodable", int64_t{0});
      damaged = damaged || m.at("log_read").value("damaged", false);
      drives.push_back({{"log", m.value("log", std::string())},
                        {"merged", o.assemble.empty() ? mapper.endDrive() : std::move(shard_drives[d])}});
      if (offsets) {
        drives.back()["offset_m"] = {offsets->offset_m[d].x(), offsets->offset_m[d].y()};
        drives.back()["offset_measurements"] = offsets->measurements[d];
      }
    }
    for (size_t d = 0; d < o.logs.size(); ++d) {
      const std::string& path = o.logs[d];
      LogReader log(path);  // a damaged log: what is readable is mapped, and said (summary.json "log_read")
      if (d > 0) mapper.startDrive();
      const auto log_size = std::max<uintmax_t>(1, fs::file_size(path));
      const int64_t undecodable_before = g_undecodable;
      int64_t events = 0;
      while (const lcm::LogEvent* ev = log.next()) {
        mapper.onEvent(*ev);
        if (!o.quiet && ++events % 2000 == 0) {
          std::fprintf(stderr, "\rlanemap-offline: %3.0f %% of %s", 100.0 * log.position() / log_size,
                       o.logs.size() > 1 ? ("log " + std::to_string(d + 1) + " of " + std::to_string(o.logs.size())).c_str() : "the log");
        }
      }
      if (log.events() == 0) throw std::runtime_error("not an LCM log, or no whole event in it: " + path + " (" + log.damageReport() + ")");
      if (log.damaged() || g_undecodable > undecodable_before) {
        std::fprintf(stderr, "lanemap-offline: warning: the log is damaged, mapping what could be read (%s): %s; %lld messages did not decode\n",
                     path.c_str(), log.damageReport().c_str(), static_cast<long long>(g_undecodable - undecodable_before));
        damaged = true;
      }
      mapper.finish();
      const auto off = mapper.offTheNetwork();
      if (off) {
        // Nothing of it can be mapped: a projection of it would only fill the store with nothing,
        // and a map of it alone would be empty for a reason "no road was mapped" does not tell.
        if (projection || o.logs.size() == 1) throw std::runtime_error(path + ": " + *off);
        std::fprintf(stderr, "lanemap-offline: warning: %s: %s; the other drives are mapped\n", path.c_str(), off->c_str());
      }
      log_read["events"] = log_read["events"].get<int64_t>() + log.events();
      log_read["bytes"] = log_read["bytes"].get<int64_t>() + log.fileSize();
      log_read["bytes_skipped"] = log_read["bytes_skipped"].get<int64_t>() + log.bytesSkipped();
      log_read["bytes_unread"] = log_read["bytes_unread"].get<int64_t>() + log.bytesUnread();
      if (projection) {  // --project-only: the drive's figures beside its traversals, and done
        nlohmann::json figures = mapper.driveFrames();
        figures["frames_segmented"] = mapper.framesSegmented();
        figures["frames_failed"] = mapper.framesFailed();
        figures["labels"] = labels;
        figures["log"] = path;
        figures["osm"] = fs::absolute(o.osm).string();
        figures["osm_bytes"] = static_cast<int64_t>(fs::file_size(o.osm));
        figures["atomic_roads"] = sk.roads().size();
        figures["log_read"] = log_read;
        figures["log_read"]["messages_undecodable"] = g_undecodable;
        figures["log_read"]["damaged"] = damaged;
        projection->finish(figures);
        std::printf("lanemap-offline: projected %s into %s\n", path.c_str(), o.project_only.c_str());
        return 0;
      }
      drives.push_back({{"log", path}, {"merged", mapper.endDrive()}});
      if (off) drives.back()["not_mapped"] = *off;
    }
    log_read["messages_undecodable"] = g_undecodable + undecodable;
    log_read["damaged"] = damaged;
    if (!o.shard.empty()) {  // --shard: its roads kept for --assemble, no map
      mapper.writeShard(o.out, {{"shard", o.shard}, {"traversals", canonicalPaths(o.traversals)}}, drives);
      std::printf("lanemap-offline: shard %s: %d roads mapped, %d failed, into %s\n", o.shard.c_str(), mapper.roadsMapped(),
                  mapper.roadsFailed(), o.out.c_str());
      return 0;
    }
    if (!o.assemble.empty()) mapper.finishAssembly(static_cast<int>(projections.size()) - 1);
    std::vector<std::string> junction_failures;
    map::LaneMap map = mapper.assembler().map(&junction_failures);
    // Stop signs, give way and traffic lights at the stop lines, from the OSM junction controls.
    intersections::addRegulatoryElements(map, sk, intersections::readControlNodes(o.osm));
    lanes::addCrosswalks(map, mapper.crosswalks());  // the crossings the BEV saw, both directions merged
    for (const auto& f : junction_failures) std::fprintf(stderr, "lanemap-offline: %s failed, the rest is mapped\n", f.c_str());
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string first_log = o.logs.empty() ? projections.front().value("log", std::string()) : o.logs.front();
    nlohmann::json summary = {{"log", first_log}, {"labels", labels}, {"roads_mapped", mapper.roadsMapped()},
                              {"roads_failed", mapper.roadsFailed()}, {"roads", mapper.roadLog()},
                              {"partial_not_mapped", mapper.partialNotMapped()},
                              {"intersections_failed", junction_failures},
                              {"passages", mapper.assembler().passageCount()},  // the car's paths through junctions
                              {"lanelets", map.lanelets.size()}, {"frames_projected", mapper.framesProjected()},
                              {"stop_lines", std::count_if(map.lines.begin(), map.lines.end(), [](const auto& l) {
                                 return l.type == map::LineType::kStopLine;
                               })},
                              {"regulatory_elements", map.regulatory_elements.size()},
                              {"crosswalks", map.crosswalks.size()},
                              {"frames_mesh", mapper.framesMesh()}, {"frames_segmented", mapper.framesSegmented()},
                              {"frames_failed", mapper.framesFailed()}, {"seconds", secs},
                              {"log_read", log_read}};
    if (o.logs.size() + o.traversals.size() > 1) summary["drives"] = drives;  // per drive: each road merged onto earlier drives, its alignment
    io::writeFileAtomically((fs::path(o.out) / "summary.json").string(), summary.dump(2) + "\n");
    if (map.lanelets.empty()) {
      throw std::runtime_error(mapper.roadsFailed() > 0 ? "no road was mapped: every road explored failed (see summary.json)"
                                                        : "no road was mapped: did the drive reach an intersection?");
    }
    io::Lanelet2WriteOptions write_options;
    write_options.speed_limit_kmh_by_road = io::speedLimitsKmh(sk);  // OSM maxspeed
    io::writeLanelet2(map, (fs::path(o.out) / "map.osm").string(), write_options);
    if (!o.autoware.empty()) io::writeAutowareMapFolder(map, o.autoware, write_options);
    io::writeGeoJson(map, (fs::path(o.out) / "map.geojson").string());
    io::MapPngOptions png;
    png.background_polylines = io::skeletonPolylines(sk);
    Eigen::AlignedBox2d extent;  // the mapped lanes and 40 m around them, over the OSM roads
    for (const auto& l : map.lines) {
      for (const auto& p : l.points) extent.extend(p.head<2>());
    }
    png.bbox = Eigen::AlignedBox2d(extent.min() - Eigen::Vector2d(40, 40), extent.max() + Eigen::Vector2d(40, 40));
    io::writeMapPng(map, (fs::path(o.out) / "map.png").string(), png);
    std::printf("lanemap-offline: %d roads mapped, %d failed, %zu lanelets; labels: %s; %lld frames projected (%lld on the LIDAR mesh); %.1f s\n",
                mapper.roadsMapped(), mapper.roadsFailed(), map.lanelets.size(), labels.c_str(),
                static_cast<long long>(mapper.framesProjected()), static_cast<long long>(mapper.framesMesh()), secs);
    std::printf("wrote %s/map.osm, map.geojson, map.png, summary.json\n", o.out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "lanemap-offline: " << e.what() << "\n";
    return 2;
  }
}
