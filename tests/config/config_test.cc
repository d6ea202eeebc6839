// The configs in config/ and their one strict reader (core/config/yaml_reader.h): every file there
// loads through the reader of the program that uses it (a new file without one fails the test);
// an unknown key and a mistyped value in a copy are errors naming the file and the key; and the
// live processes and lanemap-offline read the same skeleton and intersection options from the
// same files (processes/framework/process_configs.h).
#include "core/camera/camera_model.h"
#include "core/config/map_config.h"
#include "core/config/vehicle_config.h"
#include "core/config/yaml_reader.h"
#include "core/seg/segmenter.h"
#include "core/sim/drive.h"
#include "core/sim/lidar_scanner.h"
#include "core/sim/pose_noise.h"
#include "core/sim/world_builder.h"
#include "processes/framework/process_configs.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>

namespace {

namespace fs = std::filesystem;
namespace lt = lanemap::testing;
using lanemap::config::ConfigError;
using lanemap::config::YamlReader;

const std::string kConfigDir = std::string(LANEMAP_SOURCE_DIR) + "/config";

// Runs a program on a shipped config; the command must load it (exit 0, or the expected failure
// that comes after loading, given by `after_load`).
void runs(const std::string& cmd, int rc, const std::string& after_load = "") {
  const auto r = lt::runCommand("timeout 30 " + cmd);
  EXPECT_EQ(r.exit_code, rc) << cmd << "\n" << r.output;
  if (!after_load.empty()) {
    EXPECT_NE(r.output.find(after_load), std::string::npos) << cmd << "\n" << r.output;
  }
  EXPECT_EQ(r.output.find("unknown key"), std::string::npos) << r.output;
}

// The reader of each file in config/ and config/launch/, as its program reads it.
std::map<std::string, std::function<void(const std::string&)>> readers() {
  using namespace lanemap;
  std::map<std::string, std::function<void(const std::string&)>> m;
  m["map.yaml"] = [](const std::string& f) { (void)config::MapConfig::fromYamlFile(f); };
  m["intersections.yaml"] = [](const std::string& f) { (void)intersectionsFromFile(f); };
  m["road_tracker.yaml"] = [](const std::string& f) { (void)RoadTrackerSettings::fromYamlFile(f); };
  m["bev_builder.yaml"] = [](const std::string& f) { (void)BevBuilderSettings::fromYamlFile(f); };
  m["lane_mapper.yaml"] = [](const std::string& f) { (void)LaneMapperSettings::fromYamlFile(f); };
  m["viewer.yaml"] = [](const std::string& f) { (void)ViewerSettings::fromYamlFile(f); };
  m["vehicle.yaml"] = [](const std::string& f) {
    (void)config::VehicleConfig::fromYamlFile(f);   // the BEV builder's and lanemap-offline's
    (void)sim::LidarScannerOptions::fromYamlFile(f);  // the simulator's
  };
  m["segmenter.yaml"] = [](const std::string& f) {
    const auto s = SegmenterSettings::fromYamlFile(f);  // lanemap-segmenter's and lanemap-offline's
    ASSERT_TRUE(s.model.has_value());
    // The same model as the YAML::Node reader gives (the tests' and benchmarks' path), with and
    // without a --model override.
    for (const std::string over : {"", "/tmp/other.onnx"}) {
      const auto a = SegmenterSettings::fromYamlFile(f, over).model.value();
      const auto b = seg::ModelConfig::fromSegmenterConfig(YAML::LoadFile(f), over, LANEMAP_SOURCE_DIR);
      EXPECT_EQ(a.path, b.path);
      EXPECT_EQ(a.name, b.name);
      EXPECT_EQ(a.input_width, b.input_width);
      EXPECT_EQ(a.input_height, b.input_height);
      EXPECT_EQ(a.crop_top, b.crop_top);
      EXPECT_EQ(a.rgb, b.rgb);
      EXPECT_EQ(a.scale, b.scale);
      EXPECT_EQ(a.mean, b.mean);
      EXPECT_EQ(a.std, b.std);
      EXPECT_EQ(a.output, b.output);
      EXPECT_EQ(a.class_map, b.class_map);
      EXPECT_EQ(a.upsample_scores, b.upsample_scores);
    }
    EXPECT_EQ(SegmenterSettings::fromYamlFile(f, "/tmp/other.onnx").model->path, "/tmp/other.onnx");
  };
  m["sim_world.yaml"] = [](const std::string& f) { (void)sim::WorldOptions::fromYamlFile(f); };
  m["sim_drive.yaml"] = [](const std::string& f) {  // lanemap-sim reads its two sections
    const auto r = YamlReader::loadFile(f);
    (void)sim::DriveOptions::fromYaml(r.section("drive"));
    (void)sim::PoseNoiseOptions::fromYaml(r.section("pose_noise"));
    r.finish();
  };
  // The drivers read theirs in their executables (strictly: tests/drivers show unknown keys fail).
  m["pose_nmea.yaml"] = [](const std::string& f) {
    runs(lt::binPath("lanemap-pose-nmea") + " --lcm-url memq:// --config " + f + " --file /dev/null", 0);
  };
  m["lidar_vlp16.yaml"] = [](const std::string& f) {
    runs(lt::binPath("lanemap-lidar-vlp16") + " --lcm-url memq:// --rate-scale 0 --pcap " +
             lt::dataPath("lidar/vlp16_sample.pcap") + " --config " + f, 0);
  };
  m["camera_v4l2.yaml"] = [](const std::string& f) {
    runs(lt::binPath("lanemap-camera-v4l2") + " --lcm-url memq:// --config " + f + " --device /dev/null", 2,
         "not a V4L2 device");
  };
  return m;
}

TEST(Config, EveryShippedFileLoadsThroughItsReader) {
  const auto m = readers();
  int files = 0;
  for (const auto& e : fs::directory_iterator(kConfigDir)) {
    if (e.path().extension() != ".yaml") continue;
    ++files;
    const std::string name = e.path().filename().string();
    const auto it = m.find(name);
    if (it == m.end()) {
      ADD_FAILURE() << "config/" << name << " has no reader in tests/config/config_test.cc: add the one its program uses";
      continue;
    }
    SCOPED_TRACE(name);
    EXPECT_NO_THROW(it->second(e.path().string()));
  }
  EXPECT_GE(files, 13);
  int launch_files = 0;
  for (const auto& e : fs::directory_iterator(kConfigDir + "/launch")) {
    if (e.path().extension() != ".yaml") continue;
    ++launch_files;
    const auto r = lt::runCommand(lt::binPath("lanemap-launch") + " " + e.path().string() + " --list");
    EXPECT_EQ(r.exit_code, 0) << e.path() << "\n" << r.output;
    // Every config a launch file hands a lanemap process exists and loads.
    const YAML::Node launch = YAML::LoadFile(e.path().string());
    for (const auto& p : launch["processes"]) {
      if (!p["config"]) continue;
      const std::string cfg = p["config"].as<std::string>();
      if (cfg.find("${") != std::string::npos) continue;  // a variable (replay.yaml's bev_config, default below)
      EXPECT_TRUE(fs::exists(fs::path(LANEMAP_SOURCE_DIR) / cfg)) << e.path() << ": " << cfg;
      EXPECT_TRUE(m.count(fs::path(cfg).filename().string())) << cfg;
    }
    if (launch["vars"] && launch["vars"]["bev_config"]) {
      EXPECT_NO_THROW(lanemap::BevBuilderSettings::fromYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/" +
                                                                launch["vars"]["bev_config"].as<std::string>()));
    }
  }
  EXPECT_EQ(launch_files, 3);
}

// A copy of config/<name> with `edit` applied, written into `dir`.
std::string editedCopy(const lt::TempDir& dir, const std::string& name, const std::function<void(YAML::Node&)>& edit) {
  YAML::Node n = YAML::LoadFile(kConfigDir + "/" + name);
  edit(n);
  const std::string path = dir.str(name);
  std::ofstream(path) << n << "\n";
  return path;
}

// What `load` throws: a ConfigError naming `file` and `key`, whose message says both and `says`.
void expectError(const std::function<void()>& load, const std::string& file, const std::string& key, const std::string& says) {
  try {
    load();
    ADD_FAILURE() << "no error for " << key << " in " << file;
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), file) << what;
    EXPECT_EQ(e.key(), key) << what;
    EXPECT_EQ(what.rfind(file + ":", 0), 0u) << what;  // "FILE:LINE: ..."
    if (!key.empty()) {  // the dotted key, or the last part in its section ("unknown key 'x' in 'a.b'")
      const std::string last = key.substr(key.rfind('.') + 1);
      EXPECT_TRUE(what.find("'" + key + "'") != std::string::npos || what.find("'" + last + "'") != std::string::npos) << what;
    }
    EXPECT_NE(what.find(says), std::string::npos) << what;
  }
}

TEST(Config, UnknownKeysAreErrorsNamingFileAndKey) {
  using namespace lanemap;
  lt::TempDir dir("config-unknown");
  // A typo inside a section, with the key it was meant to be.
  std::string f = editedCopy(dir, "bev_builder.yaml", [](YAML::Node& n) { n["grid"]["resoluton_m"] = 0.1; });
  expectError([&] { BevBuilderSettings::fromYamlFile(f); }, f, "grid.resoluton_m", "did you mean 'resolution_m'?");
  expectError([&] { BevBuilderSettings::fromYamlFile(f); }, f, "grid.resoluton_m", "in 'grid'");
  // Two levels down.
  f = editedCopy(dir, "bev_builder.yaml", [](YAML::Node& n) { n["lidar"]["ground"]["sector"] = 16; });
  expectError([&] { BevBuilderSettings::fromYamlFile(f); }, f, "lidar.ground.sector", "did you mean 'sectors'?");
  // At the top level: the skeleton option the process configs used to copy now lives in map.yaml.
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["junction_merge_radius_m"] = 12.0; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "junction_merge_radius_m", "unknown key");
  f = editedCopy(dir, "road_tracker.yaml", [](YAML::Node& n) { n["tracker"]["pose_gap"] = 1.0; });
  expectError([&] { RoadTrackerSettings::fromYamlFile(f); }, f, "tracker.pose_gap", "did you mean 'pose_gap_s'?");
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["explorer"]["num_particle"] = 100; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "explorer.num_particle", "did you mean 'num_particles'?");
  f = editedCopy(dir, "viewer.yaml", [](YAML::Node& n) { n["prot"] = 8080; });
  expectError([&] { ViewerSettings::fromYamlFile(f); }, f, "prot", "did you mean 'port'?");
  f = editedCopy(dir, "intersections.yaml", [](YAML::Node& n) { n["allow_uturns"] = true; });
  expectError([&] { intersectionsFromFile(f); }, f, "allow_uturns", "did you mean 'allow_u_turns'?");
  // The explorer's frame keys moved to the map block: the error says where.
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["explorer"]["frame_smoothing_m"] = 6.0; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "explorer.frame_smoothing_m", "road_frame {spacing_m, smoothing_m} in config/map.yaml");
  f = editedCopy(dir, "map.yaml", [](YAML::Node& n) { n["road_frame"]["smoothing"] = 6.0; });
  expectError([&] { config::MapConfig::fromYamlFile(f); }, f, "road_frame.smoothing", "did you mean 'smoothing_m'?");
  f = editedCopy(dir, "map.yaml", [](YAML::Node& n) { n["skeleton"]["junction_radius_m"] = 5.0; });
  expectError([&] { config::MapConfig::fromYamlFile(f); }, f, "skeleton.junction_radius_m", "unknown key");
  const std::string map = f;
  f = editedCopy(dir, "vehicle.yaml", [](YAML::Node& n) { n["camera"]["mount"]["pich_deg"] = 4.0; });
  expectError([&] { config::VehicleConfig::fromYamlFile(f); }, f, "camera.mount.pich_deg", "did you mean 'pitch_deg'?");
  f = editedCopy(dir, "vehicle.yaml", [](YAML::Node& n) { n["lidar"]["rmp"] = 600; });
  expectError([&] { config::VehicleConfig::fromYamlFile(f); }, f, "lidar.rmp", "did you mean 'rpm'?");
  f = editedCopy(dir, "segmenter.yaml", [](YAML::Node& n) { n["model"]["crop_tp"] = 120; });
  expectError([&] { SegmenterSettings::fromYamlFile(f); }, f, "model.crop_tp", "did you mean 'crop_top'?");
  f = editedCopy(dir, "sim_world.yaml", [](YAML::Node& n) { n["surface"]["max_grad"] = 0.05; });
  try {
    sim::WorldOptions::fromYamlFile(f);
    ADD_FAILURE() << "no error";
  } catch (const sim::WorldConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(f + ":"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("did you mean 'max_grade'?"), std::string::npos) << e.what();
  }
  // The map file a process config names is read strictly too, and its errors name that file.
  f = editedCopy(dir, "road_tracker.yaml", [&](YAML::Node& n) { n["map"] = map; });
  expectError([&] { RoadTrackerSettings::fromYamlFile(f); }, map, "skeleton.junction_radius_m", "unknown key");
}

TEST(Config, MistypedValuesAreErrorsNamingFileAndKey) {
  using namespace lanemap;
  lt::TempDir dir("config-type");
  std::string f = editedCopy(dir, "bev_builder.yaml", [](YAML::Node& n) { n["grid"]["resolution_m"] = "fine"; });
  expectError([&] { BevBuilderSettings::fromYamlFile(f); }, f, "grid.resolution_m", "must be a number, not 'fine'");
  f = editedCopy(dir, "bev_builder.yaml", [](YAML::Node& n) { n["lidar"]["ground"]["range_edges_m"] = 3.0; });
  expectError([&] { BevBuilderSettings::fromYamlFile(f); }, f, "lidar.ground.range_edges_m", "must be a list of numbers");
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["explorer"]["num_particles"] = 2.5; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "explorer.num_particles", "must be an integer");
  f = editedCopy(dir, "road_tracker.yaml", [](YAML::Node& n) { n["tracker"] = 3; });
  expectError([&] { RoadTrackerSettings::fromYamlFile(f); }, f, "tracker", "must be a map of keys");
  f = editedCopy(dir, "intersections.yaml", [](YAML::Node& n) { n["right_hand_traffic"] = "maybe"; });
  expectError([&] { intersectionsFromFile(f); }, f, "right_hand_traffic", "must be true or false");
  f = editedCopy(dir, "map.yaml", [](YAML::Node& n) { n["skeleton"]["junction_merge_radius_m"] = -3.0; });
  expectError([&] { config::MapConfig::fromYamlFile(f); }, f, "skeleton.junction_merge_radius_m", "must be > 0");
  f = editedCopy(dir, "map.yaml", [](YAML::Node& n) { n["road_frame"]["spacing_m"] = 0.0; });
  expectError([&] { config::MapConfig::fromYamlFile(f); }, f, "road_frame.spacing_m", "must be in (0.05, 5]");
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["export_interval_s"] = -5.0; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "export_interval_s", "must be within [0, 86400] seconds");
  f = editedCopy(dir, "viewer.yaml", [](YAML::Node& n) { n["port"] = 70000; });
  expectError([&] { ViewerSettings::fromYamlFile(f); }, f, "port", "must be within [0, 65535]");
  f = editedCopy(dir, "vehicle.yaml", [](YAML::Node& n) { n["camera"]["width"] = "wide"; });
  expectError([&] { config::VehicleConfig::fromYamlFile(f); }, f, "camera.width", "must be an integer, not 'wide'");
  f = editedCopy(dir, "vehicle.yaml", [](YAML::Node& n) { n["lidar"]["mount"].remove("z"); });
  expectError([&] { config::VehicleConfig::fromYamlFile(f); }, f, "lidar.mount.z", "is required");
  f = editedCopy(dir, "segmenter.yaml", [](YAML::Node& n) { n["model"]["mean"] = YAML::Load("[0.5, 0.5]"); });
  expectError([&] { SegmenterSettings::fromYamlFile(f); }, f, "model.mean", "must be 3 numbers");
  f = editedCopy(dir, "segmenter.yaml", [](YAML::Node& n) { n["queue_frames"] = 0; });
  expectError([&] { SegmenterSettings::fromYamlFile(f); }, f, "queue_frames", "must be 1..8");
  // A value check over the section (the explorer's ranges) names the file and the section.
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["explorer"]["v_min"] = 2.0; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "explorer", "0 < v_min <= v_max");
  // A map file that is not there.
  f = editedCopy(dir, "lane_mapper.yaml", [](YAML::Node& n) { n["intersections"] = "/nonexistent/intersections.yaml"; });
  expectError([&] { LaneMapperSettings::fromYamlFile(f); }, f, "intersections", "does not exist");
}

TEST(Config, ReaderBasics) {
  const YamlReader r(YAML::Load("a: 1\nempty:\ns: {x: 2}\n"), "t.yaml");
  EXPECT_EQ(r.get<int>("a", 0), 1);
  EXPECT_EQ(r.get<int>("empty", 7), 7);  // a null value counts as absent
  EXPECT_EQ(r.get<int>("missing", 8), 8);
  EXPECT_FALSE(r.section("none").present());
  EXPECT_EQ(r.section("s").get<double>("x", 0.0), 2.0);
  EXPECT_EQ(r.section("s").keyPath("x"), "s.x");
  EXPECT_NO_THROW(r.finish());
  const YamlReader q(YAML::Load("a: 1\n"), "q.yaml");
  expectError([&] { q.required<int>("b"); }, "q.yaml", "b", "is required");
  expectError([&] { YamlReader::loadFile("/nonexistent/c.yaml"); }, "/nonexistent/c.yaml", "", "cannot read");
  lt::TempDir dir("config-reader");
  std::ofstream(dir.str("bad.yaml")) << "a: [1, 2\n";
  try {
    YamlReader::loadFile(dir.str("bad.yaml"));
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.str("bad.yaml") + ":"), std::string::npos) << e.what();
  }
  std::ofstream(dir.str("list.yaml")) << "- 1\n- 2\n";
  expectError([&] { YamlReader::loadFile(dir.str("list.yaml")); }, dir.str("list.yaml"), "", "must be a map");
}

void expectSameSkeleton(const lanemap::skeleton::SkeletonOptions& a, const lanemap::skeleton::SkeletonOptions& b) {
  EXPECT_EQ(a.junction_merge_radius_m, b.junction_merge_radius_m);
  ASSERT_EQ(a.origin.has_value(), b.origin.has_value());
  if (a.origin) {
    EXPECT_EQ(a.origin->lat, b.origin->lat);
    EXPECT_EQ(a.origin->lon, b.origin->lon);
    EXPECT_EQ(a.origin->alt, b.origin->alt);
  }
  EXPECT_EQ(a.roi_min_node_distance_m, b.roi_min_node_distance_m);
  EXPECT_EQ(a.roi_default_extent_m, b.roi_default_extent_m);
  EXPECT_EQ(a.roi_max_extent_m, b.roi_max_extent_m);
  EXPECT_EQ(a.index_cell_m, b.index_cell_m);
}

void expectSameIntersections(const lanemap::intersections::IntersectionOptions& a,
                             const lanemap::intersections::IntersectionOptions& b) {
  EXPECT_EQ(a.right_hand_traffic, b.right_hand_traffic);
  EXPECT_EQ(a.allow_u_turns, b.allow_u_turns);
  EXPECT_EQ(a.use_turn_lanes, b.use_turn_lanes);
  EXPECT_EQ(a.use_restrictions, b.use_restrictions);
  EXPECT_EQ(a.pockets_are_turn_lanes, b.pockets_are_turn_lanes);
  EXPECT_EQ(a.connect_orphan_lanes, b.connect_orphan_lanes);
  EXPECT_EQ(a.straight_max_deg, b.straight_max_deg);
  EXPECT_EQ(a.uturn_min_deg, b.uturn_min_deg);
  EXPECT_EQ(a.end_tolerance_m, b.end_tolerance_m);
  EXPECT_EQ(a.unseen_end_m, b.unseen_end_m);
  EXPECT_EQ(a.lane_tangent_m, b.lane_tangent_m);
  EXPECT_EQ(a.road_tangent_m, b.road_tangent_m);
  EXPECT_EQ(a.pocket_min_m, b.pocket_min_m);
  EXPECT_EQ(a.curve.parallel_deg, b.curve.parallel_deg);
  EXPECT_EQ(a.curve.min_control_fraction, b.curve.min_control_fraction);
  EXPECT_EQ(a.curve.max_control_fraction, b.curve.max_control_fraction);
  EXPECT_EQ(a.curve.cubic_handle_fraction, b.curve.cubic_handle_fraction);
  EXPECT_EQ(a.curve.step_m, b.curve.step_m);
  EXPECT_EQ(a.id_base, b.id_base);
}

// The lane mapper, the road tracker, the BEV builder and the viewer (each through its settings'
// fromYaml, as its main calls it) and lanemap-offline (which loads the lane mapper's, tracker's and
// BEV builder's files through the same functions) read one map block and one intersections block.
// Non-default values in copies show that every path reads the files (a path that kept its own
// defaults, as the lane mapper did with its absent `intersections:` section, fails here).
TEST(Config, LiveAndOfflineReadTheSameMapAndIntersections) {
  using namespace lanemap;
  lt::TempDir dir("config-same");
  const std::string map = editedCopy(dir, "map.yaml", [](YAML::Node& n) {
    n["skeleton"]["junction_merge_radius_m"] = 7.5;
    n["skeleton"]["roi_max_extent_m"] = 11.0;
    n["origin"]["lat"] = 37.8;
    n["origin"]["lon"] = -122.3;
    n["road_frame"]["spacing_m"] = 0.8;
    n["road_frame"]["smoothing_m"] = 3.0;
  });
  const std::string inter = editedCopy(dir, "intersections.yaml", [](YAML::Node& n) {
    n["straight_max_deg"] = 33.0;
    n["allow_u_turns"] = true;
    n["step_m"] = 0.25;
  });
  const auto point = [&](YAML::Node& n) {
    n["map"] = map;
    const YAML::Node& c = n;  // a non-const operator[] would add the key
    if (c["intersections"]) n["intersections"] = inter;
  };
  const auto lanes = LaneMapperSettings::fromYamlFile(editedCopy(dir, "lane_mapper.yaml", point));
  const auto tracker = RoadTrackerSettings::fromYamlFile(editedCopy(dir, "road_tracker.yaml", point));
  const auto bev = BevBuilderSettings::fromYamlFile(editedCopy(dir, "bev_builder.yaml", point));
  const auto viewer = ViewerSettings::fromYamlFile(editedCopy(dir, "viewer.yaml", point));

  EXPECT_EQ(lanes.map.skeleton.junction_merge_radius_m, 7.5);
  EXPECT_EQ(lanes.map.skeleton.roi_max_extent_m, 11.0);
  ASSERT_TRUE(lanes.map.skeleton.origin.has_value());
  EXPECT_EQ(lanes.map.skeleton.origin->lat, 37.8);
  EXPECT_EQ(lanes.intersections.straight_max_deg, 33.0);
  EXPECT_TRUE(lanes.intersections.allow_u_turns);
  EXPECT_EQ(lanes.intersections.curve.step_m, 0.25);
  expectSameSkeleton(tracker.map.skeleton, lanes.map.skeleton);
  expectSameSkeleton(bev.map.skeleton, lanes.map.skeleton);
  expectSameSkeleton(viewer.map.skeleton, lanes.map.skeleton);
  expectSameIntersections(viewer.intersections, lanes.intersections);
  EXPECT_EQ(tracker.map.osm, lanes.map.osm);
  // The road frame a partial road's station is measured in (BEV builder) is the one the explorer
  // works in (lane mapper, lanemap-offline): the map block's.
  EXPECT_EQ(bev.map.road_frame.spacing_m, 0.8);
  EXPECT_EQ(bev.map.road_frame.smoothing_m, 3.0);
  EXPECT_EQ(lanes.explorerOptions().frame_spacing_m, 0.8);
  EXPECT_EQ(lanes.explorerOptions().frame_smoothing_m, 3.0);
  const auto bev_frame = withRoadFrame(lanes::ExplorerOptions{}, bev.map.road_frame);
  EXPECT_EQ(bev_frame.frame_spacing_m, lanes.explorerOptions().frame_spacing_m);
  EXPECT_EQ(bev_frame.frame_smoothing_m, lanes.explorerOptions().frame_smoothing_m);

  // The shipped files: the lane mapper's intersections are config/intersections.yaml's (before,
  // the live lane mapper read a section lane_mapper.yaml did not have), and every process config
  // names the one config/map.yaml.
  const auto shipped = LaneMapperSettings::fromYamlFile(kConfigDir + "/lane_mapper.yaml");
  expectSameIntersections(shipped.intersections, intersectionsFromFile(kConfigDir + "/intersections.yaml"));
  const auto shipped_map = config::MapConfig::fromYamlFile(kConfigDir + "/map.yaml");
  for (const char* f : {"lane_mapper.yaml", "road_tracker.yaml", "bev_builder.yaml", "viewer.yaml"}) {
    SCOPED_TRACE(f);
    const YAML::Node n = YAML::LoadFile(kConfigDir + "/" + f);
    EXPECT_EQ(n["map"].as<std::string>(), "config/map.yaml");
    expectSameSkeleton(mapConfigOf(YamlReader(n, f)).skeleton, shipped_map.skeleton);
  }

  // One skeleton: the tracker's and the lane mapper's options build the same atomic roads.
  const auto osm = osm::readOsm(lt::dataPath("osm/west-oakland.osm"));
  const auto a = skeleton::Skeleton::build(osm, lanes.map.skeleton);
  const auto b = skeleton::Skeleton::build(osm, tracker.map.skeleton);
  ASSERT_EQ(a.roads().size(), b.roads().size());
  EXPECT_EQ(a.intersections().size(), b.intersections().size());
  // ... and the merge radius read from the file matters: the default one gives other intersections.
  const auto d = skeleton::Skeleton::build(osm, config::MapConfig::fromYamlFile(kConfigDir + "/map.yaml").skeleton);
  EXPECT_NE(d.intersections().size(), a.intersections().size());
}

}  // namespace
