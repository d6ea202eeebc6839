// lanemap-eval: scores a built Lanelet2 map against a ground-truth one (any two Lanelet2 maps) with
// the paper's metrics and more (core/eval/evaluate.h has every definition): lane precision/recall
// (a detection at IoU > 0.7 or RMS < 0.2 m), centre-line RMS, mIoU, intersection topology
// precision/recall over (in lane, out lane) pairs and trajectory RMS, lane-graph precision/recall,
// MapTR's Chamfer AP at 0.5/1.0/1.5 m, and per-road detail. Prints a summary; --json writes it all.
//
//   lanemap-eval --truth groundtruth.osm --map lane_map.osm [--json report.json]
//
// Both files are read in one ENU frame: the truth file's writer origin when its nodes carry
// local_x/local_y (lanemap's files do), else its first node (see eval::lanelet2Origin).
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "core/io/atomic_file.h"
#include "core/io/lanelet2.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  CLI::App app{"Scores a built Lanelet2 lane map against a ground-truth Lanelet2 map"};
  std::string truth_path, map_path, json_path, subtypes_arg = "road,highway,play_street,bus_lane,emergency_lane,exit,";
  lanemap::eval::EvalOptions options;
  bool no_road_tags = false, quiet = false, mapped_only = false;
  app.add_option("--truth", truth_path, "ground-truth Lanelet2 map (.osm)")->required();
  app.add_option("--map", map_path, "built Lanelet2 map (.osm)")->required();
  app.add_option("--json", json_path, "write the report as JSON");
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
    if (mapped_only) truth = lanemap::eval::restrictToMappedRoads(truth, built);
    const auto report = lanemap::eval::evaluate(truth, built, options);
    if (!quiet) {
      std::printf("truth: %s (%zu lanelets)\nmap:   %s (%zu lanelets)\n", truth_path.c_str(), truth.lanelets.size(),
                  map_path.c_str(), built.lanelets.size());
      std::cout << lanemap::eval::summary(report) << std::flush;
    }
    if (!json_path.empty()) {
      nlohmann::json j = lanemap::eval::toJson(report);
      j["truth"] = truth_path;
      j["map"] = map_path;
      j["origin"] = {{"lat", origin.lat}, {"lon", origin.lon}};
      lanemap::io::writeFileAtomically(json_path, j.dump(2) + "\n");
      if (!quiet) std::printf("wrote %s\n", json_path.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-eval: %s\n", e.what());
    return 1;
  }
  return 0;
}
