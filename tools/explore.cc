// lanemap-explore: lane exploration (core/lanes/explorer.h) on one saved road BEV, for looking into
// why a road came out as it did: the road's stretch, the particle filter's counts and every lane
// found (extent, offset, bounds, relations).
//
//   lanemap-explore --bev DIR/bev/road_ID.bev --osm roads.osm --road ID [--lanes-config FILE]
//       [--station S]          explore it as the road a drive ended on, S m along it (its
//                              summary.json "partial" station_m; DIR/bev/partial/road_ID.bev)
//       [--history FILE.csv]   surviving particles (s, d) of every 5th step, for plotting
//       [--raster FILE.png]    the straightened raster the particles ran on (s up, d to the left),
//                              the lanes' centre lines over it
#include "core/bev/bev_grid.h"
#include "core/lanes/explorer.h"
#include "core/lanes/options.h"
#include "core/mapping/partial_road.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include "processes/framework/share_dir.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>

int main(int argc, char** argv) {
  using namespace lanemap;
  CLI::App app{"Runs lane exploration on one road's saved BEV grid and prints what it finds"};
  std::string bev_path, osm_path, history_path, raster_path;
  std::string lanes_config = "config/lane_mapper.yaml";
  int64_t road_id = -1;
  double station = -1.0;
  app.add_option("--bev", bev_path, "a road's BEV grid (lanemap-offline's DIR/bev/road_<id>.bev)")->required();
  app.add_option("--osm", osm_path, "the road-level OSM the map was built on")->required();
  app.add_option("--road", road_id, "atomic road id (the <id> of the file name)")->required();
  app.add_option("--lanes-config", lanes_config, "the lane mapper config: its explorer block, and its map block's skeleton options")->capture_default_str();
  app.add_option("--station", station,
                 "explore the road as far as a drive that ended on it got: the station (m along the road) of its "
                 "summary.json \"partial\" entry; the grid is then DIR/bev/partial/road_<id>.bev")
      ->check(lanemap::cli::kNonNegative);
  app.add_option("--history", history_path, "write the surviving particles (s, d) of every 5th step as CSV");
  app.add_option("--raster", raster_path,
                 "write the straightened raster (rows along s upwards, d to the left; one pixel per cell) as PNG: "
                 "drivable blue, blocked grey, separation yellow, dashed white, solid orange, curb red, outside "
                 "purple, unobserved black; lane centre lines green");
  CLI11_PARSE(app, argc, argv);
  try {
    lanes_config = resolveShippedFile(lanes_config);
    const LaneMapperSettings settings = LaneMapperSettings::fromYamlFile(lanes_config);  // map + explorer blocks
    const auto sk = skeleton::Skeleton::build(osm::readOsm(osm_path), settings.map.skeleton);
    const auto* road = sk.road(road_id);
    if (!road) throw std::runtime_error("no atomic road " + std::to_string(road_id) + " in " + osm_path);
    const lanes::ExplorerOptions options = settings.explorerOptions();
    const auto geometry =
        station >= 0.0 ? mapping::drivenStretch(*road, station, options) : lanes::RoadGeometry::fromSkeleton(*road);
    const auto grid = bev::BevGrid::load(bev_path);
    const bool debug = !history_path.empty() || !raster_path.empty();
    const auto res = lanes::exploreRoad(grid, geometry, options, std::nullopt, debug ? 5 : 0);
    const auto stretch = lanes::explorationStretch(geometry, res.frame->length(), options);
    std::printf("road %lld (%lld -> %lld): %.1f m, ROIs leave s %.1f-%.1f, explored s %.1f-%.1f, %s\n",
                static_cast<long long>(road_id), static_cast<long long>(road->from), static_cast<long long>(road->to),
                road->length, geometry.s_begin, geometry.s_end, stretch.s_begin, stretch.s_end,
                geometry.two_way ? "two-way" : "one-way");
    const auto& st = res.stats;
    std::printf("%d steps, %d births, %lld deaths, %d tracks (%d joined as pieces of a lane), %zu lanes\n", st.steps,
                st.births, static_cast<long long>(st.deaths), st.tracks, st.pieces_joined, res.lanes.size());
    std::printf("raster cells:");
    for (int c = 0; c < 8; ++c) {
      std::printf(" %s %lld", lanes::toString(static_cast<lanes::RasterClass>(c)), static_cast<long long>(st.raster_cells[c]));
    }
    std::printf("\n");
    for (const auto& l : res.lanes) {
      std::printf("  lane %d: s %.1f-%.1f, d %.2f .. %.2f, index %d, split_from %d, merges_into %d, bounds %s/%s, %lld samples\n",
                  l.id, l.s_begin, l.s_end, l.centre.d(l.s_begin), l.centre.d(l.s_end), l.index_from_left, l.split_from,
                  l.merges_into, map::toString(l.left.type), map::toString(l.right.type),
                  static_cast<long long>(l.particle_samples));
    }
    if (!history_path.empty()) {
      std::ofstream csv(history_path);
      csv << "s,d\n";
      for (const auto& p : res.history) csv << p.x() << "," << p.y() << "\n";
    }
    if (!raster_path.empty()) {
      const auto& r = res.raster;
      const cv::Vec3b colour[8] = {{0, 0, 0},     {140, 60, 20}, {90, 90, 90}, {0, 220, 255},
                                   {255, 255, 255}, {0, 140, 255}, {0, 0, 255},  {120, 40, 100}};  // BGR
      cv::Mat img(r.rows, r.cols, CV_8UC3);
      for (int i = 0; i < r.rows; ++i) {
        for (int j = 0; j < r.cols; ++j) img.at<cv::Vec3b>(r.rows - 1 - i, r.cols - 1 - j) = colour[r.code[size_t(i) * r.cols + j] & 7];
      }
      for (const auto& l : res.lanes) {
        for (double s = l.s_begin; s <= l.s_end; s += r.resolution) {
          const int i = static_cast<int>(std::floor((s - r.s0) / r.resolution));
          const int j = static_cast<int>(std::floor((l.centre.d(s) - r.d0) / r.resolution));
          if (i >= 0 && i < r.rows && j >= 0 && j < r.cols) img.at<cv::Vec3b>(r.rows - 1 - i, r.cols - 1 - j) = {0, 200, 0};
        }
      }
      if (!cv::imwrite(raster_path, img)) throw std::runtime_error("cannot write " + raster_path);
    }
  } catch (const std::exception& e) {
    std::cerr << "lanemap-explore: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
