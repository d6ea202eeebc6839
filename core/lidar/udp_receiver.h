// A small UDP socket helper for sensor drivers (Velodyne data/position packets, NMEA over UDP):
// bind to an address and port with a large receive buffer, read datagrams without blocking with
// their kernel receive timestamp (SO_TIMESTAMP), detect oversize datagrams, and wait on several
// sockets at once. LCM-free; POSIX sockets only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::lidar {

// Thrown when a socket cannot be created or bound; the message names address, port and errno text.
class UdpError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Datagram {
  std::vector<uint8_t> data;  // payload (cut to the receiver's max size when truncated)
  std::size_t size = 0;       // real size of the datagram, even when truncated
  bool truncated = false;     // larger than the receiver's max datagram size
  int64_t receive_utime = 0;  // kernel receive time, microseconds since the epoch
  uint32_t src_ip = 0;        // host order
  uint16_t src_port = 0;
};

class UdpReceiver {
 public:
  // Binds `address` ("0.0.0.0" = every interface, "127.0.0.1", ...) and `port` (0 = any free one).
  // `rcvbuf_bytes` > 0 asks the kernel for that receive buffer (it may grant less: see
  // receiveBufferBytes()). Throws UdpError with a clear message on failure.
  UdpReceiver(const std::string& address, uint16_t port, int rcvbuf_bytes = 0,
              std::size_t max_datagram = 2048);
  ~UdpReceiver();
  UdpReceiver(const UdpReceiver&) = delete;
  UdpReceiver& operator=(const UdpReceiver&) = delete;

  // Reads one datagram if one is queued (never blocks); false when none is.
  bool receive(Datagram& out);

  int fd() const { return fd_; }
  uint16_t port() const { return port_; }  // the bound port (useful with port 0)
  int receiveBufferBytes() const;          // what the kernel granted
  std::string describe() const;            // "udp://127.0.0.1:2368"

 private:
  int fd_ = -1;
  std::string address_;
  uint16_t port_ = 0;
  std::size_t max_datagram_;
};

// Waits up to `timeout_ms` until some receivers have data; returns their indices (empty on
// timeout or when interrupted by a signal).
std::vector<std::size_t> waitReadable(const std::vector<UdpReceiver*>& receivers, int timeout_ms);

}  // namespace lanemap::lidar
