// Serial, UDP and file sources of NMEA bytes (see nmea_source.h).
#include "drivers/pose_nmea/nmea_source.h"

#include "core/geo/wall_clock.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>

namespace lanemap::drivers {
namespace {


}  // namespace

unsigned int baudConstant(int baud) {
  static const std::map<int, speed_t> kRates = {
      {4800, B4800},     {9600, B9600},     {19200, B19200},   {38400, B38400},  {57600, B57600},
      {115200, B115200}, {230400, B230400}, {460800, B460800}, {921600, B921600}};
  auto it = kRates.find(baud);
  if (it == kRates.end()) {
    throw SourceError(
        "serial baud rate " + std::to_string(baud) +
        " not supported (4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)");
  }
  return it->second;
}

SerialSource::SerialSource(const std::string& device, int baud) : device_(device) {
  const speed_t speed = baudConstant(baud);
  fd_ = open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    throw SourceError("cannot open serial device '" + device + "': " + std::strerror(errno));
  }
  termios tio{};
  if (tcgetattr(fd_, &tio) != 0) {
    const int err = errno;
    close(fd_);
    throw SourceError("'" + device + "' is not a serial device: " + std::strerror(err));
  }
  cfmakeraw(&tio);  // 8N1, no echo, no line editing, no flow control translation
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~CRTSCTS;
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  cfsetispeed(&tio, speed);
  cfsetospeed(&tio, speed);
  if (tcsetattr(fd_, TCSANOW, &tio) != 0) {
    const int err = errno;
    close(fd_);
    throw SourceError("cannot configure serial device '" + device + "' at " + std::to_string(baud) +
                      " baud: " + std::strerror(err));
  }
  tcflush(fd_, TCIFLUSH);
}

SerialSource::~SerialSource() {
  if (fd_ >= 0) close(fd_);
}

bool SerialSource::read(std::string& chunk, int64_t& receive_utime, int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  const int rc = poll(&p, 1, timeout_ms);
  if (rc <= 0) return true;  // timeout or a signal
  if (p.revents & (POLLERR | POLLNVAL)) {
    throw SourceError("serial device '" + device_ + "' failed (unplugged?)");
  }
  char buf[4096];
  const ssize_t n = ::read(fd_, buf, sizeof(buf));
  receive_utime = geo::wallUtime();
  if (n > 0) {
    chunk.append(buf, static_cast<std::size_t>(n));
  } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
    throw SourceError("reading serial device '" + device_ + "': " + std::strerror(errno));
  } else if (p.revents & POLLHUP) {
    throw SourceError("serial device '" + device_ + "' hung up (unplugged?)");
  }
  return true;
}

UdpSource::UdpSource(const std::string& address, int port)
    : rx_(address, static_cast<uint16_t>(port), 1 << 20, 65536) {}

bool UdpSource::read(std::string& chunk, int64_t& receive_utime, int timeout_ms) {
  std::vector<lidar::UdpReceiver*> rx{&rx_};
  if (lidar::waitReadable(rx, timeout_ms).empty()) return true;
  lidar::Datagram d;
  while (rx_.receive(d)) {
    chunk.append(reinterpret_cast<const char*>(d.data.data()), d.data.size());
    // A datagram is a whole number of sentences: end it with a newline if the sender did not.
    if (!d.data.empty() && d.data.back() != '\n') chunk.push_back('\n');
    receive_utime = d.receive_utime;
  }
  return true;
}

FileSource::FileSource(const std::string& path) : path_(path), in_(path, std::ios::binary) {
  if (!in_) throw SourceError("cannot read NMEA file '" + path + "'");
}

bool FileSource::read(std::string& chunk, int64_t& receive_utime, int) {
  std::string line;
  if (!std::getline(in_, line)) return false;
  chunk += line;
  chunk.push_back('\n');
  receive_utime = geo::wallUtime();
  return true;
}

}  // namespace lanemap::drivers
