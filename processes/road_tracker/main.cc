// lanemap-road-tracker: POSE in; the atomic road the car is on, and when it reaches an intersection,
// out on ROAD_EVENT (METHOD.md section 1).
// The process: processes/road_tracker/road_tracker_app.h (what it does, its STATUS counters).
//
//   lanemap-road-tracker --config config/road_tracker.yaml [--osm data/osm/west-oakland.osm]
#include "processes/road_tracker/road_tracker_app.h"

using namespace lanemap;
using namespace lanemap::road_tracker_app;

int main(int argc, char** argv) {
  lanemap::Process process("road_tracker");
  std::string osm_flag;
  process.cli().add_option("--osm", osm_flag, "OSM file of the skeleton (default: the osm of the config's map: file)");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  try {
    const auto settings = lanemap::RoadTrackerSettings::fromYaml(process.settings());
    process.settings().finish();
    const std::string osm = osm_flag.empty() ? settings.map.osm : osm_flag;
    if (osm.empty()) throw std::runtime_error("no OSM file: give --osm or `osm:` in the map config");
    auto skeleton = std::make_unique<lanemap::skeleton::Skeleton>(
        lanemap::skeleton::Skeleton::build(lanemap::osm::readOsm(osm), settings.map.skeleton));
    std::cerr << "road_tracker: " << skeleton->roads().size() << " atomic roads, "
              << skeleton->intersections().size() << " intersections from " << osm << "\n";
    RoadTrackerApp app(process, std::move(skeleton), settings.tracker, settings.pose_channel, settings.queue_capacity);
    return process.spin();
  } catch (const std::exception& e) {
    std::cerr << "road_tracker: " << e.what() << "\n";
    return 2;
  }
}
