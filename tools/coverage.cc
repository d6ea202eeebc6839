// lanemap-coverage: what a map store covers of a city (issue 14): per directed atomic road whether
// it is mapped (complete or partial), only driven, or never driven, its traversals and lane
// confidence, and the share of the city's directed road length mapped (core/mapping/coverage.h);
// as a table, JSON, GeoJSON (WGS84) and a PNG. --plan SECONDS: a route for the next drive that
// covers the most unmapped length in that much driving, as intersection ids for lanemap-sim
// --route and a GPX track for a navigation app.
//
//   lanemap-coverage --store map-store --osm city.osm [--json F] [--geojson F] [--png F] [--list]
//                    [--plan 600 --from INTERSECTION [--speed 8] [--gpx F]]
// Exit status: 0; 3 when a file of the store could not be read (named on stderr; its road counts
// as not mapped); 2 on an error (no store, a bad OSM file or config, an unknown intersection).
#include "core/config/map_config.h"
#include "core/io/atomic_file.h"
#include "core/mapping/coverage.h"
#include "core/osm/osm_data.h"
#include "processes/framework/share_dir.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace {

using lanemap::mapping::RoadState;
using lanemap::skeleton::Skeleton;

double round(double v, double unit) { return std::round(v / unit) * unit; }

nlohmann::json roadJson(const lanemap::mapping::RoadCoverage& c) {
  nlohmann::json j{{"road_id", c.road_id}, {"from", c.from}, {"to", c.to}, {"length_m", round(c.length_m, 0.01)},
                   {"state", toString(c.state)}, {"mapped_m", round(c.mapped_m, 0.01)}, {"traversals", c.traversals},
                   {"frames", c.frames}, {"lanes", c.lanes}, {"confidence", nullptr}};
  if (c.confidence) j["confidence"] = round(*c.confidence, 0.001);
  if (!c.problems.empty()) j["problems"] = c.problems;
  return j;
}

nlohmann::json lonLat(const Skeleton& sk, const Eigen::Vector2d& p) {
  const auto g = sk.frame().toWgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
  return nlohmann::json::array({round(g.lon, 1e-8), round(g.lat, 1e-8)});
}

std::string geoJson(const Skeleton& sk, const lanemap::mapping::CityCoverage& cov) {
  nlohmann::json features = nlohmann::json::array();
  for (const auto& c : cov.roads) {
    nlohmann::json coords = nlohmann::json::array();
    for (const auto& p : sk.road(c.road_id)->polyline) coords.push_back(lonLat(sk, p));
    features.push_back({{"type", "Feature"}, {"geometry", {{"type", "LineString"}, {"coordinates", coords}}}, {"properties", roadJson(c)}});
  }
  return nlohmann::json{{"type", "FeatureCollection"}, {"features", features}}.dump() + "\n";
}

// Roads drawn in their driving direction, offset 1.5 m to their right so both directions show:
// mapped green, partial yellow, driven (no lanes) orange, never driven grey.
void writePng(const Skeleton& sk, const lanemap::mapping::CityCoverage& cov, const std::string& path) {
  Eigen::AlignedBox2d box;
  for (const auto& r : sk.roads()) {
    for (const auto& p : r.polyline) box.extend(p);
  }
  if (box.isEmpty()) throw std::runtime_error("no roads to draw");
  box.min() -= Eigen::Vector2d(20, 20);
  box.max() += Eigen::Vector2d(20, 20);
  const double scale = std::min(2.0, 2048.0 / box.sizes().maxCoeff());  // px per metre
  const int w = static_cast<int>(std::ceil(box.sizes().x() * scale)), h = static_cast<int>(std::ceil(box.sizes().y() * scale));
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>((p.x() - box.min().x()) * scale), static_cast<int>((box.max().y() - p.y()) * scale));
  };
  for (const auto& c : cov.roads) {
    const auto& line = sk.road(c.road_id)->polyline;
    const cv::Scalar colour = c.state == RoadState::kMapped    ? cv::Scalar(60, 170, 40)
                              : c.state == RoadState::kPartial ? cv::Scalar(0, 200, 230)
                              : c.state == RoadState::kDriven  ? cv::Scalar(0, 130, 250)
                                                               : cv::Scalar(180, 180, 180);
    std::vector<cv::Point> pts;
    for (size_t i = 0; i < line.size(); ++i) {
      const Eigen::Vector2d d = (line[std::min(i + 1, line.size() - 1)] - line[i > 0 ? i - 1 : 0]).normalized();
      pts.push_back(px(line[i] + 1.5 * Eigen::Vector2d(d.y(), -d.x())));
    }
    cv::polylines(img, pts, false, colour, std::max(1, static_cast<int>(std::lround(2.0 * scale))), cv::LINE_AA);
  }
  std::ostringstream legend;
  legend << static_cast<int>(std::lround(100.0 * cov.share())) << "% of " << static_cast<int>(std::lround(cov.total_m)) << " m mapped";
  cv::putText(img, legend.str(), cv::Point(10, 24), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "green mapped, yellow partial, orange driven, grey never; (c) OpenStreetMap contributors", cv::Point(10, h - 10),
              cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(80, 80, 80), 1, cv::LINE_AA);
  std::vector<uchar> buf;
  if (!cv::imencode(".png", img, buf)) throw std::runtime_error("cannot encode the PNG");
  lanemap::io::writeFileAtomically(path, std::string(buf.begin(), buf.end()));
}

std::string gpx(const Skeleton& sk, const lanemap::mapping::CoveragePlan& plan) {
  std::ostringstream out;
  out.precision(9);
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<gpx version=\"1.1\" creator=\"lanemap-coverage\" "
         "xmlns=\"http://www.topografix.com/GPX/1/1\">\n<trk><name>lanemap coverage plan</name><trkseg>\n";
  for (const int64_t id : plan.roads) {
    for (const auto& p : sk.road(id)->polyline) {
      const auto g = sk.frame().toWgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
      out << "<trkpt lat=\"" << g.lat << "\" lon=\"" << g.lon << "\"/>\n";
    }
  }
  out << "</trkseg></trk>\n</gpx>\n";
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("lanemap-coverage: what a map store covers of a city, and a route for the next drive");
  std::string store, osm, map_config = "config/map.yaml", json_path, geojson_path, png_path, gpx_path;
  bool list = false;
  double plan_s = 0.0, speed = 8.0;
  int64_t from = -1;
  app.add_option("--store", store, "the map store (the BEV builder's and lane mapper's --store), or lanemap-offline's --out")->required();
  app.add_option("--osm", osm, "the city's OSM file, the one the store was built from")->required();
  app.add_option("--map-config", map_config, "skeleton options, as the processes read them (road ids depend on them)")->capture_default_str();
  app.add_option("--json", json_path, "write every road's coverage and the totals as JSON");
  app.add_option("--geojson", geojson_path, "write the roads with their coverage as GeoJSON (WGS84)");
  app.add_option("--png", png_path, "draw the roads coloured by coverage");
  app.add_flag("--list", list, "print one line per directed road");
  auto* plan_opt = app.add_option("--plan", plan_s, "plan a route of this many seconds of driving that covers the most unmapped length")
                       ->check(lanemap::cli::kPositive);
  app.add_option("--from", from, "--plan: the intersection (OSM node id) the drive starts at")->needs(plan_opt);
  app.add_option("--speed", speed, "--plan: mean driving speed, m/s")->capture_default_str()->check(lanemap::cli::kPositive)->needs(plan_opt);
  app.add_option("--gpx", gpx_path, "--plan: write the route as a GPX track")->needs(plan_opt);
  CLI11_PARSE(app, argc, argv);
  try {
    if (plan_s > 0.0 && from < 0) throw std::runtime_error("--plan needs --from INTERSECTION (an OSM node id of lanemap-skeleton's)");
    if (!std::filesystem::is_directory(store)) throw std::runtime_error("no map store folder '" + store + "'");
    const auto map = lanemap::config::MapConfig::fromYamlFile(lanemap::resolveShippedFile(map_config));
    const Skeleton sk = Skeleton::build(lanemap::osm::readOsm(osm), map.skeleton);
    const auto cov = lanemap::mapping::cityCoverage(sk, store);
    if (list) {
      std::printf("%8s %12s %12s %9s %-13s %9s %4s %6s %5s %5s\n", "ROAD", "FROM", "TO", "LENGTH_M", "STATE", "MAPPED_M", "TRAV",
                  "FRAMES", "LANES", "CONF");
      for (const auto& c : cov.roads) {
        std::printf("%8lld %12lld %12lld %9.1f %-13s %9.1f %4d %6d %5d %5s\n", static_cast<long long>(c.road_id),
                    static_cast<long long>(c.from), static_cast<long long>(c.to), c.length_m, toString(c.state), c.mapped_m,
                    c.traversals, c.frames, c.lanes, c.confidence ? std::to_string(*c.confidence).substr(0, 4).c_str() : "-");
      }
    }
    int problems = 0;
    for (const auto& p : cov.problems) {
      std::fprintf(stderr, "lanemap-coverage: %s\n", p.c_str());
      ++problems;
    }
    for (const auto& c : cov.roads) {
      for (const auto& p : c.problems) {
        std::fprintf(stderr, "lanemap-coverage: road %lld: %s\n", static_cast<long long>(c.road_id), p.c_str());
        ++problems;
      }
    }
    std::printf("%zu directed roads, %.0f m: %.0f m mapped (%.1f %%); mapped %d, partial %d, driven without lanes %d, never driven %d\n",
                cov.roads.size(), cov.total_m, cov.mapped_m, 100.0 * cov.share(), cov.count(RoadState::kMapped),
                cov.count(RoadState::kPartial), cov.count(RoadState::kDriven), cov.count(RoadState::kNeverDriven));
    nlohmann::json doc{{"store", store}, {"osm", osm}, {"total_m", round(cov.total_m, 0.01)}, {"mapped_m", round(cov.mapped_m, 0.01)},
                       {"share", round(cov.share(), 1e-4)}, {"roads", nlohmann::json::array()}};
    for (const auto& c : cov.roads) doc["roads"].push_back(roadJson(c));
    if (plan_s > 0.0) {
      const auto plan = lanemap::mapping::planCoverage(sk, cov, from, plan_s, speed);
      std::string route;
      for (const int64_t id : plan.intersections) route += (route.empty() ? "" : ",") + std::to_string(id);
      std::printf("plan: %zu roads, %.0f s at %.1f m/s, %.0f m not mapped yet (%.1f %% of the city)\n  lanemap-sim --route %s\n",
                  plan.roads.size(), plan.seconds, speed, plan.new_m, cov.total_m > 0 ? 100.0 * plan.new_m / cov.total_m : 0.0,
                  route.c_str());
      doc["plan"] = {{"roads", plan.roads}, {"intersections", plan.intersections}, {"seconds", round(plan.seconds, 0.1)},
                     {"new_m", round(plan.new_m, 0.01)}, {"speed_mps", speed}};
      if (!gpx_path.empty()) lanemap::io::writeFileAtomically(gpx_path, gpx(sk, plan));
    }
    if (!json_path.empty()) lanemap::io::writeFileAtomically(json_path, doc.dump(2) + "\n");
    if (!geojson_path.empty()) lanemap::io::writeFileAtomically(geojson_path, geoJson(sk, cov));
    if (!png_path.empty()) writePng(sk, cov, png_path);
    return problems > 0 ? 3 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-coverage: %s\n", e.what());
    return 2;
  }
}
