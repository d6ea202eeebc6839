// Each mapping process's config file, read through one function: the process's main and
// lanemap-offline both call these, so the live graph and the offline runner read the same values
// from the same files (tests/config/config_test.cc compares them).
//
// A process config names the shared blocks by file:
//   map: config/map.yaml                       # OSM file, origin, skeleton (core/config/map_config.h)
//   intersections: config/intersections.yaml   # lane mapper and viewer (IntersectionOptions)
// A relative path there is taken from the working directory when it exists there, else from the
// shipped files (processes/framework/share_dir.h: an installation's share/lanemap, or the source
// tree of a build), so a process started anywhere with the shipped configs finds them.
// Every reader is strict: an unknown key or a mistyped value is a config::ConfigError naming the
// file and the key.
#pragma once

#include "core/bev/bev_builder.h"
#include "core/bev/drive_offsets.h"
#include "core/config/map_config.h"
#include "core/config/yaml_reader.h"
#include "core/intersections/intersections.h"
#include "core/lanes/options.h"
#include "core/seg/segmenter.h"
#include "core/tracking/road_tracker.h"
#include "core/viewer/http_server.h"
#include "core/viewer/viewer_state.h"
#include "processes/framework/channels.h"
#include "processes/framework/share_dir.h"

#include <optional>
#include <string>

namespace lanemap {

inline constexpr const char* kDefaultMapConfig = "config/map.yaml";
inline constexpr const char* kDefaultIntersectionsConfig = "config/intersections.yaml";

// Relative file names in configs and flags are resolved with resolveShippedFile: from the current
// folder, else from the shipped files (processes/framework/share_dir.h).

// The map block a process config names in `map:` (default config/map.yaml), loaded strictly.
config::MapConfig mapConfigOf(const config::YamlReader& process_config);
// The intersections block named in `intersections:` (default config/intersections.yaml).
intersections::IntersectionOptions intersectionsOf(const config::YamlReader& process_config);
// The intersections file itself (config/intersections.yaml), strictly.
intersections::IntersectionOptions intersectionsFromFile(const std::string& path);

// config/road_tracker.yaml
struct RoadTrackerSettings {
  config::MapConfig map;
  tracking::RoadTrackerConfig tracker;
  std::string pose_channel = channels::kPose;
  int queue_capacity = 1000;
  static RoadTrackerSettings fromYaml(const config::YamlReader& r);  // the caller calls r.finish()
  static RoadTrackerSettings fromYamlFile(const std::string& path);  // and finish()
};

// config/bev_builder.yaml
struct BevBuilderSettings {
  config::MapConfig map;
  std::string vehicle = "config/vehicle.yaml";  // resolved with resolveShippedFile
  std::string store;
  std::string semantic_channel = channels::kSemanticFront;
  int pose_queue = 1000, semantic_queue = 30, lidar_queue = 10, road_event_queue = 100;
  double preview_period_s = 1.0;     // preview.period_s: BEV_OPEN pictures (0: none)
  int preview_max_px = 512;          // preview.max_px (>= 16)
  double checkpoint_period_s = 1.0;  // checkpoint.period_s: the open road to <store>/bev/open/ (0: none)
  bev::DriveOffsetOptions drive_offset;  // drive_offset: this drive's offset learned on stored roads
  bev::BevBuilderOptions options;
  static BevBuilderSettings fromYaml(const config::YamlReader& r);
  static BevBuilderSettings fromYamlFile(const std::string& path);
};

// `o` in the map block's road frame (the explorer's frame, and the frame a partial road's station
// is measured in: the BEV builder and the lane mapper use the same).
inline lanes::ExplorerOptions withRoadFrame(lanes::ExplorerOptions o, const config::RoadFrameConfig& frame) {
  o.frame_spacing_m = frame.spacing_m;
  o.frame_smoothing_m = frame.smoothing_m;
  return o;
}

// config/lane_mapper.yaml
struct LaneMapperSettings {
  config::MapConfig map;
  intersections::IntersectionOptions intersections;
  lanes::ExplorerOptions explorer;  // the explorer block as read (its frame: explorerOptions())
  std::string store;
  std::string bev_channel = channels::kBevRoad;
  int queue_capacity = 100;
  // lane_map.osm (every road and intersection, core/mapping/map_assembler.h): 0 = written after
  // every road (its cost grows with the store); > 0 = at most once per this many seconds, the
  // last change always within it, and when the process stops (lanes/road_<id>.osm, written per
  // road, are the store either way: a restart writes lane_map.osm again from them).
  double export_interval_s = 0.0;
  // The explorer block with the map block's road frame: what exploreRoad runs with.
  lanes::ExplorerOptions explorerOptions() const { return withRoadFrame(explorer, map.road_frame); }
  static LaneMapperSettings fromYaml(const config::YamlReader& r);
  static LaneMapperSettings fromYamlFile(const std::string& path);
};

// config/viewer.yaml
struct ViewerSettings {
  config::MapConfig map;
  intersections::IntersectionOptions intersections;
  viewer::ViewerOptions viewer;
  viewer::HttpServerOptions server;  // address (`listen`), port, idle_timeout_s, max_connections, event_interval_s
  std::string assets;                // "": <bin>/../share/lanemap/viewer
  int pose_queue = 1000;
  static ViewerSettings fromYaml(const config::YamlReader& r);
  static ViewerSettings fromYamlFile(const std::string& path);
};

// config/segmenter.yaml
struct SegmenterSettings {
  std::string camera_channel = channels::kCameraFront;
  std::string output_channel = channels::kSemanticFront;
  std::string truth_channel = channels::kSemanticFrontTruth;
  bool raw = false;            // encoding: raw (else png)
  int queue_frames = 1;        // 1..8
  int expect_width = 0, expect_height = 0;
  int lcm_queue = 30;
  int debug_delay_ms = 0;
  bool oracle = false;
  int threads = 0;             // cv::setNumThreads when > 0
  // The model block (relative paths: the working directory, else the repository root), its path
  // replaced by `model_path` when given; absent when the config has no model block and no
  // model_path is given (the oracle needs none).
  std::optional<seg::ModelConfig> model;
  static SegmenterSettings fromYaml(const config::YamlReader& r, const std::string& model_path = "");
  static SegmenterSettings fromYamlFile(const std::string& path, const std::string& model_path = "");
};

}  // namespace lanemap
