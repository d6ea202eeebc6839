// A raw HTTP/1.1 client over POSIX sockets for the viewer's tests: it sends exactly the bytes a
// test gives (malformed requests included) and reads the answer until the server closes or a
// timeout. Loopback only (127.0.0.1).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstdlib>
#include <cstdint>
#include <string>

namespace lanemap::testing {

// A connected socket to 127.0.0.1:port, or -1.
inline int connectLoopback(uint16_t port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

inline bool sendAll(int fd, const std::string& bytes) {
  size_t off = 0;
  while (off < bytes.size()) {
    const ssize_t n = send(fd, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
    if (n <= 0) return false;
    off += static_cast<size_t>(n);
  }
  return true;
}

// Reads until the peer closes, `timeout_ms` passes, or (when stop_at is not empty) the data holds
// stop_at. `closed` says whether the peer closed.
inline std::string readUntil(int fd, int timeout_ms, bool* closed = nullptr, const std::string& stop_at = "") {
  std::string out;
  char buf[65536];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  if (closed) *closed = false;
  for (;;) {
    const int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count());
    if (left <= 0) break;
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, left) <= 0) break;
    const ssize_t n = recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) {
      if (closed) *closed = true;
      break;
    }
    out.append(buf, static_cast<size_t>(n));
    if (!stop_at.empty() && out.find(stop_at) != std::string::npos) break;
  }
  return out;
}

// True when `data` holds a whole response: headers, then Content-Length bytes of body, or a
// chunked body up to its last chunk (servers may keep the connection open despite
// "Connection: close"). A response without either ends when the server closes.
inline bool completeResponse(const std::string& data) {
  const size_t h = data.find("\r\n\r\n");
  if (h == std::string::npos) return false;
  std::string head = data.substr(0, h);
  for (auto& c : head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const size_t cl = head.find("content-length:");
  if (cl != std::string::npos) return data.size() - (h + 4) >= std::stoul(head.substr(cl + 15));
  if (head.find("transfer-encoding: chunked") != std::string::npos) return data.find("\r\n0\r\n\r\n", h) != std::string::npos;
  return false;
}

// Sends `request` on a fresh connection and reads the answer until the server closes.
inline std::string exchange(uint16_t port, const std::string& request, int timeout_ms = 5000) {
  const int fd = connectLoopback(port);
  if (fd < 0) return "";
  sendAll(fd, request);
  shutdown(fd, SHUT_WR);
  std::string r = readUntil(fd, timeout_ms);
  close(fd);
  return r;
}

// Status code of a response ("HTTP/1.1 200 OK..."), -1 when there is none.
inline int statusCode(const std::string& response) {
  if (response.rfind("HTTP/1.", 0) != 0 || response.size() < 12) return -1;
  return std::atoi(response.substr(9, 3).c_str());
}

// The body of a response (after the blank line), de-chunked when Transfer-Encoding is chunked.
inline std::string responseBody(const std::string& response) {
  const size_t h = response.find("\r\n\r\n");
  if (h == std::string::npos) return "";
  std::string head = response.substr(0, h);
  for (auto& c : head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::string body = response.substr(h + 4);
  if (head.find("transfer-encoding: chunked") == std::string::npos) return body;
  std::string out;
  size_t pos = 0;
  while (pos < body.size()) {
    const size_t eol = body.find("\r\n", pos);
    if (eol == std::string::npos) break;
    const size_t len = std::stoul(body.substr(pos, eol - pos), nullptr, 16);
    if (len == 0) break;
    out += body.substr(eol + 2, len);
    pos = eol + 2 + len + 2;
  }
  return out;
}

// GET / POST / DELETE with Connection: close; returns the whole response.
inline std::string httpCall(uint16_t port, const std::string& method, const std::string& target,
                            const std::string& body = "", int timeout_ms = 30000) {
  std::string req = method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nConnection: close\r\n";
  if (!body.empty() || method == "POST") {
    req += "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  }
  req += "\r\n" + body;
  const int fd = connectLoopback(port);
  if (fd < 0) return "";
  sendAll(fd, req);
  std::string r;
  char buf[65536];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!completeResponse(r)) {
    const int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count());
    pollfd p{fd, POLLIN, 0};
    if (left <= 0 || poll(&p, 1, left) <= 0) break;
    const ssize_t n = recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) break;
    r.append(buf, static_cast<size_t>(n));
  }
  close(fd);
  return r;
}

}  // namespace lanemap::testing
