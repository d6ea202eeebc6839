// UDP receive helper for drivers (see udp_receiver.h).
#include "core/lidar/udp_receiver.h"

#include "core/geo/wall_clock.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace lanemap::lidar {
namespace {


}  // namespace

UdpReceiver::UdpReceiver(const std::string& address, uint16_t port, int rcvbuf_bytes,
                         std::size_t max_datagram)
    : address_(address), port_(port), max_datagram_(max_datagram) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, address.c_str(), &addr.sin_addr) != 1) {
    throw UdpError("invalid IPv4 address '" + address + "' for UDP port " + std::to_string(port));
  }
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw UdpError(std::string("cannot create a UDP socket: ") + std::strerror(errno));
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof(one));
  if (rcvbuf_bytes > 0) setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf_bytes, sizeof(rcvbuf_bytes));
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int err = errno;
    close(fd_);
    fd_ = -1;
    throw UdpError("cannot bind UDP " + address + ":" + std::to_string(port) + ": " +
                   std::strerror(err) +
                   (err == EADDRINUSE ? " (another driver or program already listens there)" : ""));
  }
  sockaddr_in bound{};
  socklen_t len = sizeof(bound);
  if (getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &len) == 0)
    port_ = ntohs(bound.sin_port);
}

UdpReceiver::~UdpReceiver() {
  if (fd_ >= 0) close(fd_);
}

int UdpReceiver::receiveBufferBytes() const {
  int v = 0;
  socklen_t len = sizeof(v);
  getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &v, &len);
  return v;
}

std::string UdpReceiver::describe() const {
  return "udp://" + address_ + ":" + std::to_string(port_);
}

bool UdpReceiver::receive(Datagram& out) {
  out.data.resize(max_datagram_);
  sockaddr_in src{};
  iovec iov{out.data.data(), out.data.size()};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval))];
  msghdr msg{};
  msg.msg_name = &src;
  msg.msg_namelen = sizeof(src);
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);
  // MSG_TRUNC: the return value is the datagram's real length even when it did not fit.
  const ssize_t n = recvmsg(fd_, &msg, MSG_TRUNC | MSG_DONTWAIT);
  if (n < 0) {
    out.data.clear();
    return false;
  }
  out.size = static_cast<std::size_t>(n);
  out.truncated = out.size > max_datagram_;
  out.data.resize(std::min(out.size, max_datagram_));
  out.src_ip = ntohl(src.sin_addr.s_addr);
  out.src_port = ntohs(src.sin_port);
  out.receive_utime = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
      timeval tv{};
      std::memcpy(&tv, CMSG_DATA(c), sizeof(tv));
      out.receive_utime = static_cast<int64_t>(tv.tv_sec) * 1000000 + tv.tv_usec;
    }
  }
  if (out.receive_utime == 0) out.receive_utime = geo::wallUtime();
  return true;
}

std::vector<std::size_t> waitReadable(const std::vector<UdpReceiver*>& receivers, int timeout_ms) {
  std::vector<pollfd> fds;
  for (auto* r : receivers) fds.push_back(pollfd{r->fd(), POLLIN, 0});
  std::vector<std::size_t> ready;
  if (poll(fds.data(), fds.size(), timeout_ms) <= 0) return ready;
  for (std::size_t i = 0; i < fds.size(); ++i) {
    if (fds[i].revents & POLLIN) ready.push_back(i);
  }
  return ready;
}

}  // namespace lanemap::lidar
