#include "processes/framework/process_configs.h"

#include "processes/framework/channels.h"
#include "processes/framework/share_dir.h"

#include <filesystem>

namespace lanemap {

namespace fs = std::filesystem;

namespace {

// The file a process config names in `key` (default `fallback`).
std::string namedFile(const config::YamlReader& r, const char* key, const char* fallback) {
  std::string path = r.get<std::string>(key, fallback);
  if (path.empty()) r.fail(key, "must name a file");
  path = resolveShippedFile(path);
  if (!fs::exists(path)) r.fail(key, "names '" + path + "', which does not exist");
  return path;
}

template <typename Settings>
Settings loadStrictly(const std::string& path) {
  const auto r = config::YamlReader::loadFile(path);
  r.allow({"lcm_url"});  // lanemap::Process's own key
  Settings s = Settings::fromYaml(r);
  r.finish();
  return s;
}

void positiveQueue(const config::YamlReader& r, const char* key, int& v) {
  if (r.read(key, v) && v < 1) r.fail(key, "must be >= 1");
}

}  // namespace

config::MapConfig mapConfigOf(const config::YamlReader& r) {
  config::MapConfig m = config::MapConfig::fromYamlFile(namedFile(r, "map", kDefaultMapConfig));
  m.osm = resolveShippedFile(m.osm);  // the bundled OSM file from any working directory
  return m;
}

intersections::IntersectionOptions intersectionsFromFile(const std::string& path) {
  const auto r = config::YamlReader::loadFile(path);
  const auto o = intersections::IntersectionOptions::fromYaml(r);
  r.finish();
  return o;
}

intersections::IntersectionOptions intersectionsOf(const config::YamlReader& r) {
  return intersectionsFromFile(namedFile(r, "intersections", kDefaultIntersectionsConfig));
}

RoadTrackerSettings RoadTrackerSettings::fromYaml(const config::YamlReader& r) {
  RoadTrackerSettings s;
  s.map = mapConfigOf(r);
  s.tracker = tracking::RoadTrackerConfig::fromYaml(r.section("tracker"));
  r.read("pose_channel", s.pose_channel);
  positiveQueue(r, "queue_capacity", s.queue_capacity);
  return s;
}
RoadTrackerSettings RoadTrackerSettings::fromYamlFile(const std::string& path) { return loadStrictly<RoadTrackerSettings>(path); }

BevBuilderSettings BevBuilderSettings::fromYaml(const config::YamlReader& r) {
  BevBuilderSettings s;
  s.map = mapConfigOf(r);
  r.read("vehicle", s.vehicle);
  r.read("store", s.store);
  r.read("semantic_channel", s.semantic_channel);
  const auto q = r.section("queue_capacity");
  positiveQueue(q, "pose", s.pose_queue);
  positiveQueue(q, "semantic", s.semantic_queue);
  positiveQueue(q, "lidar", s.lidar_queue);
  positiveQueue(q, "road_event", s.road_event_queue);
  const auto preview = r.section("preview");
  if (preview.read("period_s", s.preview_period_s) && !(s.preview_period_s >= 0)) preview.fail("period_s", "must be >= 0");
  if (preview.read("max_px", s.preview_max_px) && s.preview_max_px < 16) preview.fail("max_px", "must be >= 16");
  const auto checkpoint = r.section("checkpoint");
  if (checkpoint.read("period_s", s.checkpoint_period_s) && !(s.checkpoint_period_s >= 0)) checkpoint.fail("period_s", "must be >= 0");
  const auto drive_offset = r.section("drive_offset");
  drive_offset.read("enabled", s.drive_offset.enabled);
  if (drive_offset.read("min_roads", s.drive_offset.min_roads) && s.drive_offset.min_roads < 1) drive_offset.fail("min_roads", "must be >= 1");
  if (drive_offset.read("max_spread_m", s.drive_offset.max_spread_m) && !(s.drive_offset.max_spread_m > 0)) {
    drive_offset.fail("max_spread_m", "must be > 0");
  }
  s.options = bev::BevBuilderOptions::fromYaml(r);
  return s;
}
BevBuilderSettings BevBuilderSettings::fromYamlFile(const std::string& path) { return loadStrictly<BevBuilderSettings>(path); }

LaneMapperSettings LaneMapperSettings::fromYaml(const config::YamlReader& r) {
  LaneMapperSettings s;
  s.map = mapConfigOf(r);
  s.intersections = intersectionsOf(r);
  s.explorer = lanes::ExplorerOptions::fromYaml(r.section("explorer"));
  r.read("store", s.store);
  r.read("bev_channel", s.bev_channel);
  positiveQueue(r, "queue_capacity", s.queue_capacity);
  if (r.read("export_interval_s", s.export_interval_s) && !(s.export_interval_s >= 0.0 && s.export_interval_s <= 86400.0)) {
    r.fail("export_interval_s", "must be within [0, 86400] seconds");
  }
  return s;
}
LaneMapperSettings LaneMapperSettings::fromYamlFile(const std::string& path) { return loadStrictly<LaneMapperSettings>(path); }

ViewerSettings ViewerSettings::fromYaml(const config::YamlReader& r) {
  ViewerSettings s;
  s.map = mapConfigOf(r);
  s.intersections = intersectionsOf(r);
  r.read("listen", s.server.address);
  int port = s.server.port;
  if (r.read("port", port) && (port < 0 || port > 65535)) r.fail("port", "must be within [0, 65535]");
  s.server.port = static_cast<uint16_t>(port);
  r.read("assets", s.assets);
  r.read("idle_timeout_s", s.server.idle_timeout_s);
  r.read("max_connections", s.server.max_connections);
  r.read("event_interval_s", s.server.event_interval_s);
  r.read("trail_spacing_m", s.viewer.trail_spacing_m);
  r.read("bev_max_px", s.viewer.bev_max_px);
  r.read("status_stale_s", s.viewer.status_stale_s);
  positiveQueue(r, "pose_queue", s.pose_queue);
  return s;
}
ViewerSettings ViewerSettings::fromYamlFile(const std::string& path) { return loadStrictly<ViewerSettings>(path); }

SegmenterSettings SegmenterSettings::fromYaml(const config::YamlReader& r, const std::string& model_path) {
  SegmenterSettings s;
  r.read("camera_channel", s.camera_channel);
  r.read("output_channel", s.output_channel);
  r.read("truth_channel", s.truth_channel);
  const std::string encoding = r.get<std::string>("encoding", "png");
  if (encoding != "png" && encoding != "raw") r.fail("encoding", "must be png or raw, not '" + encoding + "'");
  s.raw = encoding == "raw";
  if (r.read("queue_frames", s.queue_frames) && (s.queue_frames < 1 || s.queue_frames > 8)) {
    r.fail("queue_frames", "must be 1..8");
  }
  r.read("expect_width", s.expect_width);
  r.read("expect_height", s.expect_height);
  positiveQueue(r, "lcm_queue", s.lcm_queue);
  r.read("debug_delay_ms", s.debug_delay_ms);
  r.read("oracle", s.oracle);
  r.read("threads", s.threads);
  if (r.has("model") || !model_path.empty()) {
    // With model_path, the model is named by its stem unless it is the config's own file.
    s.model = seg::ModelConfig::fromYaml(r.section("model"), shareDir().string(), model_path);
  }
  return s;
}
SegmenterSettings SegmenterSettings::fromYamlFile(const std::string& path, const std::string& model_path) {
  const auto r = config::YamlReader::loadFile(path);
  r.allow({"lcm_url"});
  SegmenterSettings s = fromYaml(r, model_path);
  r.finish();
  return s;
}

}  // namespace lanemap
