// lanemap-eval: scores a built Lanelet2 map against a ground-truth one (any two Lanelet2 maps) with
// the paper's metrics and more (core/eval/evaluate.h has every definition): lane precision/recall
// (a detection at IoU > 0.7 or RMS < 0.2 m), centre-line RMS, mIoU, intersection topology
// precision/recall over (in lane, out lane) pairs and trajectory RMS, lane-graph precision/recall,
// MapTR's Chamfer AP at 0.5/1.0/1.5 m, per-road detail, and (core/eval/regulatory.h) stop-line and
// crosswalk precision/recall/position error, agreement of the rules at matched stop lines and
// lane-change permission accuracy, and lane precision/recall per band of the map's per-lane
// confidence (core/eval/confidence.h; JSON "confidence"). Prints a summary; --json writes it all.
//
//   lanemap-eval --truth groundtruth.osm --map lane_map.osm [--json report.json]
//                [--driven scenario.json | --driven drive.lcmlog --osm roads.osm | --mapped-roads-only]
//
// --driven scores the roads the car drove to their end intersection (and the junction connections
// between them): a driven road the map has no lanes on counts as missed. The road the drive ended
// on counts as far as the car drove it (core/eval/area.h restrictToDriven: its truth cut across
// the road at the car's last position; the road it began on from the car's first position), so
// lanes mapped there as far as driven are scored, not counted against precision. The route comes from
// lanemap-sim's scenario.json, or, for a recording scored against a surveyed map, from the log's
// POSE map-matched to the OSM by the road tracker (the same as the live graph's road tracker).
// Two atomic roads between the same two junctions (a street and the tunnel under it) are told apart
// by scenario.json's road ids: only the one driven is scored.
//
// Both files are read in one ENU frame: the truth file's writer origin when its nodes carry
// local_x/local_y (lanemap's files do), else its first node (see eval::lanelet2Origin).
#include "core/eval/area.h"
#include "core/eval/confidence.h"
#include "core/eval/evaluate.h"
#include "core/io/atomic_file.h"
#include "core/io/lanelet2.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"
#include "lanemap/pose_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include "processes/framework/share_dir.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

// The roads a recorded drive closed: its POSE channel through the road tracker on the OSM's
// skeleton; every kReachedIntersection closes the road it ends. The road entered and not closed
// when the log ends is the partial one, driven to the last pose (moved into `frame`); the first
// road entered counts from where it was entered (unless entered again).
lanemap::eval::DrivenArea drivenRoadsFromLog(const std::string& log_path, const std::string& osm_path,
                                             const std::string& tracker_config, const lanemap::geo::LocalFrame& frame) {
  using namespace lanemap;
  if (osm_path.empty()) throw std::runtime_error("--driven with an LCM log needs --osm (the road network it drove)");
  const RoadTrackerSettings settings = RoadTrackerSettings::fromYamlFile(tracker_config);  // its map block too
  const auto sk = skeleton::Skeleton::build(osm::readOsm(osm_path), settings.map.skeleton);
  tracking::RoadTracker tracker(sk, settings.tracker);
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error("cannot read LCM log: " + log_path);
  eval::DrivenArea out;
  size_t poses = 0;
  std::optional<eval::RoadKey> open;  // entered, not closed
  std::optional<Eigen::Vector3d> last;
  std::optional<eval::EnteredDrive> began;  // the first road entered, where
  std::map<eval::RoadKey, int> times_entered;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != channels::kPose) continue;
    pose_t m;
    if (m.decode(ev->data, 0, static_cast<int>(ev->datalen)) < 0) continue;
    ++poses;
    const EnuPose p = toEnuPose(m, sk.frame());
    if (p.position.allFinite()) last = p.position;
    for (const auto& e : tracker.update(toPoseInput(p))) {
      switch (e.type) {
        case tracking::RoadEventType::kEnteredRoad:
          open = eval::RoadKey{e.from_node, e.to_node};
          ++times_entered[*open];
          if (!began && p.position.allFinite()) began = eval::EnteredDrive{*open, frame.toEnu(sk.frame().toWgs84(p.position)).head<2>()};
          break;
        case tracking::RoadEventType::kReachedIntersection:
          out.roads.insert({e.from_node, e.to_node});
          open.reset();
          break;
        case tracking::RoadEventType::kLeftMap:
        case tracking::RoadEventType::kPoseLost: open.reset(); break;
        default: break;
      }
    }
  }
  if (poses == 0) throw std::runtime_error(log_path + ": no " + std::string(channels::kPose) + " message");
  if (open && last) out.partial.push_back({*open, frame.toEnu(sk.frame().toWgs84(*last)).head<2>()});
  // The road the drive began on counts from where it was entered, unless it was entered again.
  if (began && times_entered[began->road] == 1 && (out.roads.count(began->road) || (open && *open == began->road))) {
    out.entered.push_back(*began);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Scores a built Lanelet2 lane map against a ground-truth Lanelet2 map: lanes, intersections, lane "
               "graph, Chamfer AP, stop lines, crosswalks, their rules and lane-change permissions"};
  std::string truth_path, map_path, json_path, subtypes_arg = "road,highway,play_street,bus_lane,emergency_lane,exit,";
  lanemap::eval::EvalOptions options;
  std::string driven_path, osm_path;
  std::string tracker_config = "config/road_tracker.yaml";
  bool no_road_tags = false, quiet = false, mapped_only = false;
  app.add_option("--truth", truth_path, "ground-truth Lanelet2 map (.osm)")->required();
  app.add_option("--map", map_path, "built Lanelet2 map (.osm)")->required();
  app.add_option("--json", json_path, "write the report as JSON (with every truth lane and every built lane: what each matched, IoU, RMS, coverage)");
  app.add_option("--subtypes", subtypes_arg,
                 "lanelet subtypes that are lanes, comma separated (an empty item: lanelets with no subtype)")
      ->capture_default_str();
  app.add_option("--iou", options.iou_threshold, "IoU above which a lane is detected")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  app.add_option("--rms", options.rms_threshold_m, "RMS (m) below which a lane is detected")->capture_default_str()->check(CLI::Range(0.0, 100.0));
  app.add_option("--step", options.sample_step_m, "centre line sample spacing (m)")->capture_default_str()->check(CLI::Range(0.01, 10.0));
  app.add_flag("--no-road-tags", no_road_tags, "match lanes by geometry only (ignore lanemap:from_node/to_node)");
  app.add_flag("--mapped-roads-only", mapped_only,
               "score against the truth of the atomic roads the map has (and the intersection lanes between "
               "them), not the whole city: what one drive could map (needs lanemap:from_node/to_node tags)");
  auto* driven_opt = app.add_option(
      "--driven", driven_path,
      "score against the truth of the atomic roads the car drove to their end (and the intersection lanes "
      "between them); a driven road with no lanes counts as missed. ROUTE: lanemap-sim's scenario.json, or "
      "an LCM log whose POSE is map-matched to --osm by the road tracker");
  app.add_option("--osm", osm_path, "road-level OSM file the drive used (with --driven LOG)");
  app.add_option("--tracker-config", tracker_config, "road tracker options (with --driven LOG)")->capture_default_str();
  driven_opt->excludes(app.get_option("--mapped-roads-only"));
  app.add_flag("-q,--quiet", quiet, "no summary on stdout");
  CLI11_PARSE(app, argc, argv);
  options.match_by_road_tags = !no_road_tags;

  try {
    lanemap::io::Lanelet2ReadOptions ro;
    std::stringstream ss(subtypes_arg);
    std::string item;
    while (std::getline(ss, item, ',')) ro.subtypes.push_back(item);
    if (!subtypes_arg.empty() && subtypes_arg.back() == ',') ro.subtypes.push_back("");
    const lanemap::geo::LatLonAlt origin = lanemap::eval::lanelet2Origin(truth_path);
    auto truth = lanemap::io::readLanelet2(truth_path, origin.lat, origin.lon, ro);
    const auto built = lanemap::io::readLanelet2(map_path, origin.lat, origin.lon, ro);
    size_t driven_roads = 0, partial_roads = 0, entered_roads = 0;
    if (mapped_only) truth = lanemap::eval::restrictToMappedRoads(truth, built);
    if (!driven_path.empty()) {
      const bool json = std::filesystem::path(driven_path).extension() == ".json";
      const lanemap::geo::LocalFrame frame(origin);
      const auto area = json ? lanemap::eval::drivenAreaFromScenario(driven_path, frame)
                             : drivenRoadsFromLog(driven_path, osm_path, lanemap::resolveShippedFile(tracker_config), frame);
      driven_roads = area.roads.size();
      partial_roads = area.partial.size();
      entered_roads = area.entered.size();
      truth = lanemap::eval::restrictToDriven(truth, area);
    }
    const auto report = lanemap::eval::evaluate(truth, built, options);
    const auto bands = lanemap::eval::confidenceBands(report, built);  // lanemap's per-lane confidence
    if (!quiet) {
      std::printf("truth: %s (%zu lanelets%s)\nmap:   %s (%zu lanelets)\n", truth_path.c_str(), truth.lanelets.size(),
                  driven_path.empty() ? "" : (", " + std::to_string(driven_roads) + " driven roads" +
                                              (partial_roads ? " + " + std::to_string(partial_roads) + " as far as driven" : "") +
                                              (entered_roads ? ", " + std::to_string(entered_roads) + " from where the drive began" : "")).c_str(),
                  map_path.c_str(), built.lanelets.size());
      std::cout << lanemap::eval::summary(report);
      if (bands.unrated < report.built_lanes.size()) std::cout << lanemap::eval::summary(bands);
      std::cout << std::flush;
    }
    if (!json_path.empty()) {
      nlohmann::json j = lanemap::eval::toJson(report);
      j["truth"] = truth_path;
      j["map"] = map_path;
      j["origin"] = {{"lat", origin.lat}, {"lon", origin.lon}};
      j["confidence"] = lanemap::eval::toJson(bands);  // lane P/R per confidence band
      j["scored_area"] = !driven_path.empty() ? "driven" : mapped_only ? "mapped_roads" : "whole_truth";
      if (!driven_path.empty()) {
        j["driven_roads"] = driven_roads;    // to their end intersection
        j["partial_roads"] = partial_roads;  // the road the drive ended on, scored as far as driven
        j["entered_roads"] = entered_roads;  // the road the drive began on, scored from where it began
      }
      lanemap::io::writeFileAtomically(json_path, j.dump(2) + "\n");
      if (!quiet) std::printf("wrote %s\n", json_path.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-eval: %s\n", e.what());
    return 1;
  }
  return 0;
}
