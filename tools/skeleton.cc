// lanemap-skeleton: builds the map skeleton M0 from an OSM file and prints its size; optionally
// writes it as GeoJSON (roads as LineStrings, intersection ROIs as Polygons, WGS84) and as a PNG
// drawing (roads with direction arrows, ROI polygons, scale bar, OSM attribution).
//
//   lanemap-skeleton --osm data/osm/west-oakland.osm --geojson /tmp/wo.geojson --png /tmp/wo.png
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <vector>

namespace {

using lanemap::skeleton::Skeleton;

nlohmann::json lonLat(const Skeleton& sk, const Eigen::Vector2d& p) {
  const auto g = sk.frame().toWgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
  return nlohmann::json::array({std::round(g.lon * 1e8) / 1e8, std::round(g.lat * 1e8) / 1e8});
}

void writeGeoJson(const Skeleton& sk, const std::string& path) {
  nlohmann::json features = nlohmann::json::array();
  for (const auto& r : sk.roads()) {
    nlohmann::json coords = nlohmann::json::array();
    for (const auto& p : r.polyline) coords.push_back(lonLat(sk, p));
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "LineString"}, {"coordinates", coords}}},
                        {"properties",
                         {{"kind", "atomic_road"}, {"id", r.id}, {"from", r.from}, {"to", r.to},
                          {"way_id", r.way_id}, {"reverse_id", r.reverse_id},
                          {"length", std::round(r.length * 100) / 100},
                          {"s_begin", std::round(r.s_begin * 100) / 100},
                          {"s_end", std::round(r.s_end * 100) / 100},
                          {"highway", r.tags.count("highway") ? r.tags.at("highway") : ""}}}});
  }
  for (const auto& in : sk.intersections()) {
    nlohmann::json ring = nlohmann::json::array();
    for (const auto& p : in.roi) ring.push_back(lonLat(sk, p));
    ring.push_back(lonLat(sk, in.roi.front()));
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "Polygon"}, {"coordinates", {ring}}}},
                        {"properties",
                         {{"kind", "intersection"}, {"id", in.id}, {"osm_nodes", in.osm_nodes},
                          {"dead_end", in.dead_end}, {"incoming", in.incoming},
                          {"outgoing", in.outgoing}}}});
  }
  nlohmann::json doc = {{"type", "FeatureCollection"}, {"features", features}};
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write GeoJSON file '" + path + "'");
  out << doc.dump() << "\n";
  if (!out) throw std::runtime_error("error writing GeoJSON file '" + path + "'");
}

// Drawing: ENU -> pixels with north up.
struct Canvas {
  Eigen::Vector2d lo, hi;
  double scale = 1.0;  // px per metre
  int margin = 30;
  cv::Point px(const Eigen::Vector2d& p) const {
    return cv::Point(static_cast<int>(std::lround(margin + (p.x() - lo.x()) * scale)),
                     static_cast<int>(std::lround(margin + (hi.y() - p.y()) * scale)));
  }
};

// Draws the skeleton; `bbox` (min_lat, min_lon, max_lat, max_lon) zooms on a part of it.
void writePng(const Skeleton& sk, const std::string& path, int max_px, const std::vector<double>& bbox) {
  Canvas c;
  if (bbox.size() == 4) {
    c.lo = sk.frame().toEnu(bbox[0], bbox[1], 0.0).head<2>();
    c.hi = sk.frame().toEnu(bbox[2], bbox[3], 0.0).head<2>();
  } else {
    c.lo = c.hi = sk.roads().front().polyline.front();
    for (const auto& r : sk.roads()) {
      for (const auto& p : r.polyline) {
        c.lo = c.lo.cwiseMin(p);
        c.hi = c.hi.cwiseMax(p);
      }
    }
  }
  const Eigen::Vector2d size = (c.hi - c.lo).cwiseMax(Eigen::Vector2d(1, 1));
  c.scale = (max_px - 2 * c.margin) / std::max(size.x(), size.y());
  const int w = static_cast<int>(size.x() * c.scale) + 2 * c.margin;
  const int h = static_cast<int>(size.y() * c.scale) + 2 * c.margin + 40;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const int thick = std::max(1, static_cast<int>(std::lround(c.scale * 1.2)));

  for (const auto& in : sk.intersections()) {
    std::vector<cv::Point> poly;
    for (const auto& p : in.roi) poly.push_back(c.px(p));
    const cv::Scalar fill = in.dead_end ? cv::Scalar(200, 200, 200) : cv::Scalar(160, 220, 255);
    cv::fillPoly(img, std::vector<std::vector<cv::Point>>{poly}, fill, cv::LINE_AA);
    cv::polylines(img, std::vector<std::vector<cv::Point>>{poly}, true, cv::Scalar(0, 140, 255), 1,
                  cv::LINE_AA);
  }
  for (const auto& r : sk.roads()) {
    // Each direction drawn a little to its right, so both directions of a two-way road show.
    const double offset = r.reverse_id >= 0 ? 2.0 / c.scale + 0.8 : 0.0;
    const cv::Scalar colour = r.reverse_id >= 0 ? cv::Scalar(90, 90, 90) : cv::Scalar(200, 60, 0);
    std::vector<cv::Point> line;
    const int n = std::max(2, static_cast<int>(r.length / 2.0));
    for (int i = 0; i <= n; ++i) {
      const double s = r.length * i / n;
      const Eigen::Vector2d t = sk.tangentAt(r, s);
      const Eigen::Vector2d right(t.y(), -t.x());
      line.push_back(c.px(sk.pointAt(r, s) + offset * right));
    }
    cv::polylines(img, std::vector<std::vector<cv::Point>>{line}, false, colour, thick, cv::LINE_AA);
    // Direction arrow in the middle of the part between the ROIs.
    const double sm = 0.5 * (r.s_begin + r.s_end);
    const double len = std::min(0.4 * (r.s_end - r.s_begin), 30.0 / c.scale);  // about 30 px
    if (len > 0.5) {
      const Eigen::Vector2d t = sk.tangentAt(r, sm);
      const Eigen::Vector2d right(t.y(), -t.x());
      const Eigen::Vector2d m = sk.pointAt(r, sm) + offset * right;
      cv::arrowedLine(img, c.px(m - 0.5 * len * t), c.px(m + 0.5 * len * t), colour, thick,
                      cv::LINE_AA, 0, 0.5);
    }
  }
  // Legend strip (roads of a --bbox view may run under it).
  cv::rectangle(img, cv::Point(0, h - 40), cv::Point(w, h), cv::Scalar(255, 255, 255), cv::FILLED);
  // Scale bar: a round length of about a fifth of the width.
  const double target = 0.2 * (w - 2 * c.margin) / c.scale;
  double bar = std::pow(10.0, std::floor(std::log10(target)));
  for (double m : {5.0, 2.0}) {
    if (bar * m <= target) {
      bar *= m;
      break;
    }
  }
  const int y = h - 25;
  const cv::Point a(c.margin, y), b(c.margin + static_cast<int>(bar * c.scale), y);
  cv::line(img, a, b, cv::Scalar(0, 0, 0), 3);
  cv::line(img, a + cv::Point(0, -6), a + cv::Point(0, 6), cv::Scalar(0, 0, 0), 2);
  cv::line(img, b + cv::Point(0, -6), b + cv::Point(0, 6), cv::Scalar(0, 0, 0), 2);
  char label[32];
  std::snprintf(label, sizeof label, "%g m", bar);
  cv::putText(img, label, b + cv::Point(8, 6), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  const std::string attribution = "(c) OpenStreetMap contributors, ODbL";
  int base = 0;
  const cv::Size ts = cv::getTextSize(attribution, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &base);
  cv::putText(img, attribution, cv::Point(w - ts.width - 10, h - 10), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write PNG file '" + path + "'");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Builds the OSM map skeleton M0 (atomic roads and intersections) and prints it"};
  std::string osm_path, geojson_path, png_path;
  double merge_radius = 12.0;
  int png_size = 1600;
  std::vector<double> bbox;
  app.add_option("--osm", osm_path, "OSM file (.osm or .osm.pbf)")->required();
  app.add_option("--geojson", geojson_path, "write roads and intersection ROIs as GeoJSON");
  app.add_option("--png", png_path, "write a drawing of the skeleton");
  app.add_option("--png-size", png_size, "largest side of the PNG in pixels")->check(CLI::Range(200, 20000));
  app.add_option("--bbox", bbox, "PNG extent: min_lat min_lon max_lat max_lon (default: all roads)")
      ->expected(4);
  app.add_option("--merge-radius", merge_radius, "junction_merge_radius_m")->check(CLI::Range(0.0, 100.0));
  CLI11_PARSE(app, argc, argv);

  try {
    const auto data = lanemap::osm::readOsm(osm_path);
    lanemap::skeleton::SkeletonOptions options;
    options.junction_merge_radius_m = merge_radius;
    const Skeleton sk = Skeleton::build(data, options);
    int dead_ends = 0, merged = 0;
    for (const auto& in : sk.intersections()) {
      dead_ends += in.dead_end ? 1 : 0;
      merged += in.osm_nodes.size() > 1 ? 1 : 0;
    }
    int oneway = 0;
    double km = 0.0;
    for (const auto& r : sk.roads()) {
      oneway += r.reverse_id < 0 ? 1 : 0;
      km += r.length / 1000.0;
    }
    const auto& o = sk.frame().origin();
    std::printf("osm file:        %s\n", osm_path.c_str());
    std::printf("drivable ways:   %zu (nodes %zu, turn restrictions %zu)\n", data.ways.size(),
                data.nodes.size(), data.restrictions.size());
    std::printf("ENU origin:      lat %.7f lon %.7f\n", o.lat, o.lon);
    std::printf("intersections:   %zu (junctions %zu, dead ends %d, merged from several nodes %d)\n",
                sk.intersections().size(), sk.intersections().size() - dead_ends, dead_ends, merged);
    std::printf("atomic roads:    %zu (one-way %d)\n", sk.roads().size(), oneway);
    std::printf("total length:    %.3f km of atomic roads\n", km);
    if (!geojson_path.empty()) {
      writeGeoJson(sk, geojson_path);
      std::printf("wrote %s\n", geojson_path.c_str());
    }
    if (!png_path.empty()) {
      writePng(sk, png_path, png_size, bbox);
      std::printf("wrote %s\n", png_path.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-skeleton: %s\n", e.what());
    return 1;
  }
  return 0;
}
