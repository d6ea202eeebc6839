// The map block every process that builds the road skeleton shares (config/map.yaml): the OSM file,
// the ENU origin and the skeleton options. The road tracker, the BEV builder, the lane mapper, the
// viewer and lanemap-offline read it through MapConfig::fromYaml, so all of them build the same
// skeleton (same atomic roads, ids and ROIs) from the same file.
//
//   osm: data/osm/west-oakland.osm          # optional; the processes' --osm overrides it
//   origin: {lat: 37.80765, lon: -122.30042} # optional (alt: 0); default: centre of the OSM bounds
//   skeleton: {junction_merge_radius_m: 12.0, ...}   # core/skeleton/skeleton.h SkeletonOptions
//   road_frame: {spacing_m: 0.5, smoothing_m: 6.0}   # the atomic road's Frenet frame
#pragma once

#include "core/config/yaml_reader.h"
#include "core/skeleton/skeleton.h"

#include <string>

namespace lanemap::config {

// The Frenet frame of an atomic road (core/lanes/frenet.h: samples every spacing_m along the
// skeleton polyline, smoothed by a moving average of radius smoothing_m): the frame the lane
// explorer works in and a partial road's station is measured along, so the BEV builder (which
// stores the station) and the lane mapper (which explores up to it) read it from one place.
struct RoadFrameConfig {
  double spacing_m = 0.5;    // (0.05, 5]
  double smoothing_m = 6.0;  // >= 0
};

struct MapConfig {
  std::string osm;  // as written; "" when not given (the processes resolve it: share_dir.h)
  skeleton::SkeletonOptions skeleton;
  RoadFrameConfig road_frame;

  // Reads the keys above from `r` (strict: r.finish() refuses any other key).
  static MapConfig fromYaml(const YamlReader& r);
  // Loads `path` (config/map.yaml); errors are ConfigError naming the file and key.
  static MapConfig fromYamlFile(const std::string& path);
};

// SkeletonOptions from a `skeleton:` section (every key optional; values checked: > 0).
skeleton::SkeletonOptions skeletonOptionsFromYaml(const YamlReader& r);

}  // namespace lanemap::config
