// The viewer in a real browser. Inside a private network namespace, the live graph of
// config/launch/demo.yaml (viewer included) replays the short simulated drive the live-graph test
// uses; Debian's headless Chromium, driven by chromedriver over its WebDriver HTTP API, opens the
// viewer's page. The test listens to LANE_MAP itself and waits until the page draws the lanes of
// the first road mapped; then it checks that the page draws exactly as many lanes for that road as
// the LANE_MAP message has, that it shows the BEV and the OSM roads, that the car marker moved
// along the drive, that the status panel lists every process of the graph and that clicking a lane
// shows its tags. It saves a screenshot under build/test-artifacts/viewer_browser.png. Then the
// finished store is browsed with --store (no LCM): same roads and lanes, trail, both downloads.
#include "core/io/lanelet2.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/lane_map_t.hpp"
#include "tests/bev/bev_replay.h"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"
#include "tests/viewer/http_client.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
namespace lt = lanemap::testing;
using nlohmann::json;

constexpr uint16_t kViewerPort = 8765;
constexpr uint16_t kDriverPort = 9515;

std::string base64Decode(const std::string& in) {
  std::string out;
  int val = 0, bits = -8;
  for (unsigned char c : in) {
    int d;
    if (c >= 'A' && c <= 'Z') d = c - 'A';
    else if (c >= 'a' && c <= 'z') d = c - 'a' + 26;
    else if (c >= '0' && c <= '9') d = c - '0' + 52;
    else if (c == '+') d = 62;
    else if (c == '/') d = 63;
    else continue;
    val = (val << 6) + d;
    bits += 6;
    if (bits >= 0) {
      out.push_back(static_cast<char>((val >> bits) & 0xff));
      bits -= 8;
    }
  }
  return out;
}

// A WebDriver session of chromedriver on loopback.
class WebDriver {
 public:
  json call(const std::string& method, const std::string& path, const json& body = nullptr) {
    const std::string r = lt::httpCall(kDriverPort, method, path, body.is_null() ? "" : body.dump());
    const std::string b = lt::responseBody(r);
    json j = json::parse(b.empty() ? "{}" : b, nullptr, false);
    if (j.is_discarded()) return json{{"error", "unparsable"}, {"raw", r}};
    return j;
  }
  bool open(const std::string& profile) {
    const json caps = {{"capabilities",
                        {{"alwaysMatch",
                          {{"browserName", "chrome"},
                           {"goog:chromeOptions",
                            {{"binary", "/usr/bin/chromium"},
                             {"args", {"--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                                       "--window-size=1400,900", "--user-data-dir=" + profile, "--no-first-run"}}}}}}}}};
    const json r = call("POST", "/session", caps);
    if (!r.contains("value") || !r["value"].contains("sessionId")) {
      std::cerr << "chromedriver: " << r.dump() << "\n";
      return false;
    }
    session_ = r["value"]["sessionId"];
    return true;
  }
  json navigate(const std::string& url) { return call("POST", "/session/" + session_ + "/url", {{"url", url}}); }
  // Runs `script` (a function body) in the page; its return value.
  json script(const std::string& script) {
    return call("POST", "/session/" + session_ + "/execute/sync", {{"script", script}, {"args", json::array()}})["value"];
  }
  std::string screenshotPng() {
    const json r = call("GET", "/session/" + session_ + "/screenshot");
    return r.contains("value") && r["value"].is_string() ? base64Decode(r["value"].get<std::string>()) : "";
  }
  void close() {
    if (!session_.empty()) call("DELETE", "/session/" + session_);
    session_.clear();
  }
  ~WebDriver() { close(); }

 private:
  std::string session_;
};

// LANE_MAP as the graph publishes it, in order.
struct LaneMapListener {
  lcm::LCM lcm{lt::testUdpmUrl()};
  std::mutex mutex;
  std::vector<std::pair<int64_t, int32_t>> maps;  // road id, lane count
  std::atomic<bool> stop{false};
  std::thread thread;
  LaneMapListener() {
    lcm.subscribe("LANE_MAP", &LaneMapListener::onLaneMap, this);
    thread = std::thread([this] {
      while (!stop) lcm.handleTimeout(100);
    });
  }
  ~LaneMapListener() {
    stop = true;
    thread.join();
  }
  void onLaneMap(const lcm::ReceiveBuffer*, const std::string&, const lanemap::lane_map_t* m) {
    std::lock_guard<std::mutex> lock(mutex);
    if (m->kind == lanemap::lane_map_t::KIND_ROAD) maps.emplace_back(m->id, m->num_lanes);
  }
  // The first road mapped with lanes and its latest lane count; -1 when none yet.
  std::pair<int64_t, int32_t> firstRoad() {
    std::lock_guard<std::mutex> lock(mutex);
    int64_t road = -1;
    int32_t n = 0;
    for (const auto& [id, count] : maps) {
      if (road < 0 && count > 0) road = id;
      if (id == road) n = count;
    }
    return {road, n};
  }
};

bool waitFor(const std::function<bool()>& ok, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
  while (std::chrono::steady_clock::now() < deadline) {
    if (ok()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  return ok();
}

std::string processLogs(const std::string& dir) {
  std::string all;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::ifstream in(e.path());
    std::string text((std::istreambuf_iterator<char>(in)), {});
    if (text.size() > 3000) text = "..." + text.substr(text.size() - 3000);
    all += "\n--- " + e.path().filename().string() + "\n" + text;
  }
  return all;
}

TEST(ViewerBrowser, PageShowsTheFirstClosedRoadsLanesTheCarAndEveryProcess) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  ASSERT_TRUE(fs::exists("/usr/bin/chromium") && fs::exists("/usr/bin/chromedriver"))
      << "needs Debian's chromium and chromium-driver (scripts/install-deps.sh installs them)";
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  ASSERT_FALSE(drive.empty());
  lt::TempDir out("viewer-browser");
  const fs::path artefacts = fs::path(LANEMAP_BIN_DIR).parent_path() / "test-artifacts";
  fs::create_directories(artefacts);

  // The browser first (Chromium takes seconds to start), then the graph.
  lt::ChildProcess driver({"/usr/bin/chromedriver", "--port=" + std::to_string(kDriverPort), "--log-path=" + out.str("chromedriver.log")});
  ASSERT_TRUE(driver.started());
  ASSERT_TRUE(waitFor([] { return lt::statusCode(lt::httpCall(kDriverPort, "GET", "/status", "", 2000)) == 200; }, 30));
  WebDriver browser;
  ASSERT_TRUE(browser.open(out.str("profile")));
  LaneMapListener lane_maps;
  lt::ChildProcess graph({lt::binPath("lanemap-launch"), std::string(LANEMAP_SOURCE_DIR) + "/config/launch/demo.yaml", "--all-hosts",
                          "--status-interval", "0", "--set", "drive=" + drive, "--set", "store=" + out.str("store"),
                          "--set", "viewer_port=" + std::to_string(kViewerPort), "--log-dir", out.str("logs")});
  ASSERT_TRUE(graph.started());
  ASSERT_TRUE(waitFor([] { return lt::statusCode(lt::httpCall(kViewerPort, "GET", "/api/state", "", 2000)) == 200; }, 60))
      << "the viewer never answered" << processLogs(out.str("logs"));
  browser.navigate("http://127.0.0.1:" + std::to_string(kViewerPort) + "/");
  const auto started = std::chrono::steady_clock::now();

  // Until the page draws the first mapped road's lanes (the drive is 18 s at 1x).
  json stats;
  std::pair<int64_t, int32_t> first{-1, 0};
  const bool shown = waitFor(
      [&] {
        first = lane_maps.firstRoad();
        stats = browser.script("return window.lanemapViewer ? window.lanemapViewer.stats : null;");
        if (first.first < 0 || !stats.is_object()) return false;
        const std::string key = std::to_string(first.first);
        return stats["lanesByRoad"].contains(key) && stats["lanesByRoad"][key] == first.second;
      },
      100);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::cout << "page showed road " << first.first << " (" << first.second << " lanes) after " << waited << " s; stats "
            << stats.dump() << "\n";
  // Let the status panel and the car catch up for the picture, then take it.
  std::this_thread::sleep_for(std::chrono::seconds(1));
  stats = browser.script("return window.lanemapViewer.stats;");
  const std::string png = browser.screenshotPng();
  ASSERT_FALSE(png.empty());
  { std::ofstream(artefacts / "viewer_browser.png", std::ios::binary) << png; }
  const cv::Mat shot = cv::imdecode(std::vector<uchar>(png.begin(), png.end()), cv::IMREAD_COLOR);
  EXPECT_EQ(shot.cols, 1400);
  std::cout << "screenshot: " << (artefacts / "viewer_browser.png").string() << "\n";

  ASSERT_TRUE(shown) << "first LANE_MAP road " << first.first << " with " << first.second << " lanes; page stats " << stats.dump()
                     << processLogs(out.str("logs"));
  EXPECT_GT(first.second, 0);
  EXPECT_EQ(stats["lanesByRoad"][std::to_string(first.first)], first.second);
  // The base layer: every atomic road of the drive's OSM file.
  const auto skeleton = lanemap::skeleton::Skeleton::build(lanemap::osm::readOsm(drive + "/roads.osm"));
  EXPECT_EQ(stats["skeletonRoads"].get<size_t>(), skeleton.roads().size());
  EXPECT_GE(stats["bevUpdates"].get<int>(), 1);       // BEV_ROAD comes before the road's LANE_MAP
  // The open road's BEV (BEV_OPEN, ~1 Hz) was shown and refreshed while the first road was driven.
  EXPECT_GE(stats["bevOpenUpdates"].get<int>(), 2);
  EXPECT_EQ(stats["transport"], "events");
  // The car drove: the marker moved by tens of metres (the drive runs ~8 m/s).
  EXPECT_GT(stats["carUpdates"].get<int>(), 5);
  EXPECT_GT(stats["carMovedM"].get<double>(), 20.0);
  // Every process of the graph is in the status panel.
  const json rows = browser.script(
      "return Array.from(document.querySelectorAll('#status tr[data-process]')).map(function (r) { return r.dataset.process; });");
  std::set<std::string> listed;
  for (const auto& r : rows) listed.insert(r.get<std::string>());
  for (const char* p : {"segmenter", "road_tracker", "bev_builder", "lane_mapper", "viewer"}) {
    EXPECT_TRUE(listed.count(p)) << p << " missing from the status panel: " << rows.dump();
  }
  // Clicking a lane shows its tags: the popup names its road.
  const std::string road = std::to_string(first.first);
  const json popup = browser.script(
      "var hit = null;"
      "window.lanemapViewer.lanesLayer.eachLayer(function (l) {"
      "  var p = l.feature.properties; if (!hit && p.feature === 'lanelet' && String(p.road_id) === '" + road + "') hit = l; });"
      "if (!hit) return null;"
      "hit.fire('click', {latlng: hit.getBounds().getCenter()});"
      "var c = document.querySelector('.leaflet-popup-content'); return c ? c.textContent : null;");
  ASSERT_TRUE(popup.is_string()) << popup.dump();
  EXPECT_NE(popup.get<std::string>().find("road_id" + road), std::string::npos) << popup.dump();
  EXPECT_NE(popup.get<std::string>().find("index_from_left"), std::string::npos) << popup.dump();
  browser.close();
  graph.stop();
  driver.stop();

  // The finished store, browsed afterwards with no LCM (--store): the same roads and lanes as the
  // store's files, the trail from its graph.lcmlog, and both downloads.
  const std::string url_file = out.str("viewer.url");
  lt::ChildProcess store_viewer({lt::binPath("lanemap-viewer"), "--store", out.str("store"), "--osm", drive + "/roads.osm",
                                 "--port", "0", "--url-file", url_file});
  ASSERT_TRUE(waitFor([&] { return fs::exists(url_file); }, 30)) << "the store viewer never listened";
  std::string url;
  std::getline(std::ifstream(url_file), url);
  const uint16_t port = static_cast<uint16_t>(std::stoi(url.substr(url.rfind(':') + 1)));
  const json st = json::parse(lt::responseBody(lt::httpCall(port, "GET", "/api/state")));
  size_t road_files = 0;
  for (const auto& e : fs::directory_iterator(out.str("store/lanes"))) road_files += e.path().extension() == ".osm";
  EXPECT_EQ(st["map"]["roads"].get<size_t>(), road_files);
  EXPECT_EQ(st["map"]["lanes_by_road"][road], first.second);
  EXPECT_GT(st["trail_count"].get<int>(), 20);
  EXPECT_FALSE(st["bev"].is_null());
  const std::string osm = lt::httpCall(port, "GET", "/download/lane_map.osm");
  EXPECT_EQ(lt::statusCode(osm), 200);
  EXPECT_NE(osm.find("attachment; filename=\"lane_map.osm\""), std::string::npos);
  { std::ofstream(out.str("download.osm")) << lt::responseBody(osm); }
  const auto& o = skeleton.frame().origin();
  const auto downloaded = lanemap::io::readLanelet2(out.str("download.osm"), o.lat, o.lon);
  EXPECT_EQ(downloaded.lanelets.size(), st["map"]["road_lanes"].get<size_t>() + st["map"]["connections"].get<size_t>());
  const std::string gj = lt::httpCall(port, "GET", "/download/lane_map.geojson");
  EXPECT_EQ(lt::statusCode(gj), 200);
  EXPECT_EQ(json::parse(lt::responseBody(gj))["type"], "FeatureCollection");
  EXPECT_EQ(store_viewer.stop(), 0);
}

}  // namespace
