// The viewer's HTTP server on Boost.Beast (see http_server.h).
#include "core/viewer/http_server.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace lanemap::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace asio = boost::asio;
using tcp = asio::ip::tcp;

std::chrono::milliseconds ms(double s) { return std::chrono::milliseconds(static_cast<int64_t>(s * 1000.0)); }

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

const char* reasonText(int status) {
  switch (status) {
    case 400: return "bad request";
    case 404: return "not found";
    case 405: return "method not allowed";
    case 413: return "request body too large";
    case 431: return "request header fields too large";
    case 500: return "internal error";
    case 503: return "too many connections";
    default: return "error";
  }
}

}  // namespace

std::optional<std::string> validateTarget(const std::string& target, std::string* query) {
  if (target.empty() || target[0] != '/' || target.size() > 2048) return std::nullopt;  // origin-form only
  const size_t q = target.find('?');
  const std::string raw = target.substr(0, q);
  if (query) *query = q == std::string::npos ? "" : target.substr(q + 1);
  if (raw.find('#') != std::string::npos) return std::nullopt;
  std::string path;
  path.reserve(raw.size());
  for (size_t i = 0; i < raw.size(); ++i) {
    char c = raw[i];
    if (c == '%') {
      if (i + 2 >= raw.size()) return std::nullopt;
      const int hi = hexValue(raw[i + 1]), lo = hexValue(raw[i + 2]);
      if (hi < 0 || lo < 0) return std::nullopt;
      c = static_cast<char>(hi * 16 + lo);
      i += 2;
    }
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f || c == '\\') return std::nullopt;
    path.push_back(c);
  }
  if (path.find("..") != std::string::npos) return std::nullopt;  // no asset name holds ".."
  if (path.find("/./") != std::string::npos || path.find("//") != std::string::npos) return std::nullopt;
  return path;
}

const char* contentTypeFor(const std::string& path) {
  auto ends = [&](const char* ext) {
    const std::string e(ext);
    return path.size() >= e.size() && path.compare(path.size() - e.size(), e.size(), e) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".png")) return "image/png";
  if (ends(".svg")) return "image/svg+xml";
  if (ends(".json") || ends(".geojson")) return "application/json";
  if (ends(".ico")) return "image/x-icon";
  if (ends(".txt") || ends(".md")) return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

std::map<std::string, StaticAsset> loadAssets(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw std::runtime_error("viewer assets: no folder " + folder);
  std::map<std::string, StaticAsset> out;
  for (auto it = fs::recursive_directory_iterator(folder, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const fs::file_status st = it->symlink_status();
    if (!fs::is_regular_file(st)) continue;  // symbolic links (and their targets) are never served
    const std::string rel = fs::relative(it->path(), folder).generic_string();
    std::ifstream in(it->path(), std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    out["/" + rel] = StaticAsset{contentTypeFor(rel), ss.str()};
  }
  if (ec) throw std::runtime_error("viewer assets: cannot list " + folder + ": " + ec.message());
  return out;
}

struct HttpServer::Impl {
  HttpServerOptions options;
  HttpHandler handler;
  EventSource events;
  std::atomic<int> connections{0};
  std::atomic<uint64_t> requests{0}, rejected{0};
  // Declared after the counters: destroying the io_context destroys the sessions its pending
  // handlers hold, which touch the counters.
  asio::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  asio::steady_timer accept_retry{ioc};
  uint16_t port = 0;

  void doAccept();
};

namespace {

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, HttpServer::Impl* server)
      : server_(server), stream_(std::move(socket)), timer_(stream_.get_executor()) {
    ++server_->connections;
  }
  ~Session() { --server_->connections; }

  void run() { doRead(); }
  void reject(int status) { sendError(status); }

 private:
  const HttpServerOptions& opt() const { return server_->options; }

  void doRead() {
    parser_.emplace();
    parser_->header_limit(opt().header_limit);
    parser_->body_limit(opt().body_limit);
    stream_.expires_after(ms(opt().idle_timeout_s));
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&Session::onRead, shared_from_this()));
  }

  void onRead(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout || ec == asio::error::operation_aborted ||
        ec == asio::error::connection_reset || ec == asio::error::eof || ec == asio::error::broken_pipe) {
      close();
      return;
    }
    if (ec == http::error::header_limit) return sendError(431);
    if (ec == http::error::body_limit) return sendError(413);
    if (ec) return sendError(400);  // any other parse error: the request is malformed
    handle(parser_->release());
  }

  void handle(http::request<http::string_body> req) {
    if (req.method() != http::verb::get) return sendError(405);
    std::string query;
    const auto path = validateTarget(std::string(req.target()), &query);
    if (!path) return sendError(400);
    HttpResponse r;
    try {
      r = server_->handler(HttpRequest{std::string(req.method_string()), *path, query});
    } catch (const std::exception& e) {
      std::cerr << "viewer: " << *path << ": " << e.what() << "\n";
      return sendError(500);
    }
    ++server_->requests;
    if (r.event_stream && server_->events) return startStream();
    auto res = std::make_shared<http::response<http::string_body>>(static_cast<http::status>(r.status), req.version());
    res->set(http::field::server, "lanemap-viewer");
    res->set(http::field::content_type, r.content_type);
    res->set("X-Content-Type-Options", "nosniff");
    for (const auto& [k, v] : r.headers) res->set(k, v);
    res->body() = std::move(r.body);
    res->keep_alive(req.keep_alive());
    res->prepare_payload();
    write(res, !req.keep_alive());
  }

  void sendError(int status) {
    ++server_->rejected;
    auto res = std::make_shared<http::response<http::string_body>>(static_cast<http::status>(status), 11);
    res->set(http::field::server, "lanemap-viewer");
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    res->body() = std::to_string(status) + " " + reasonText(status) + "\n";
    res->keep_alive(false);
    res->prepare_payload();
    write(res, true);
  }

  void write(std::shared_ptr<http::response<http::string_body>> res, bool close_after) {
    response_ = res;
    stream_.expires_after(ms(opt().write_timeout_s));
    http::async_write(stream_, *res, [self = shared_from_this(), close_after](beast::error_code ec, std::size_t) {
      self->response_.reset();
      if (ec) return self->close();
      if (close_after) return self->lingerClose();
      self->doRead();
    });
  }

  // Server-sent events: a response without a length, ended by closing the connection.
  void startStream() {
    sse_ = "HTTP/1.1 200 OK\r\nServer: lanemap-viewer\r\nContent-Type: text/event-stream\r\n"
           "Cache-Control: no-store\r\nConnection: close\r\n\r\nretry: 2000\n\n";
    last_sent_ = std::chrono::steady_clock::now();
    writeStream();
  }
  void writeStream() {
    stream_.expires_after(ms(opt().write_timeout_s));
    asio::async_write(stream_, asio::buffer(sse_), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->close();
      self->waitStream();
    });
  }
  void waitStream() {
    stream_.expires_never();
    timer_.expires_after(ms(opt().event_interval_s));
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      std::string ev;
      try {
        ev = self->server_->events(self->last_version_);
      } catch (const std::exception& e) {
        std::cerr << "viewer: event stream: " << e.what() << "\n";
      }
      const auto now = std::chrono::steady_clock::now();
      if (ev.empty()) {
        if (now - self->last_sent_ < ms(self->opt().keepalive_interval_s)) return self->waitStream();
        ev = ": keepalive\n\n";
      }
      self->sse_ = std::move(ev);
      self->last_sent_ = now;
      self->writeStream();
    });
  }

  // After a final response: stop sending, then read and discard what the client still sends (up
  // to 4 MB or 1 s) before closing, so that closing with unread data (which makes the kernel send
  // a reset) does not destroy the response before the client reads it.
  void lingerClose() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    if (ec) return close();
    stream_.expires_after(std::chrono::seconds(1));
    drain();
  }
  void drain() {
    stream_.async_read_some(asio::buffer(discard_), [self = shared_from_this()](beast::error_code ec, std::size_t n) {
      self->drained_ += n;
      if (ec || self->drained_ > (4u << 20)) return self->close();
      self->drain();
    });
  }

  void close() {
    beast::error_code ec;
    timer_.cancel();
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    stream_.socket().close(ec);
  }

  HttpServer::Impl* server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_{16384};
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<void> response_;
  asio::steady_timer timer_;
  std::string sse_;
  std::array<char, 16384> discard_{};
  size_t drained_ = 0;
  uint64_t last_version_ = 0;
  std::chrono::steady_clock::time_point last_sent_;
};

}  // namespace

void HttpServer::Impl::doAccept() {
  acceptor.async_accept(ioc, [this](beast::error_code ec, tcp::socket socket) {
    if (!acceptor.is_open()) return;
    if (ec) {
      // Out of descriptors and the like: wait instead of spinning on the error.
      accept_retry.expires_after(std::chrono::milliseconds(100));
      accept_retry.async_wait([this](beast::error_code e) {
        if (!e) doAccept();
      });
      return;
    }
    if (connections.load() >= options.max_connections) {
      std::make_shared<Session>(std::move(socket), this)->reject(503);
    } else {
      std::make_shared<Session>(std::move(socket), this)->run();
    }
    doAccept();
  });
}

HttpServer::HttpServer(HttpServerOptions options, HttpHandler handler, EventSource events) : impl_(std::make_shared<Impl>()) {
  impl_->options = std::move(options);
  impl_->handler = std::move(handler);
  impl_->events = std::move(events);
  beast::error_code ec;
  const auto address = asio::ip::make_address(impl_->options.address, ec);
  if (ec) throw std::runtime_error("viewer: bad listen address '" + impl_->options.address + "': " + ec.message());
  const tcp::endpoint endpoint(address, impl_->options.port);
  auto& a = impl_->acceptor;
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error("viewer: cannot listen on " + impl_->options.address + ":" +
                             std::to_string(impl_->options.port) + ": " + ec.message());
  }
  impl_->port = a.local_endpoint().port();
}

HttpServer::~HttpServer() { stop(); }

void HttpServer::start() {
  if (thread_.joinable()) return;
  impl_->doAccept();
  thread_ = std::thread([impl = impl_] {
    for (;;) {
      try {
        impl->ioc.run();
        return;
      } catch (const std::exception& e) {
        std::cerr << "viewer: HTTP: " << e.what() << "\n";  // keep serving
      }
    }
  });
}

void HttpServer::stop() {
  if (!thread_.joinable()) return;
  asio::post(impl_->ioc, [impl = impl_.get()] {
    beast::error_code ec;
    impl->acceptor.close(ec);
    impl->accept_retry.cancel();
  });
  impl_->ioc.stop();
  thread_.join();
}

uint16_t HttpServer::port() const { return impl_->port; }
int HttpServer::connections() const { return impl_->connections.load(); }
uint64_t HttpServer::requests() const { return impl_->requests.load(); }
uint64_t HttpServer::rejected() const { return impl_->rejected.load(); }

}  // namespace lanemap::viewer
