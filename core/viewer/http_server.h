// The viewer's small HTTP server on Boost.Beast (header-only Beast + Asio from Debian's Boost):
// one I/O thread, asynchronous sessions, HTTP/1.1 keep-alive, and server-sent events for the
// page's updates. What it defends against (tests/viewer/http_server_test.cc):
// - a request line or header that does not parse: 400, connection closed;
// - headers over header_limit bytes: 431; any request body over body_limit: 413;
// - a target that is not an absolute path, or that holds "..", a backslash, a NUL or a bad
//   percent-escape after decoding: 400 (the handler never sees it);
// - idle connections: closed after idle_timeout_s without a complete request; at most
//   max_connections at once (the next one gets 503 and is closed).
// Static files are served from an in-memory copy of the asset folder taken at start (regular
// files only, symbolic links skipped): nothing outside that set can ever be read.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace lanemap::viewer {

struct HttpRequest {
  std::string method;  // "GET", "HEAD", ...
  std::string path;    // percent-decoded, validated, without the query
  std::string query;   // raw, after '?', "" when none
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
  // An event stream (text/event-stream): the server keeps the connection and asks the server's
  // event source for the next event every event_interval_s.
  bool event_stream = false;
};

using HttpHandler = std::function<HttpResponse(const HttpRequest&)>;
// Next server-sent event for a stream: `last` is the stream's state (0 at first); returns the
// event text ("event: ...\ndata: ...\n\n") or "" when nothing changed.
using EventSource = std::function<std::string(uint64_t& last)>;

struct HttpServerOptions {
  std::string address = "127.0.0.1";
  uint16_t port = 8765;              // 0: any free port (see HttpServer::port())
  double idle_timeout_s = 30.0;      // without a complete request
  double write_timeout_s = 10.0;     // a client that does not read its response
  int max_connections = 256;
  uint32_t header_limit = 8192;      // bytes of request line + headers
  uint64_t body_limit = 1024;        // the viewer takes no uploads
  double event_interval_s = 0.5;     // event-stream poll period
  double keepalive_interval_s = 15.0;  // event-stream comment when nothing changed
};

// Percent-decodes and checks a request target's path (see the header comment); nullopt when it
// must be refused. `query` receives the part after '?'.
std::optional<std::string> validateTarget(const std::string& target, std::string* query = nullptr);

// Files of an asset folder, keyed by URL path ("/index.html", "/leaflet/leaflet.js").
struct StaticAsset {
  std::string content_type;
  std::string body;
};
std::map<std::string, StaticAsset> loadAssets(const std::string& folder);
const char* contentTypeFor(const std::string& path);

class HttpServer {
 public:
  // Throws std::runtime_error when it cannot listen (bad address, port in use).
  HttpServer(HttpServerOptions options, HttpHandler handler, EventSource events = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  void start();  // the I/O thread
  void stop();   // closes every connection, joins the thread (also on destruction)
  uint16_t port() const;
  int connections() const;   // open now
  uint64_t requests() const;  // answered so far
  uint64_t rejected() const;  // 4xx/5xx answered by the server itself (malformed, limits)

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
  std::thread thread_;
};

}  // namespace lanemap::viewer
