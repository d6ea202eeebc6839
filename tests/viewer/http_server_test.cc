// core/viewer/http_server.h on loopback inside a private network namespace: it serves its bundled
// files and nothing else (`..`, percent-encoded `..`, backslashes, absolute-form targets and
// symbolic links refused, with the file next to the asset folder never in any answer), answers a
// malformed request with 400, a huge header with 431, a body with 413/405, too many connections
// with 503, closes idle connections after its timeout, streams server-sent events, and after
// every one of these still answers a plain GET with 200.
#include "core/viewer/http_server.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"
#include "tests/viewer/http_client.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
namespace lt = lanemap::testing;
using lanemap::viewer::HttpRequest;
using lanemap::viewer::HttpResponse;
using lanemap::viewer::HttpServer;
using lanemap::viewer::HttpServerOptions;

constexpr const char* kSecret = "TOP-SECRET-3f9a";

// An asset folder (index.html, js/app.js, a symbolic link to a file outside it) next to a secret.
struct Site {
  lt::TempDir dir{"viewer-http"};
  std::map<std::string, lanemap::viewer::StaticAsset> assets;
  Site() {
    fs::create_directories(dir.path() / "assets" / "js");
    std::ofstream(dir.path() / "assets" / "index.html") << "<html>lanemap index</html>";
    std::ofstream(dir.path() / "assets" / "js" / "app.js") << "console.log('app');";
    std::ofstream(dir.path() / "secret.txt") << kSecret;
    fs::create_symlink(dir.path() / "secret.txt", dir.path() / "assets" / "link.txt");
    assets = lanemap::viewer::loadAssets(dir.str("assets"));
  }
};

std::unique_ptr<HttpServer> startServer(const Site& site, HttpServerOptions o) {
  o.address = "127.0.0.1";
  o.port = 0;
  auto assets = site.assets;
  auto handler = [assets](const HttpRequest& r) {
    HttpResponse res;
    if (r.path == "/api/events") {
      res.event_stream = true;
      return res;
    }
    if (r.path == "/api/echo") {
      res.body = "query=" + r.query;
      return res;
    }
    auto it = assets.find(r.path == "/" ? "/index.html" : r.path);
    if (it == assets.end()) {
      res.status = 404;
      res.body = "not found";
      return res;
    }
    res.content_type = it->second.content_type;
    res.body = it->second.body;
    return res;
  };
  auto version = std::make_shared<std::atomic<uint64_t>>(1);
  auto events = [version](uint64_t& last) -> std::string {
    const uint64_t v = version->load();
    if (v == last) return "";
    last = v;
    return "event: state\ndata: {\"version\":" + std::to_string(v) + "}\n\n";
  };
  auto server = std::make_unique<HttpServer>(o, handler, events);
  server->start();
  return server;
}

std::string get(const std::string& target) { return "GET " + target + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"; }

void expectStillServes(uint16_t port) {
  const std::string r = lt::exchange(port, get("/index.html"));
  EXPECT_EQ(lt::statusCode(r), 200) << r;
  EXPECT_NE(r.find("lanemap index"), std::string::npos);
}

TEST(ViewerHttpTarget, ValidateTargetRefusesTraversalAndDecodes) {
  using lanemap::viewer::validateTarget;
  std::string q;
  EXPECT_EQ(validateTarget("/a/b.js?x=1&y=2", &q).value_or("?"), "/a/b.js");
  EXPECT_EQ(q, "x=1&y=2");
  EXPECT_EQ(validateTarget("/leaflet%2Fleaflet.js").value_or("?"), "/leaflet/leaflet.js");
  for (const char* bad : {"/../etc/passwd", "/a/../../b", "/%2e%2e/x", "/%2E%2E%2Fx", "/..%2fx", "/a/%2e%2e/b",
                          "/a\\..\\b", "/a%5cb", "/a%00b", "/a%zzb", "/a%2", "//etc/passwd", "/./x", "x", "",
                          "http://host/index.html", "*", "/a#b"}) {
    EXPECT_FALSE(validateTarget(bad).has_value()) << bad;
  }
}

TEST(ViewerHttp, ServesOnlyItsFilesAndRefusesTraversal) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  Site site;
  EXPECT_EQ(site.assets.size(), 2u);  // index.html, js/app.js; the symbolic link is not an asset
  auto server = startServer(site, {});
  const uint16_t port = server->port();
  std::string r = lt::exchange(port, get("/"));
  EXPECT_EQ(lt::statusCode(r), 200) << r;
  EXPECT_NE(r.find("text/html"), std::string::npos);
  r = lt::exchange(port, get("/js/app.js"));
  EXPECT_EQ(lt::statusCode(r), 200);
  EXPECT_NE(r.find("text/javascript"), std::string::npos);
  EXPECT_NE(r.find("console.log"), std::string::npos);
  EXPECT_EQ(lt::statusCode(lt::exchange(port, get("/api/echo?a=%2e%2e"))), 200);  // a query may say anything

  const std::vector<std::pair<std::string, int>> attacks = {
      {"/../secret.txt", 400},          {"/js/../../secret.txt", 400},   {"/%2e%2e/secret.txt", 400},
      {"/%2E%2E%2Fsecret.txt", 400},    {"/..%2fsecret.txt", 400},       {"/js/%2e%2e/%2e%2e/secret.txt", 400},
      {"/..\\secret.txt", 400},         {"/%2e%2e%5csecret.txt", 400},   {"//secret.txt", 400},
      {"/secret.txt", 404},             {"/link.txt", 404},              {"/%252e%252e/secret.txt", 404},
      {"/index.html%00.js", 400},       {"http://127.0.0.1/../secret.txt", 400}};
  for (const auto& [target, code] : attacks) {
    r = lt::exchange(port, get(target));
    EXPECT_EQ(lt::statusCode(r), code) << target << "\n" << r;
    EXPECT_EQ(r.find(kSecret), std::string::npos) << target;
  }
  expectStillServes(port);
}

TEST(ViewerHttp, MalformedRequestsGet400AndTheServerGoesOn) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  Site site;
  auto server = startServer(site, {});
  const uint16_t port = server->port();
  const std::vector<std::string> bad = {
      "GARBAGE\r\n\r\n",
      "GET /index.html\r\n\r\n",                        // no version
      "GET /index.html HTTP/1.1\r\nHost x\r\n\r\n",     // header without a colon
      "GET /index.html HTTP/1.1\r\nContent-Length: abc\r\n\r\n",
      "GET /index.html HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\nZZ\r\n",
      std::string("\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03", 11) + std::string(200, '\xff') + "\r\n\r\n",  // TLS hello
  };
  for (const auto& b : bad) {
    const std::string r = lt::exchange(port, b);
    EXPECT_EQ(lt::statusCode(r), 400) << "request: " << b << "\nresponse: " << r;
    expectStillServes(port);
  }
  // Methods other than GET; a body over the limit.
  EXPECT_EQ(lt::statusCode(lt::exchange(port, "DELETE /index.html HTTP/1.1\r\nHost: x\r\n\r\n")), 405);
  EXPECT_EQ(lt::statusCode(lt::exchange(port, "POST /index.html HTTP/1.1\r\nHost: x\r\nContent-Length: 3\r\n\r\nabc")), 405);
  const std::string big_body = "GET /index.html HTTP/1.1\r\nHost: x\r\nContent-Length: 100000\r\n\r\n" + std::string(100000, 'a');
  EXPECT_EQ(lt::statusCode(lt::exchange(port, big_body)), 413);
  // Keep-alive: two requests on one connection, both answered.
  const std::string two = "GET /js/app.js HTTP/1.1\r\nHost: x\r\n\r\nGET /index.html HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
  const std::string r = lt::exchange(port, two);
  EXPECT_EQ(lt::statusCode(r), 200);
  EXPECT_NE(r.find("console.log"), std::string::npos);
  EXPECT_NE(r.find("lanemap index"), std::string::npos);
  EXPECT_GE(server->rejected(), bad.size() + 3);
  expectStillServes(port);
}

TEST(ViewerHttp, HugeHeadersGet431) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  Site site;
  HttpServerOptions o;
  o.header_limit = 8192;
  auto server = startServer(site, o);
  const uint16_t port = server->port();
  // One 100 kB header; then 2000 small headers; then a 1 MB request line.
  std::string r = lt::exchange(port, "GET /index.html HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(100000, 'b') + "\r\n\r\n");
  EXPECT_EQ(lt::statusCode(r), 431) << r.substr(0, 200);
  std::string many = "GET /index.html HTTP/1.1\r\nHost: x\r\n";
  for (int i = 0; i < 2000; ++i) many += "X-H" + std::to_string(i) + ": v\r\n";
  r = lt::exchange(port, many + "\r\n");
  EXPECT_EQ(lt::statusCode(r), 431);
  r = lt::exchange(port, "GET /" + std::string(1 << 20, 'a') + " HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(lt::statusCode(r), 431);
  // Just under the limit is fine.
  r = lt::exchange(port, "GET /index.html HTTP/1.1\r\nHost: x\r\nX-Ok: " + std::string(7000, 'o') + "\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(lt::statusCode(r), 200);
  expectStillServes(port);
}

TEST(ViewerHttp, IdleConnectionsTimeOutAndTooManyGet503) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  Site site;
  HttpServerOptions o;
  o.idle_timeout_s = 1.0;
  o.max_connections = 50;
  auto server = startServer(site, o);
  const uint16_t port = server->port();
  // 50 idle connections (one with half a request line): the 51st is refused with 503.
  std::vector<int> idle;
  for (int i = 0; i < 50; ++i) {
    const int fd = lt::connectLoopback(port);
    ASSERT_GE(fd, 0);
    if (i == 0) lt::sendAll(fd, "GET /index.h");
    idle.push_back(fd);
  }
  for (int i = 0; i < 100 && server->connections() < 50; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(server->connections(), 50);
  std::string r = lt::exchange(port, get("/index.html"));
  EXPECT_EQ(lt::statusCode(r), 503) << r;
  // After the idle timeout the server has closed every one of them ...
  std::this_thread::sleep_for(std::chrono::milliseconds(1600));
  int closed_by_server = 0;
  for (int fd : idle) {
    bool closed = false;
    lt::readUntil(fd, 200, &closed);
    if (closed) ++closed_by_server;
    close(fd);
  }
  EXPECT_EQ(closed_by_server, 50);
  // ... and answers again.
  expectStillServes(port);
  // 300 connections opened and dropped at once, some mid-request: no crash, still serving.
  for (int i = 0; i < 300; ++i) {
    const int fd = lt::connectLoopback(port);
    if (fd < 0) continue;
    if (i % 3 == 0) lt::sendAll(fd, "GET /index.html HTTP/1.1\r\nHo");
    close(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  expectStillServes(port);
}

TEST(ViewerHttp, EventStreamSendsState) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  Site site;
  HttpServerOptions o;
  o.event_interval_s = 0.1;
  o.idle_timeout_s = 0.5;  // an event stream is not idle: it stays open past this
  auto server = startServer(site, o);
  const int fd = lt::connectLoopback(server->port());
  ASSERT_GE(fd, 0);
  lt::sendAll(fd, "GET /api/events HTTP/1.1\r\nHost: x\r\nAccept: text/event-stream\r\n\r\n");
  bool closed = false;
  const std::string all = lt::readUntil(fd, 3000, &closed, "{\"version\":1}\n\n");
  EXPECT_EQ(lt::statusCode(all), 200) << all;
  EXPECT_NE(all.find("Content-Type: text/event-stream"), std::string::npos);
  EXPECT_NE(all.find("event: state\ndata: {\"version\":1}\n\n"), std::string::npos) << all;
  EXPECT_FALSE(closed);
  // Still open well past the idle timeout: a stream is not an idle connection.
  lt::readUntil(fd, 1200, &closed);
  EXPECT_FALSE(closed);
  close(fd);
  expectStillServes(server->port());
}

TEST(ViewerHttp, RefusesToListenOnABadAddress) {
  Site site;
  HttpServerOptions o;
  o.address = "not-an-address";
  EXPECT_THROW(HttpServer(o, [](const HttpRequest&) { return HttpResponse{}; }), std::runtime_error);
}

}  // namespace
