// lanemap-viewer: the live map in a browser. Subscribes to POSE, ROAD_EVENT, BEV_ROAD, BEV_OPEN,
// LANE_MAP and STATUS, keeps what a person wants to see in core/viewer/viewer_state.h (car and
// trail, the skeleton coloured by coverage, the BEV of the open road (its picture, ~1 Hz) or of the
// road last handed over, the mapped lanes and
// intersections, every process's health) and serves it with the bundled page (web/viewer, Leaflet
// from npm, built into build/share/lanemap/viewer) on http://127.0.0.1:8765/ (core/viewer/
// http_server.h, Boost.Beast). The page updates itself from a server-sent event stream.
//
//   lanemap-viewer --osm roads.osm [--config config/viewer.yaml] [--listen 127.0.0.1] [--port 8765]
//   lanemap-viewer --store DIR --osm roads.osm     browse a finished map store: no LCM at all
//   lanemap-viewer --osm roads.osm --replay IN.lcmlog --replay-out OUT.lcmlog --state-out S.jsonl --port 0
//                                                  process replay: the state the inputs leave
//
// Endpoints: / (the page), /api/state, /api/events (text/event-stream), /api/skeleton.geojson,
// /api/lanes.geojson, /api/trail?from=N, /api/bev.png, /download/lane_map.osm (Lanelet2),
// /download/lane_map.geojson. Anything else is one of the bundled files or 404.
//
// STATUS latency (per LANE_MAP): from the message's receive time to the map reassembled
// (roads + intersections, core/mapping) and ready to serve.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/io/lanelet2.h"
#include "core/skeleton/skeleton.h"
#include "core/viewer/http_server.h"
#include "core/viewer/viewer_state.h"
#include "lanemap/bev_preview_t.hpp"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "lanemap/status_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/lane_map_message.h"
#include "processes/framework/share_dir.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include <lcm/lcm-cpp.hpp>
#include <unistd.h>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <regex>
#include <string>
#include <vector>

namespace lanemap::viewer_app {


namespace fs = std::filesystem;
using namespace lanemap;

inline double monotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

inline viewer::ProcessStatus fromMessage(const status_t& s) {
  viewer::ProcessStatus p;
  p.process = s.process;
  p.host = s.host;
  p.state = s.state;
  p.pid = s.pid;
  for (size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i) p.counters[s.counter_names[i]] = s.counter_values[i];
  p.latency_p50_ms = s.latency_p50_ms;
  p.latency_p99_ms = s.latency_p99_ms;
  p.cpu_fraction = s.cpu_fraction;
  return p;
}

// Feeds the state from the bus.
class LiveFeed {
 public:
  LiveFeed(Process& process, viewer::ViewerState& state, int pose_queue) : process_(process), state_(state) {
    process_.lcm().subscribe(channels::kPose, &LiveFeed::onPose, this)->setQueueCapacity(pose_queue);
    process_.lcm().subscribe(channels::kRoadEvent, &LiveFeed::onRoadEvent, this)->setQueueCapacity(100);
    process_.lcm().subscribe(channels::kBevRoad, &LiveFeed::onBevRoad, this)->setQueueCapacity(20);
    process_.lcm().subscribe(channels::kBevOpen, &LiveFeed::onBevOpen, this)->setQueueCapacity(2);
    process_.lcm().subscribe(channels::kLaneMap, &LiveFeed::onLaneMap, this)->setQueueCapacity(100);
    process_.lcm().subscribe(channels::kStatus, &LiveFeed::onStatus, this)->setQueueCapacity(100);
  }

 private:
  void onPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* msg) {
    process_.counters().add("poses_received");
    const EnuPose p = toEnuPose(*msg, state_.skeleton().frame());
    if (!p.valid) {
      process_.counters().add("poses_invalid");
      return;
    }
    state_.onPose(msg->utime, msg->latitude, msg->longitude, p.heading);
  }
  void onRoadEvent(const lcm::ReceiveBuffer*, const std::string&, const road_event_t* msg) {
    process_.counters().add("road_events_received");
    if (msg->type == road_event_t::TYPE_ENTERED_ROAD) state_.onRoadEntered(msg->road_id);
    if (msg->type == road_event_t::TYPE_REACHED_INTERSECTION) state_.onRoadClosed(msg->road_id);
  }
  void onBevRoad(const lcm::ReceiveBuffer*, const std::string&, const bev_road_t* msg) {
    process_.counters().add("bev_roads_received");
    try {
      state_.setBev(msg->road_id, bev::BevGrid::load(msg->path));
    } catch (const std::exception& e) {
      // The grid lives in the map store of the BEV builder's host: not readable from every host.
      process_.counters().add("bev_unreadable");
      std::cerr << "viewer: BEV of road " << msg->road_id << ": " << e.what() << "\n";
    }
  }
  // The open road's picture: only the newest matters (queue of 2).
  void onBevOpen(const lcm::ReceiveBuffer*, const std::string&, const bev_preview_t* msg) {
    process_.counters().add("bev_previews_received");
    bev::BevPicture pic;
    pic.png.assign(msg->png.begin(), msg->png.end());
    pic.enu = Eigen::AlignedBox2d(Eigen::Vector2d(msg->west, msg->south), Eigen::Vector2d(msg->east, msg->north));
    try {
      if (!state_.setOpenRoadBev(msg->road_id, pic)) process_.counters().add("bev_previews_stale");
    } catch (const std::exception& e) {
      process_.counters().add("bev_previews_bad");
      std::cerr << "viewer: BEV_OPEN of road " << msg->road_id << ": " << e.what() << "\n";
    }
  }
  void onLaneMap(const lcm::ReceiveBuffer* rbuf, const std::string&, const lane_map_t* msg) {
    process_.counters().add("lane_maps_received");
    if (msg->kind != lane_map_t::KIND_ROAD) return;  // intersections are assembled here from the roads
    try {
      state_.setRoadLanes(msg->id, fromMessage(*msg, state_.skeleton()));
      process_.counters().set("roads_shown", static_cast<int64_t>(state_.mappedRoadCount()));
      process_.latency().add(static_cast<double>(geo::wallUtime() - rbuf->recv_utime) * 1e-3);
    } catch (const std::exception& e) {
      process_.counters().add("lane_maps_failed");
      std::cerr << "viewer: LANE_MAP of road " << msg->id << ": " << e.what() << "\n";
    }
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const status_t* msg) {
    state_.onStatus(fromMessage(*msg), monotonicSeconds());
  }

  Process& process_;
  viewer::ViewerState& state_;
};

// A finished map store: every road's lanes (<store>/lanes/road_<id>.osm), the BEV grid written
// last (<store>/bev/road_<id>.bev); the car's trail, the
// roads driven and the last STATUS of each process from <store>/graph.lcmlog when the run
// recorded one (read as a file: no LCM bus).
inline void loadStore(const std::string& store, viewer::ViewerState& state) {
  const fs::path lanes = fs::path(store) / "lanes";
  if (!fs::is_directory(lanes)) throw std::runtime_error("no map store at " + store + " (no lanes/ folder)");
  const auto& o = state.skeleton().frame().origin();
  io::Lanelet2ReadOptions ro;
  ro.origin_alt = o.alt;
  int loaded = 0;
  for (const auto& [id, path] : bev::roadFiles(lanes.string(), ".osm")) {
    try {
      map::LaneMap m = io::readLanelet2(path, o.lat, o.lon, ro);
      for (auto& ll : m.lanelets) ll.road_id = id;
      state.onRoadClosed(id);
      state.setRoadLanes(id, std::move(m));
      ++loaded;
    } catch (const std::exception& e) {
      std::cerr << "viewer: skipping " << path << ": " << e.what() << "\n";
    }
  }
  std::cerr << "viewer: " << loaded << " mapped roads from " << lanes << "\n";
  // The BEV layer: the grid written last (<store>/bev/road_<id>.bev).
  fs::path newest;
  int64_t newest_id = -1;
  for (const auto& [id, path] : bev::roadFiles((fs::path(store) / "bev").string(), ".bev")) {
    if (newest.empty() || fs::last_write_time(path) > fs::last_write_time(newest)) {
      newest = path;
      newest_id = id;
    }
  }
  if (!newest.empty()) {
    try {
      state.setBev(newest_id, bev::BevGrid::load(newest.string()));
    } catch (const std::exception& e) {
      std::cerr << "viewer: skipping " << newest << ": " << e.what() << "\n";
    }
  }
  const fs::path log = fs::path(store) / "graph.lcmlog";
  if (!fs::exists(log)) return;
  lcm::LogFile file(log.string(), "r");
  if (!file.good()) return;
  int poses = 0;
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (ev->channel == channels::kPose) {
      pose_t p;
      if (p.decode(ev->data, 0, ev->datalen) < 0) continue;
      const EnuPose e = toEnuPose(p, state.skeleton().frame());
      if (e.valid) {
        state.onPose(p.utime, p.latitude, p.longitude, e.heading);
        ++poses;
      }
    } else if (ev->channel == channels::kRoadEvent) {
      road_event_t r;
      if (r.decode(ev->data, 0, ev->datalen) < 0) continue;
      if (r.type == road_event_t::TYPE_ENTERED_ROAD || r.type == road_event_t::TYPE_REACHED_INTERSECTION) state.onRoadClosed(r.road_id);
    } else if (ev->channel == channels::kStatus) {
      status_t s;
      if (s.decode(ev->data, 0, ev->datalen) < 0) continue;
      state.onStatus(fromMessage(s), monotonicSeconds());
    }
  }
  std::cerr << "viewer: " << poses << " poses from " << log << "\n";
}

inline viewer::HttpResponse text(int status, std::string body) {
  viewer::HttpResponse r;
  r.status = status;
  r.body = std::move(body);
  return r;
}

inline viewer::HttpResponse body(std::string content_type, std::string content, std::pair<std::string, std::string> header) {
  viewer::HttpResponse r;
  r.content_type = std::move(content_type);
  r.body = std::move(content);
  r.headers.push_back(std::move(header));
  return r;
}

inline viewer::HttpResponse json(std::string content) {
  return body("application/json", std::move(content), {"Cache-Control", "no-store"});
}

inline int64_t queryInt(const std::string& query, const std::string& key, int64_t fallback) {
  const std::regex re("(^|&)" + key + "=(-?[0-9]{1,18})(&|$)");
  std::smatch m;
  if (std::regex_search(query, m, re)) return std::stoll(m[2]);
  return fallback;
}

inline viewer::HttpHandler makeHandler(viewer::ViewerState& state, std::map<std::string, viewer::StaticAsset> assets, Counters& counters) {
  return [&state, &counters, assets = std::move(assets)](const viewer::HttpRequest& req) -> viewer::HttpResponse {
    counters.add("http_requests");
    const std::string& p = req.path;
    if (p == "/api/state") return json(state.stateJson(monotonicSeconds()));
    if (p == "/api/events") {
      viewer::HttpResponse r;
      r.event_stream = true;
      return r;
    }
    if (p == "/api/skeleton.geojson") return json(state.skeletonGeoJson());
    if (p == "/api/lanes.geojson") return json(state.lanesGeoJson());
    if (p == "/api/trail") return json(state.trail(queryInt(req.query, "from", 0)).dump());
    if (p == "/api/bev.png") {
      std::string png = state.bevPng();
      if (png.empty()) return text(404, "no BEV yet\n");
      return body("image/png", std::move(png), {"Cache-Control", "no-store"});
    }
    if (p == "/download/lane_map.osm") {
      std::string xml = state.lanelet2Xml();
      if (xml.empty()) return text(404, "nothing mapped yet\n");
      return body("application/xml", std::move(xml), {"Content-Disposition", "attachment; filename=\"lane_map.osm\""});
    }
    if (p == "/download/lane_map.geojson") {
      viewer::HttpResponse r = json(state.lanesGeoJson());
      r.content_type = "application/geo+json";
      r.headers.emplace_back("Content-Disposition", "attachment; filename=\"lane_map.geojson\"");
      return r;
    }
    auto it = assets.find(p == "/" ? "/index.html" : p);
    if (it == assets.end()) return text(404, "not found\n");
    viewer::HttpResponse r;
    r.content_type = it->second.content_type;
    r.body = it->second.body;
    return r;
  };
}

// build/bin/lanemap-viewer -> build/share/lanemap/viewer (where CMake puts the page).
inline std::string defaultAssets() {
  const fs::path bin = executableDir();
  return bin.empty() ? "" : (bin.parent_path() / "share" / "lanemap" / "viewer").string();
}

// The command line's own flags (the framework's --config, --lcm-url, --replay come with Process).
struct ViewerFlags {
  std::string osm, store, listen, assets, url_file, state_out;
  int port = -1;

  void add(CLI::App& cli) {
    cli.description(
        "lanemap-viewer: the live map in a web browser (car, BEV, mapped lanes, coverage, process health).\n"
        "Live: lanemap-viewer --osm roads.osm   (subscribes to POSE, ROAD_EVENT, BEV_ROAD, LANE_MAP, STATUS)\n"
        "Store: lanemap-viewer --store DIR --osm roads.osm   (a finished map store, no LCM)\n"
        "Then open the URL it prints (default http://127.0.0.1:8765/).");
    cli.add_option("--osm", osm, "OSM file of the skeleton (default: the osm of the config's map: file)");
    cli.add_option("--store", store, "browse this finished map store (lanes/, graph.lcmlog) instead of the bus");
    cli.add_option("--listen", listen, "address to listen on (default: config listen, else 127.0.0.1; 0.0.0.0 = every interface)");
    cli.add_option("--port", port, "TCP port (default: config port, else 8765; 0 = any free port)")->check(CLI::Range(0, 65535));
    cli.add_option("--assets", assets, "folder of the page (default: config assets, else <bin>/../share/lanemap/viewer)");
    cli.add_option("--url-file", url_file, "write the page's URL to this file once listening (scripts, tests)");
    cli.add_option("--state-out", state_out,
                   "on exit, write what the page would show as JSON lines: the state (processes aside), the "
                   "roads driven or mapped, the lanes' GeoJSON (process replay, tests/replay)");
  }
};

// Browsing a store needs no bus: the process framework then gets an in-process LCM (memq://),
// which sends nothing anywhere. The arguments to give the framework; empty when --store and
// --lcm-url are both given (said on stderr).
inline std::vector<char*> busArguments(int argc, char** argv) {
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
    return {};
  }
  if (store_mode) args.push_back(lcm_flag);
  return args;
}

// What a person sees, without what depends on the wall clock (the processes' ages): the lines of
// --state-out.
inline std::string stateLines(viewer::ViewerState& state) {
  nlohmann::json s = state.stateValue(monotonicSeconds());
  s.erase("processes");
  nlohmann::json coverage = nlohmann::json::object();
  for (const auto& r : state.skeleton().roads()) {  // the roads driven or mapped (the rest: never driven)
    const viewer::Coverage c = state.coverage(r.id);
    if (c != viewer::Coverage::kNeverDriven) coverage[std::to_string(r.id)] = viewer::toString(c);
  }
  return nlohmann::json{{"state", s}}.dump() + "\n" + nlohmann::json{{"coverage", coverage}}.dump() + "\n" +
         nlohmann::json{{"lanes", nlohmann::json::parse(state.lanesGeoJson())}}.dump() + "\n";
}

// The process, after Process::init: the skeleton, the state fed from the bus or a store, the HTTP
// server until the process is stopped (or its replay ends). Returns the exit code.
inline int run(Process& process, const ViewerFlags& flags) {
  try {
    const auto settings = ViewerSettings::fromYaml(process.settings());
    process.settings().finish();
    const std::string osm = flags.osm.empty() ? settings.map.osm : flags.osm;
    const std::string listen = flags.listen.empty() ? settings.server.address : flags.listen;
    const int port = flags.port >= 0 ? flags.port : settings.server.port;
    std::string assets = flags.assets.empty() ? settings.assets : flags.assets;
    if (assets.empty()) assets = defaultAssets();
    if (osm.empty()) throw std::runtime_error("no OSM file: give --osm or `osm:` in the map config");

    const osm::OsmData osm_data = osm::readOsm(osm);
    auto sk = std::make_shared<const skeleton::Skeleton>(skeleton::Skeleton::build(osm_data, settings.map.skeleton));
    viewer::ViewerOptions vo = settings.viewer;
    if (!flags.store.empty()) {
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
    if (!flags.store.empty()) {
      loadStore(flags.store, state);
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
    std::cerr << "viewer: " << sk->roads().size() << " atomic roads from " << osm
              << (flags.store.empty() ? "" : ", store " + flags.store) << "; open " << url << "\n";
    if (!flags.url_file.empty()) {
      const std::string tmp = flags.url_file + ".tmp";
      std::ofstream(tmp) << url << "\n";
      fs::rename(tmp, flags.url_file);
    }
    process.setState("ready");
    const int rc = process.spin();
    server.stop();
    if (!flags.state_out.empty()) {
      std::ofstream out(flags.state_out, std::ios::binary);
      out << stateLines(state);
      if (!out) throw std::runtime_error("cannot write " + flags.state_out);
    }
    return rc;
  } catch (const std::exception& e) {
    std::cerr << "viewer: " << e.what() << "\n";
    return 2;
  }
}

}  // namespace lanemap::viewer_app
