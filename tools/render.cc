// lanemap-render: draws a road's BEV grid (the bev_builder's <store>/bev/road_<id>.bev) as a PNG,
// layers in colours (core/bev/bev_render.h), the OSM skeleton over it.
//   lanemap-render --bev map-store/bev/road_12.bev [--osm roads.osm] --png out.png [--scale 2]
#include "core/bev/bev_grid.h"
#include "core/bev/bev_render.h"
#include "core/config/map_config.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process_configs.h"
#include "processes/framework/share_dir.h"

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <string>

using namespace lanemap;

int main(int argc, char** argv) {
  CLI::App app("Draws a BEV grid as a PNG: layers in colours, the skeleton in green.");
  std::string bev_path, osm_path, png_path;
  bev::RenderOptions options;
  app.add_option("--bev", bev_path, "BEV grid file (BevGrid::save)")->required()->check(CLI::ExistingFile);
  app.add_option("--osm", osm_path, "OSM file whose skeleton is drawn over it (same ENU origin as the grid)")
      ->check(CLI::ExistingFile);
  std::string map_config = lanemap::kDefaultMapConfig;
  app.add_option("--map-config", map_config, "map block whose skeleton options build the roads drawn")->capture_default_str();
  app.add_option("--png", png_path, "output PNG")->required();
  app.add_option("--scale", options.scale, "pixels per cell side")->check(CLI::Range(1, 16));
  app.add_option("--min-fraction", options.min_fraction, "a layer shows where its share of observations reaches this");
  CLI11_PARSE(app, argc, argv);
  try {
    const bev::BevGrid grid = bev::BevGrid::load(bev_path);
    std::vector<std::vector<Eigen::Vector2d>> lines;
    if (!osm_path.empty()) {
      const auto map = config::MapConfig::fromYamlFile(lanemap::resolveShippedFile(map_config));
      const auto sk = skeleton::Skeleton::build(osm::readOsm(osm_path), map.skeleton);
      for (const auto& r : sk.roads()) lines.push_back(r.polyline);
      for (const auto& i : sk.intersections()) {
        if (i.roi.size() < 3) continue;
        lines.push_back(i.roi);
        lines.back().push_back(i.roi.front());
      }
    }
    const cv::Mat img = bev::renderBev(grid, lines, options);
    if (!cv::imwrite(png_path, img)) throw std::runtime_error("cannot write " + png_path);
    std::printf("lanemap-render: %s: %d frames, %zu tiles -> %s (%dx%d)\n", bev_path.c_str(), grid.frames(),
                grid.tileCount(), png_path.c_str(), img.cols, img.rows);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-render: %s\n", e.what());
    return 2;
  }
}
