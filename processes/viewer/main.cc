// lanemap-viewer: the live map in a browser (Leaflet page over HTTP on 127.0.0.1), or a finished
// store with --store.
// The process: processes/viewer/viewer_app.h (what it does, its STATUS counters).
//
//   lanemap-viewer --osm roads.osm [--config config/viewer.yaml] [--listen 127.0.0.1] [--port 8765]
//   lanemap-viewer --store DIR --osm roads.osm     browse a finished map store: no LCM at all
#include "processes/viewer/viewer_app.h"

using namespace lanemap;
using namespace lanemap::viewer_app;

int main(int argc, char** argv) {
  // Browsing a store needs no bus: the process framework then gets an in-process LCM (memq://),
  // which sends nothing anywhere.
  std::vector<char*> args(argv, argv + argc);
  bool store_mode = false, url_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--store" || a.rfind("--store=", 0) == 0) store_mode = true;
    if (a == "--lcm-url" || a.rfind("--lcm-url=", 0) == 0) url_given = true;
  }
  static char lcm_flag[] = "--lcm-url=memq://";
  if (store_mode && url_given) {
    std::cerr << "viewer: --store browses a finished map store without LCM; drop --lcm-url\n";
    return 2;
  }
  if (store_mode) args.push_back(lcm_flag);

  lanemap::Process process("viewer");
  std::string osm_flag, store, listen_flag, assets_flag, url_file;
  int port_flag = -1;
  auto& cli = process.cli();
  cli.description(
      "lanemap-viewer: the live map in a web browser (car, BEV, mapped lanes, coverage, process health).\n"
      "Live: lanemap-viewer --osm roads.osm   (subscribes to POSE, ROAD_EVENT, BEV_ROAD, LANE_MAP, STATUS)\n"
      "Store: lanemap-viewer --store DIR --osm roads.osm   (a finished map store, no LCM)\n"
      "Then open the URL it prints (default http://127.0.0.1:8765/).");
  cli.add_option("--osm", osm_flag, "OSM file of the skeleton (default: the osm of the config's map: file)");
  cli.add_option("--store", store, "browse this finished map store (lanes/, graph.lcmlog) instead of the bus");
  cli.add_option("--listen", listen_flag, "address to listen on (default: config listen, else 127.0.0.1; 0.0.0.0 = every interface)");
  cli.add_option("--port", port_flag, "TCP port (default: config port, else 8765; 0 = any free port)")->check(CLI::Range(0, 65535));
  cli.add_option("--assets", assets_flag, "folder of the page (default: config assets, else <bin>/../share/lanemap/viewer)");
  cli.add_option("--url-file", url_file, "write the page's URL to this file once listening (scripts, tests)");
  if (int rc = process.init(static_cast<int>(args.size()), args.data()); rc >= 0) return rc;
  try {
    const auto settings = ViewerSettings::fromYaml(process.settings());
    process.settings().finish();
    const std::string osm = osm_flag.empty() ? settings.map.osm : osm_flag;
    const std::string listen = listen_flag.empty() ? settings.server.address : listen_flag;
    const int port = port_flag >= 0 ? port_flag : settings.server.port;
    std::string assets = assets_flag.empty() ? settings.assets : assets_flag;
    if (assets.empty()) assets = defaultAssets();
    if (osm.empty()) throw std::runtime_error("no OSM file: give --osm or `osm:` in the map config");

    const osm::OsmData osm_data = osm::readOsm(osm);
    auto sk = std::make_shared<const skeleton::Skeleton>(skeleton::Skeleton::build(osm_data, settings.map.skeleton));
    viewer::ViewerOptions vo = settings.viewer;
    if (!store.empty()) {
      // A finished run: its last STATUS is old by nature; show it as recorded, drops included,
      // without calling anything behind for being silent or for drops long past.
      vo.status_stale_s = std::numeric_limits<double>::infinity();
      vo.loss_window_s = -1.0;
    }
    viewer::ViewerState state(sk, osm_data.restrictions, settings.intersections, vo);

    viewer::HttpServerOptions so = settings.server;
    so.address = listen;
    so.port = static_cast<uint16_t>(port);
    auto assets_map = viewer::loadAssets(assets);
    if (!assets_map.count("/index.html")) throw std::runtime_error("viewer assets: no index.html in " + assets);

    std::unique_ptr<LiveFeed> feed;
    if (!store.empty()) {
      loadStore(store, state);
    } else {
      feed = std::make_unique<LiveFeed>(process, state, settings.pose_queue);
    }
    auto events = [&state](uint64_t& last) -> std::string {
      const uint64_t v = state.version();
      if (v == last) return "";
      last = v;
      return "event: state\ndata: " + state.stateJson(monotonicSeconds()) + "\n\n";
    };
    viewer::HttpServer server(so, makeHandler(state, std::move(assets_map), process.counters()), events);
    server.start();
    const std::string host = listen.find(':') != std::string::npos ? "[" + listen + "]" : listen;
    const std::string url = "http://" + (listen == "0.0.0.0" ? std::string("127.0.0.1") : host) + ":" + std::to_string(server.port()) + "/";
    std::cerr << "viewer: " << sk->roads().size() << " atomic roads from " << osm << (store.empty() ? "" : ", store " + store)
              << "; open " << url << "\n";
    if (!url_file.empty()) {
      const std::string tmp = url_file + ".tmp";
      std::ofstream(tmp) << url << "\n";
      fs::rename(tmp, url_file);
    }
    process.setState("ready");
    const int rc = process.spin();
    server.stop();
    return rc;
  } catch (const std::exception& e) {
    std::cerr << "viewer: " << e.what() << "\n";
    return 2;
  }
}
