// lanemap-sim: simulates a data-collection drive over a street network from an OSM file (or, with
// --lanelet2, over the lanes of a Lanelet2 HD map someone drew: core/sim/lanelet2_world.h) and writes
//   <out>/drive.lcmlog      CAMERA_FRONT (JPEG), SEMANTIC_FRONT_TRUTH, LIDAR_PACKETS, POSE
//   <out>/groundtruth.osm   the true lane-level map (Lanelet2)
//   <out>/groundtruth.png   a picture of it over the street network
//   <out>/roads.osm         the road-level OSM the mapper is given (no lane tags by default)
//   <out>/trajectory.csv    the true motion at 10 Hz (for tests and evaluation)
//   <out>/scenario.json     route, seed, options, counts
// Everything is checked (OSM, route) before anything is written; output goes to a temporary
// folder renamed into place at the end, so a failed run leaves nothing behind.
#include "core/config/map_config.h"
#include "core/intersections/regulatory.h"
#include "core/io/lanelet2.h"
#include "core/io/speed_limits.h"
#include "core/map/simplify.h"
#include "core/mapping/coverage.h"
#include "core/io/map_png.h"
#include "core/io/road_osm_writer.h"
#include "core/osm/osm_data.h"
#include "core/sim/drive.h"
#include "core/sim/lanelet2_world.h"
#include "core/sim/simulator.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/pose_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/lcm_log_writer.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include "processes/framework/share_dir.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <opencv2/core/utility.hpp>

#include <unistd.h>

#include <chrono>
#include <random>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <optional>
#include <iostream>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using namespace lanemap;

namespace {


// Writes every measurement to an LCM log file as the car's drivers would have published it.
class LogSink : public sim::SensorSink {
 public:
  explicit LogSink(const std::string& path) : log_(path) {}
  void onPose(const sim::PoseMeasurement& m) override {
    pose_t msg{};
    msg.utime = m.utime;
    msg.latitude = m.wgs84.lat;
    msg.longitude = m.wgs84.lon;
    msg.altitude = m.wgs84.alt;
    msg.orientation[0] = m.orientation.w();
    msg.orientation[1] = m.orientation.x();
    msg.orientation[2] = m.orientation.y();
    msg.orientation[3] = m.orientation.z();
    for (int i = 0; i < 3; ++i) {
      msg.velocity_enu[i] = m.velocity_enu[i];
      msg.angular_rate[i] = m.angular_rate[i];
    }
    const double pv = m.position_sigma_m * m.position_sigma_m;
    msg.position_covariance[0] = msg.position_covariance[4] = pv;
    msg.position_covariance[8] = 4.0 * pv;
    msg.orientation_covariance[8] = m.yaw_sigma_rad * m.yaw_sigma_rad;
    msg.status = pose_t::STATUS_SIMULATED;
    log_.message(channels::kPose, m.utime, msg);
  }
  void onCamera(const sim::CameraMeasurement& m) override {
    image_t img;
    img.utime = m.utime;
    img.seq = m.seq;
    img.width = m.width;
    img.height = m.height;
    img.row_stride = 0;
    img.pixelformat = image_t::PIXEL_FORMAT_JPEG;
    img.data = m.jpeg;
    img.size = static_cast<int32_t>(img.data.size());
    log_.message(channels::kCameraFront, m.utime, img);
    label_image_t lab;
    lab.utime = m.utime;
    lab.seq = m.seq;
    lab.width = m.width;
    lab.height = m.height;
    lab.encoding = label_image_t::ENCODING_PNG;
    lab.data = m.labels_png;
    lab.size = static_cast<int32_t>(lab.data.size());
    lab.source = "sim-truth";
    log_.message(channels::kSemanticFrontTruth, m.utime, lab);
  }
  void onLidar(const sim::LidarMeasurement& m) override {
    lidar_packets_t msg;
    msg.utime = m.utime;
    msg.model = "VLP-16";
    msg.num_packets = static_cast<int32_t>(m.packets.size());
    msg.packet_size = lidar::kDataPacketSize;
    msg.packet_utime = m.packet_utime;
    for (const auto& p : m.packets) msg.data.emplace_back(p.begin(), p.end());
    log_.message(channels::kLidarPackets, m.publish_utime, msg);
  }

 private:
  LcmLogWriter log_;
};

std::vector<int64_t> parseRoute(const std::string& text) {
  std::vector<int64_t> ids;
  if (text.empty() || text == "auto") return ids;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      ids.push_back(std::stoll(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw sim::RouteError("--route: '" + item + "' is not an OSM node id (use auto or id,id,...)");
    }
  }
  return ids;
}

}  // namespace

// groundtruth.osm (Lanelet2, with stop signs, give way and traffic lights from the OSM's control
// nodes), roads.osm and groundtruth.png into `dir`; returns the lanelets Lanelet2 would misread.
std::vector<std::string> writeTruthFiles(const sim::SimWorld& world, const skeleton::Skeleton& sk,
                                         const osm::OsmData& osm_data, const std::string& osm_path,
                                         bool keep_lane_tags, const fs::path& dir) {
  // The truth is sampled densely; 1 cm Douglas-Peucker keeps its shape and cuts the file ~4x.
  // The world builder shapes every lanelet so that Lanelet2's loader reads it as meant; a short
  // lane piece ending in a bend tighter than the road is wide can still defeat its heuristic
  // (Monaco: one lanelet of ~12,600 for 7 of 9 seeds tried; West Oakland: none): it is written
  // as it is, named here and in scenario.json ("lanelet2_misread"), rather than failing the drive.
  map::LaneMap truth_written = map::simplified(world.truth(), sim::kTruthSimplifyTolerance);
  // Stop signs, give way and traffic lights at the truth's stop lines, from the OSM nodes.
  // (A world from a Lanelet2 map has no OSM control nodes: its roads.osm is derived.)
  const auto controls = osm_path.empty() ? decltype(intersections::readControlNodes(osm_path)){}
                                         : intersections::readControlNodes(osm_path);
  intersections::addRegulatoryElements(truth_written, sk, controls);
  auto misread = io::orientationProblems(truth_written);
  io::Lanelet2WriteOptions truth_options;
  truth_options.check_orientation = misread.empty();
  truth_options.speed_limit_kmh_by_road = io::speedLimitsKmh(sk);
  io::writeLanelet2(truth_written, (dir / "groundtruth.osm").string(), truth_options);
  io::RoadOsmOptions road_options;
  road_options.keep_lane_tags = keep_lane_tags;
  for (const auto& [id, c] : controls) {  // roads.osm keeps the junction controls for the mapper
    road_options.node_tags[id]["highway"] = intersections::toString(c.control);
    if (!c.direction.empty()) road_options.node_tags[id]["direction"] = c.direction;
  }
  io::writeRoadOsm(osm_data, (dir / "roads.osm").string(), road_options);
  io::MapPngOptions png;
  png.background_polylines = io::skeletonPolylines(sk);
  if (osm_data.bounds.valid()) {  // the extract's area, not the far ends of ways leaving it
    const auto& b = osm_data.bounds;
    png.bbox = Eigen::AlignedBox2d(sk.frame().toEnu(b.min_lat, b.min_lon).head<2>(),
                                   sk.frame().toEnu(b.max_lat, b.max_lon).head<2>());
  }
  io::writeMapPng(world.truth(), (dir / "groundtruth.png").string(), png);
  return misread;
}

int main(int argc, char** argv) {
  CLI::App app(
      "lanemap-sim: simulate a data-collection drive over the street network of an OSM file.\n"
      "Writes drive.lcmlog, groundtruth.osm (Lanelet2), groundtruth.png, roads.osm, trajectory.csv\n"
      "and scenario.json into --out. Deterministic for a seed.\n"
      "With --lanelet2 MAP.osm the world is the HD map's own lanes, markings, curbs, crosswalks and\n"
      "junctions, the ground truth its vehicle lanelets, and roads.osm a road-level OSM derived from\n"
      "the lanelets (ways along groups of side-by-side lanelets, junction nodes where they branch).");
  std::string osm_path, lanelet2_path, origin_text, out_dir, route_text = "auto";
  std::string vehicle_path = "config/vehicle.yaml";
  std::string world_path = "config/sim_world.yaml";
  std::string drive_path = "config/sim_drive.yaml";
  std::string map_path = kDefaultMapConfig;
  uint64_t seed = 1;
  std::optional<uint64_t> world_seed;
  double duration = 120.0, camera_hz = 10.0, pose_hz = 100.0;
  bool no_lidar = false, flat = false, keep_lane_tags = false, force = false, quiet = false, stop_at_dead_ends = false;
  int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  auto* osm_opt = app.add_option("--osm", osm_path, "road network (.osm or .osm.pbf)");
  auto* l2_opt = app.add_option("--lanelet2", lanelet2_path,
                                "a Lanelet2 HD map (.osm) to build the world from, instead of --osm");
  app.add_option("--origin", origin_text,
                 "with --lanelet2: LAT,LON of the map's ENU origin (default: the centre of its nodes)");
  osm_opt->excludes(l2_opt);
  l2_opt->excludes(osm_opt);
  app.add_option("--out", out_dir, "output folder (must not exist or be empty, unless --force)")->required();
  auto* route_opt = app.add_option("--route", route_text, "auto, or intersection node ids to pass through: id,id,...");
  std::string cover_path;
  int64_t cover_from = -1;
  auto* cover_opt = app.add_option("--cover", cover_path,
                                   "a coverage file (lanemap-coverage --json of the store): the route covers the most road it does "
                                   "not list as mapped in --duration (core/mapping/coverage.h planCoverage)");
  cover_opt->excludes(route_opt);
  app.add_option("--cover-from", cover_from, "--cover: the intersection to start at (default: seeded, the start of a road still to cover out of a dead end, else of any road still to cover)")
      ->needs(cover_opt);
  app.add_option("--seed", seed, "random seed: the route, speeds, pose noise and light (and the world, without --world-seed)");
  app.add_option("--world-seed", world_seed,
                 "the world's own seed (lane widths, parked cars, paint wear, ...): drives of one campaign share it and "
                 "write the same groundtruth.osm; each such drive also gets its own constant pose offset "
                 "(sim_drive.yaml pose_noise campaign_offset_sigma_m, campaign_heading_sigma_deg)");
  app.add_option("--duration", duration, "longest drive, seconds")->check(lanemap::cli::kPositive);
  app.add_option("--camera-hz", camera_hz, "camera frame rate")->check(CLI::Range(0.1, 60.0));
  app.add_option("--pose-hz", pose_hz, "pose rate")->check(CLI::Range(0.1, 1000.0));
  app.add_flag("--no-lidar", no_lidar, "no LIDAR_PACKETS");
  app.add_flag("--stop-at-dead-ends", stop_at_dead_ends,
               "auto route: end the drive at the first dead end it cannot avoid rather than turn round there "
               "(sim_drive.yaml turn_round_at_dead_ends: false; the routes before 2026-12-06)");
  app.add_flag("--flat", flat, "a flat world: no grades, crown or bumps");
  app.add_flag("--keep-lane-tags", keep_lane_tags, "roads.osm keeps lanes/turn:lanes/width tags");
  app.add_option("--vehicle", vehicle_path, "camera and LIDAR config");
  app.add_option("--world-config", world_path, "world generation config");
  app.add_option("--drive-config", drive_path, "driving style and pose noise config");
  app.add_option("--map-config", map_path,
                 "the map block whose skeleton options cut the atomic roads (the mapper's, so that "
                 "scenario.json's road ids are the map's)")->capture_default_str();
  app.add_option("--threads", threads,
                 "threads rendering camera frames and casting LIDAR sweeps (default: the cores, here " +
                     std::to_string(threads) + "); the output is byte-identical for any count")
      ->check(CLI::Range(1, 256));
  app.add_flag("--force", force, "replace a non-empty --out");
  app.add_flag("-q,--quiet", quiet, "no progress");
  CLI11_PARSE(app, argc, argv);

  if (osm_path.empty() && lanelet2_path.empty()) {
    std::fprintf(stderr, "lanemap-sim: error: give --osm FILE or --lanelet2 FILE (see --help)\n");
    return 2;
  }
  if (!origin_text.empty() && lanelet2_path.empty()) {
    std::fprintf(stderr, "lanemap-sim: error: --origin goes with --lanelet2\n");
    return 2;
  }

  const auto t_start = std::chrono::steady_clock::now();
  fs::path out(out_dir);
  fs::path tmp;
  try {
    // Relative names: the current folder, else the shipped files (configs, data/osm/...).
    for (std::string* f : {&vehicle_path, &world_path, &drive_path, &osm_path, &lanelet2_path, &map_path}) *f = resolveShippedFile(*f);
    if (fs::exists(out) && !fs::is_directory(out)) throw std::runtime_error("--out '" + out_dir + "' is a file");
    if (fs::exists(out) && !fs::is_empty(out) && !force) {
      throw std::runtime_error("--out '" + out_dir + "' is not empty (use --force to replace it)");
    }
    // 1. Everything that can fail on bad input, before any output.
    const YAML::Node vehicle = loadYamlFile(vehicle_path);
    const camera::CameraModel camera = camera::CameraModel::fromYaml(vehicle["camera"]);
    std::optional<sim::LidarScannerOptions> lidar;
    if (!no_lidar) lidar = sim::LidarScannerOptions::fromYaml(vehicle["lidar"]);
    sim::WorldOptions world_options = sim::WorldOptions::fromYaml(loadYamlFile(world_path));
    world_options.seed = world_seed ? *world_seed : seed;
    if (flat) world_options.flat = true;

    osm::OsmData osm_data;
    std::unique_ptr<skeleton::Skeleton> sk_ptr;
    std::unique_ptr<sim::SimWorld> world;
    std::optional<sim::Lanelet2WorldStats> l2_stats;
    if (!lanelet2_path.empty()) {
      geo::LatLonAlt origin;
      if (origin_text.empty()) {
        origin = sim::lanelet2MapCentre(lanelet2_path);
      } else {
        double lat = 0, lon = 0;
        char extra = 0;
        if (std::sscanf(origin_text.c_str(), "%lf,%lf%c", &lat, &lon, &extra) != 2 || !(std::abs(lat) <= 90.0) ||
            !(std::abs(lon) <= 180.0)) {
          throw std::runtime_error("--origin: '" + origin_text + "' is not LAT,LON in degrees (e.g. 49,8.4)");
        }
        origin.lat = lat;
        origin.lon = lon;
      }
      sim::Lanelet2World l2 = sim::buildLanelet2World(lanelet2_path, origin, world_options);
      osm_data = std::move(l2.roads);
      sk_ptr = std::move(l2.skeleton);
      world = std::move(l2.world);
      l2_stats = l2.stats;
    } else {
      osm_data = osm::readOsm(osm_path);
      const auto map = config::MapConfig::fromYamlFile(map_path);
      sk_ptr = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(osm_data, map.skeleton));
      world = sim::buildWorld(*sk_ptr, world_options, osm_data.restrictions);
    }
    const skeleton::Skeleton& sk = *sk_ptr;
    const YAML::Node drive_config = loadYamlFile(drive_path);
    sim::DriveOptions drive = sim::DriveOptions::fromYaml(drive_config["drive"]);
    drive.seed = seed;
    drive.duration_s = duration;
    drive.route_nodes = parseRoute(route_text);
    if (stop_at_dead_ends) drive.turn_round_at_dead_ends = false;
    nlohmann::json cover_json = nullptr;
    if (!cover_path.empty()) {
      const auto cov = mapping::readCoverageJson(cover_path, sk);
      // Default: a road still to cover out of a dead end (only a drive's start covers those).
      if (cover_from < 0) cover_from = mapping::coverageStart(sk, cov, seed);
      // Planned at 0.75 of the cruise speed: the car slows for turns and starts from standstill.
      const auto cover_plan = mapping::planCoverage(sk, cov, cover_from, duration, 0.75 * drive.cruise_speed_mps);
      if (cover_plan.roads.empty()) throw sim::RouteError("--cover: no road left to cover within reach of " + std::to_string(cover_from));
      drive.route_nodes = cover_plan.intersections;
      cover_json = {{"file", cover_path}, {"from", cover_from}, {"roads", cover_plan.roads}, {"new_m", cover_plan.new_m},
                    {"planned_s", cover_plan.seconds}, {"share_before", cov.share()}};
    }
    const sim::LanePlan plan = sim::planDrive(sk, world->truth(), drive);
    const sim::Trajectory trajectory(world->truth(), *world, plan, drive);
    if (!quiet) {
      std::printf("lanemap-sim: %zu atomic roads, %zu lanelets; route of %zu roads, %.0f m, %.1f s\n",
                  sk.roads().size(), world->truth().lanelets.size(), plan.roads.size(),
                  trajectory.length(), trajectory.duration());
    }

    // 2. Write into a temporary sibling folder, then rename it into place.
    const fs::path parent = fs::absolute(out).parent_path();
    fs::create_directories(parent);
    tmp = parent / (out.filename().string() + ".partial." + std::to_string(getpid()));
    fs::remove_all(tmp);
    fs::create_directories(tmp);

    // The truth files (a city's groundtruth.osm is some 150 MB) are written by a thread of their
    // own while the drive is rendered; it only reads the world's truth and the skeleton.
    auto truth_files = std::async(std::launch::async, [&] {
      return writeTruthFiles(*world, sk, osm_data, osm_path, keep_lane_tags, tmp);
    });
    sim::SimulatorOptions sim_options;
    sim_options.seed = seed;
    sim_options.camera_rate_hz = camera_hz;
    sim_options.pose_rate_hz = pose_hz;
    sim_options.threads = threads;
    sim_options.lidar = !no_lidar;
    if (vehicle["camera"]["jpeg_quality"]) sim_options.jpeg_quality = vehicle["camera"]["jpeg_quality"].as<int>();
    sim_options.pose_noise = sim::PoseNoiseOptions::fromYaml(drive_config["pose_noise"]);
    if (!world_seed) {  // a drive on its own defines its frame: no drive offset
      sim_options.pose_noise.drive_offset_sigma_m = 0.0;
      sim_options.pose_noise.drive_heading_sigma_deg = 0.0;
    }
    const sim::DriveOffset drive_offset = sim::driveOffset(sim_options.pose_noise, seed);
    sim::RenderOptions render;
    // Lines between the two directions of a road are painted yellow (US style).
    render.opposite_directions = [w = world.get()](int64_t a, int64_t b) {
      const map::Lanelet* la = w->lanelet(a);
      const map::Lanelet* lb = w->lanelet(b);
      return la && lb && la->from_node == lb->to_node && la->to_node == lb->from_node;
    };
    // Whole frames and sweeps go to the --threads workers; OpenCV's own row split inside a frame
    // would only add threads to them (and use more than one core with --threads 1).
    cv::setNumThreads(1);
    sim::Simulator simulator(*world, trajectory, sk.frame(), camera, render, lidar, sim_options);
    sim::SimulatorCounts counts;
    {
      LogSink sink((tmp / "drive.lcmlog").string());
      counts = simulator.run(sink, [quiet](double f) {
        if (!quiet) std::fprintf(stderr, "\rlanemap-sim: rendering %3.0f %%", 100.0 * f);
      });
      if (!quiet) std::fprintf(stderr, "\n");
    }
    const std::vector<std::string> misread = truth_files.get();
    for (const auto& m : misread) std::fprintf(stderr, "lanemap-sim: warning: %s\n", m.c_str());

    struct DrivenRoad {
      int64_t road_id;
      int64_t entered_utime;
      std::optional<int64_t> left_utime;
    };
    std::vector<DrivenRoad> driven;
    {
      std::ofstream csv(tmp / "trajectory.csv");
      csv << "t_s,utime,east_m,north_m,up_m,yaw_rad,speed_mps,lanelet,road_id\n";
      char line[256];
      for (double t = 0.0; t <= trajectory.duration() + 1e-9; t += 0.1) {
        const sim::VehicleState st = trajectory.at(t);
        const Eigen::Vector3d p = st.vehicle_to_enu.translation();
        const Eigen::Vector3d x = st.vehicle_to_enu.linear().col(0);
        std::snprintf(line, sizeof(line), "%.3f,%lld,%.4f,%.4f,%.4f,%.6f,%.3f,%lld,%lld\n", t,
                      static_cast<long long>(sim_options.start_utime + std::llround(t * 1e6)), p.x(), p.y(),
                      p.z(), std::atan2(x.y(), x.x()), st.speed, static_cast<long long>(st.lanelet),
                      static_cast<long long>(st.road_id));
        csv << line;
        // The roads truly driven: a road starts at its first sample, ends at the first sample
        // that is no longer on it (inside the intersection ROI's lanelets, or the next road).
        const int64_t utime = sim_options.start_utime + std::llround(t * 1e6);
        if (!driven.empty() && !driven.back().left_utime && st.road_id != driven.back().road_id) {
          driven.back().left_utime = utime;
        }
        if (st.road_id >= 0 && (driven.empty() || driven.back().left_utime)) driven.push_back({st.road_id, utime, {}});
      }
    }

    nlohmann::json scenario;
    scenario["osm"] = lanelet2_path.empty() ? fs::absolute(osm_path).string() : (fs::absolute(out) / "roads.osm").string();
    if (!lanelet2_path.empty()) {
      const auto& st = *l2_stats;
      scenario["lanelet2"] = fs::absolute(lanelet2_path).string();
      scenario["lanelet2_world"] = {{"map_lanelets", st.map_lanelets}, {"map_vehicle_lanelets", st.map_vehicle_lanelets},
                                    {"two_way_split", st.two_way_split}, {"road_lanelets", st.road_lanelets},
                                    {"junction_lanelets", st.junction_lanelets}, {"junction_areas", st.junction_areas},
                                    {"joined_junction_paths", st.joined_junction_paths}, {"roads", st.roads},
                                    {"stubs_in_junctions", st.stubs_in_junctions},
                                    {"crosswalks", st.crosswalks}, {"stop_lines", st.stop_lines}};
    }
    scenario["seed"] = seed;
    scenario["world_seed"] = world_options.seed;
    scenario["pose_offset"] = {{"east_m", drive_offset.position.x()}, {"north_m", drive_offset.position.y()},
                               {"heading_deg", drive_offset.yaw_rad * 180.0 / M_PI}};
    scenario["start_utime"] = sim_options.start_utime;
    scenario["duration_s"] = trajectory.duration();
    scenario["length_m"] = trajectory.length();
    if (!cover_json.is_null()) scenario["cover"] = cover_json;
    scenario["options"] = {{"route", route_text}, {"camera_hz", camera_hz}, {"pose_hz", pose_hz},
                           {"lidar", !no_lidar}, {"flat", world->options().flat},
                           {"keep_lane_tags", keep_lane_tags}, {"vehicle", fs::absolute(vehicle_path).string()}};
    scenario["origin"] = {{"lat", sk.frame().origin().lat}, {"lon", sk.frame().origin().lon},
                          {"alt", sk.frame().origin().alt}};
    // route: the atomic roads the car truly drove, in order, with when it entered each and when it
    // reached the road's end intersection (null if the drive ended on the road); planned_route:
    // every road the plan held (the drive may stop before its end).
    nlohmann::json route = nlohmann::json::array();
    for (const auto& d : driven) {
      const auto* road = sk.road(d.road_id);
      route.push_back({{"road_id", d.road_id}, {"from", road->from}, {"to", road->to}, {"way_id", road->way_id},
                       {"length_m", road->length}, {"entered_utime", d.entered_utime},
                       {"left_utime", d.left_utime ? nlohmann::json(*d.left_utime) : nlohmann::json(nullptr)}});
    }
    scenario["route"] = route;
    scenario["lanelet2_misread"] = misread;
    // Turns an OSM turn restriction forbids (the truth has no lanelet for them).
    scenario["turns_restricted"] = world->stats().turns_restricted;
    scenario["planned_route"] = plan.roads;
    scenario["counts"] = {{"poses", counts.poses}, {"camera_frames", counts.camera_frames},
                          {"lidar_sweeps", counts.lidar_sweeps}, {"lidar_packets", counts.lidar_packets}};
    {
      std::ofstream js(tmp / "scenario.json");
      js << scenario.dump(2) << "\n";
    }

    if (fs::exists(out)) fs::remove_all(out);
    fs::rename(tmp, out);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    if (!quiet) {
      std::printf("lanemap-sim: wrote %s: %lld poses, %lld camera frames, %lld LIDAR sweeps in %.1f s\n",
                  out_dir.c_str(), static_cast<long long>(counts.poses),
                  static_cast<long long>(counts.camera_frames), static_cast<long long>(counts.lidar_sweeps), secs);
    }
    return 0;
  } catch (const std::exception& e) {
    std::error_code ec;
    if (!tmp.empty()) fs::remove_all(tmp, ec);
    std::fprintf(stderr, "lanemap-sim: error: %s\n", e.what());
    return 2;
  }
}
