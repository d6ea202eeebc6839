// lanemap-bev-builder: labelled camera frames, LIDAR sweeps, poses and road events in; one BEV grid per
// closed atomic road out (METHOD.md section 3).
// The process: processes/bev_builder/bev_builder_app.h (what it does, its STATUS counters).
//
//   lanemap-bev-builder --config config/bev_builder.yaml [--osm FILE] [--store DIR] [--vehicle FILE]
//                       [--semantic-channel SEMANTIC_FRONT_TRUTH] [--no-lidar]
#include "processes/bev_builder/bev_builder_app.h"

using namespace lanemap;
using namespace lanemap::bev_builder_app;

int main(int argc, char** argv) {
  Process process("bev_builder");
  std::string osm_flag, store_flag, channel_flag, vehicle_flag;
  bool no_lidar = false;
  process.cli().add_option("--osm", osm_flag, "OSM file of the skeleton (default: the osm of the config's map: file)");
  process.cli().add_option("--store", store_flag, "map store folder (default: config store)");
  process.cli().add_option("--semantic-channel", channel_flag, "semantic channel (default: config semantic_channel)");
  process.cli().add_option("--vehicle", vehicle_flag, "vehicle YAML: camera, lidar mount (default: config vehicle)");
  process.cli().add_flag("--no-lidar", no_lidar, "flat ground only");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  try {
    const auto settings = BevBuilderSettings::fromYaml(process.settings());
    process.settings().finish();
    const std::string osm = osm_flag.empty() ? settings.map.osm : osm_flag;
    const std::string store = store_flag.empty() ? settings.store : store_flag;
    const std::string channel = channel_flag.empty() ? settings.semantic_channel : channel_flag;
    const std::string vehicle = vehicle_flag.empty() ? resolveShippedFile(settings.vehicle) : vehicle_flag;
    if (osm.empty()) throw std::runtime_error("no OSM file: give --osm or `osm:` in the map config");
    if (store.empty()) throw std::runtime_error("no map store: give --store or `store:` in the config");
    const io::StoreLock lock(store, "bev_builder");  // one BEV builder per store; a read-only store fails here
    std::unique_ptr<BevBuilderApp> app;
    BevBuilderApp::subscribe(process.lcm(), channel, settings, &app);  // first: the bus waits in LCM's queues while we start
    const int stale = io::removeStaleTemporaries((std::filesystem::path(store) / "bev").string()) +
                      io::removeStaleTemporaries((std::filesystem::path(store) / "bev" / "open").string());
    if (stale > 0) std::cerr << "bev_builder: removed " << stale << " temporaries a killed writer left in " << store << "/bev\n";
    auto sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(osm::readOsm(osm), settings.map.skeleton));
    const auto vehicle_config = config::VehicleConfig::fromYamlFile(vehicle);
    const camera::CameraModel& camera = vehicle_config.camera;
    bev::BevBuilderOptions options = settings.options;
    if (no_lidar) options.use_lidar = false;
    if (options.use_lidar) options.lidar_to_vehicle = vehicle_config.lidarToVehicle();
    std::cerr << "bev_builder: " << sk->roads().size() << " atomic roads from " << osm << ", " << channel
              << (options.use_lidar ? " + LIDAR mesh" : " (flat ground)") << ", store " << store << "\n";
    auto made = std::make_unique<BevBuilderApp>(process, std::move(sk), camera, options, store);
    made->setPreview(settings.preview_period_s, settings.preview_max_px);
    made->setCheckpointPeriod(settings.checkpoint_period_s);
    made->setDriveOffset(settings.drive_offset, options.accumulator.grid.resolution_m);
    made->setRoadFrame(withRoadFrame(lanes::ExplorerOptions{}, settings.map.road_frame));
    made->recover();
    app = std::move(made);
    const int rc = process.spin();
    app->finish();
    return rc;
  } catch (const io::StoreInUseError& e) {
    std::cerr << "bev_builder: " << e.what() << "\n";
    return io::kExitStoreInUse;
  } catch (const std::exception& e) {
    std::cerr << "bev_builder: " << e.what() << "\n";
    return 2;
  }
}
