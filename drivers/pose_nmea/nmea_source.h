// Where the NMEA driver's bytes come from: a serial device (termios raw mode at a configured baud
// rate), a UDP port (one or more sentences per datagram), or a file. Each source hands out chunks
// of bytes; the driver cuts them into lines.
#pragma once

#include "core/lidar/udp_receiver.h"

#include <cstdint>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

namespace lanemap::drivers {

class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class NmeaSource {
 public:
  virtual ~NmeaSource() = default;
  // Appends what arrived within `timeout_ms` to `chunk` and sets `receive_utime`. Returns false at
  // the end of the stream (file end); a live source returns true with an empty chunk on timeout.
  // Throws SourceError when the device fails (e.g. unplugged).
  virtual bool read(std::string& chunk, int64_t& receive_utime, int timeout_ms) = 0;
  virtual std::string describe() const = 0;
};

// termios speed constant of a baud rate; throws SourceError listing the supported rates.
unsigned int baudConstant(int baud);

class SerialSource : public NmeaSource {
 public:
  SerialSource(const std::string& device, int baud);  // throws SourceError naming the device
  ~SerialSource() override;
  bool read(std::string& chunk, int64_t& receive_utime, int timeout_ms) override;
  std::string describe() const override { return device_; }

 private:
  std::string device_;
  int fd_ = -1;
};

class UdpSource : public NmeaSource {
 public:
  UdpSource(const std::string& address, int port);  // throws lidar::UdpError
  bool read(std::string& chunk, int64_t& receive_utime, int timeout_ms) override;
  std::string describe() const override { return rx_.describe(); }

 private:
  lidar::UdpReceiver rx_;
};

class FileSource : public NmeaSource {
 public:
  explicit FileSource(const std::string& path);  // throws SourceError naming the file
  bool read(std::string& chunk, int64_t& receive_utime, int timeout_ms) override;
  std::string describe() const override { return path_; }

 private:
  std::string path_;
  std::ifstream in_;
};

}  // namespace lanemap::drivers
