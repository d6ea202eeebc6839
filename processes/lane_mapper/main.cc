// lanemap-lane-mapper: a closed road's BEV grid in; its lanes (particle filter) and the intersections
// around it out, into the map store and on LANE_MAP (METHOD.md sections 4-5).
// The process: processes/lane_mapper/lane_mapper_app.h (what it does, its STATUS counters).
//
//   lanemap-lane-mapper --config config/lane_mapper.yaml [--osm FILE] [--store DIR]
#include "processes/lane_mapper/lane_mapper_app.h"

using namespace lanemap;
using namespace lanemap::lane_mapper_app;

int main(int argc, char** argv) {
  lanemap::Process process("lane_mapper");
  std::string osm_flag, store_flag;
  process.cli().add_option("--osm", osm_flag, "OSM file of the skeleton (default: the osm of the config's map: file)");
  process.cli().add_option("--store", store_flag, "map store folder (default: config store)");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  try {
    const auto settings = lanemap::LaneMapperSettings::fromYaml(process.settings());
    process.settings().finish();
    const std::string osm = osm_flag.empty() ? settings.map.osm : osm_flag;
    const std::string store = store_flag.empty() ? settings.store : store_flag;
    if (osm.empty()) throw std::runtime_error("no OSM file: give --osm or `osm:` in the map config");
    if (store.empty()) throw std::runtime_error("no map store: give --store or `store:` in the config");
    const lanemap::io::StoreLock lock(store, "lane_mapper");  // one lane mapper per store; a read-only store fails here
    const int stale = lanemap::io::removeStaleTemporaries((fs::path(store) / "lanes").string()) +
                      lanemap::io::removeStaleTemporaries((fs::path(store) / "passages").string()) +
                      lanemap::io::removeStaleTemporaries(store);
    if (stale > 0) std::cerr << "lane_mapper: removed " << stale << " temporaries a killed writer left in " << store << "\n";
    const lanemap::osm::OsmData osm_data = lanemap::osm::readOsm(osm);
    auto sk = std::make_unique<lanemap::skeleton::Skeleton>(lanemap::skeleton::Skeleton::build(osm_data, settings.map.skeleton));
    std::cerr << "lane_mapper: " << sk->roads().size() << " atomic roads from " << osm << ", store " << store << "\n";
    LaneMapperApp app(process, std::move(sk), settings.explorerOptions(), store, settings.bev_channel, settings.queue_capacity,
                      settings.intersections, osm_data.restrictions, settings.export_interval_s);
    app.setControls(lanemap::intersections::readControlNodes(osm));
    return process.spin();
  } catch (const lanemap::io::StoreInUseError& e) {
    std::cerr << "lane_mapper: " << e.what() << "\n";
    return lanemap::io::kExitStoreInUse;
  } catch (const std::exception& e) {
    std::cerr << "lane_mapper: " << e.what() << "\n";
    return 2;
  }
}
