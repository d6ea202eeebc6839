#include "core/config/map_config.h"

#include <cmath>

namespace lanemap::config {

skeleton::SkeletonOptions skeletonOptionsFromYaml(const YamlReader& r) {
  skeleton::SkeletonOptions o;
  const auto positive = [&r](const char* key, double& v) {
    if (r.read(key, v) && !(v > 0.0 && std::isfinite(v))) r.fail(key, "must be > 0");
  };
  positive("junction_merge_radius_m", o.junction_merge_radius_m);
  positive("roi_min_node_distance_m", o.roi_min_node_distance_m);
  positive("roi_default_extent_m", o.roi_default_extent_m);
  positive("roi_max_extent_m", o.roi_max_extent_m);
  positive("index_cell_m", o.index_cell_m);
  return o;
}

MapConfig MapConfig::fromYaml(const YamlReader& r) {
  MapConfig m;
  r.read("osm", m.osm);
  m.skeleton = skeletonOptionsFromYaml(r.section("skeleton"));
  if (const YamlReader f = r.section("road_frame"); f.present()) {
    if (f.read("spacing_m", m.road_frame.spacing_m) && !(m.road_frame.spacing_m > 0.05 && m.road_frame.spacing_m <= 5.0)) {
      f.fail("spacing_m", "must be in (0.05, 5]");
    }
    if (f.read("smoothing_m", m.road_frame.smoothing_m) && !(m.road_frame.smoothing_m >= 0.0 && std::isfinite(m.road_frame.smoothing_m))) {
      f.fail("smoothing_m", "must be >= 0");
    }
  }
  if (const YamlReader origin = r.section("origin"); origin.present()) {
    geo::LatLonAlt o{origin.required<double>("lat"), origin.required<double>("lon"), origin.get<double>("alt", 0.0)};
    if (!(std::abs(o.lat) <= 90.0)) origin.fail("lat", "must be within [-90, 90]");
    if (!(std::abs(o.lon) <= 180.0)) origin.fail("lon", "must be within [-180, 180]");
    m.skeleton.origin = o;
  }
  return m;
}

MapConfig MapConfig::fromYamlFile(const std::string& path) {
  const YamlReader r = YamlReader::loadFile(path);
  MapConfig m = fromYaml(r);
  r.finish();
  return m;
}

}  // namespace lanemap::config
