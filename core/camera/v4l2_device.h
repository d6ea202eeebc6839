// The camera device interface of lanemap-camera-v4l2 and its Video4Linux2 implementation.
//
// VideoDevice is what the capture loop (core/camera/v4l2_capture.h) talks to: open, negotiate a
// format, start mmap streaming, dequeue a filled buffer (waiting with poll), requeue it, stop.
// V4l2Device does that with the kernel's ioctls (QUERYCAP, S_FMT, S_PARM, REQBUFS, QUERYBUF + mmap,
// QBUF/DQBUF, STREAMON/STREAMOFF); the tests drive the loop with a scripted fake instead.
//
// Errors are VideoDeviceError, which says what failed, on which device, the errno text, and whether
// the failure is one a reconnect can cure (device missing, unplugged, busy) or not (not a camera,
// no supported pixel format).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::camera {

// V4L2 fourcc codes (same values as linux/videodev2.h and lanemap::image_t).
constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(static_cast<uint8_t>(a)) |
         (static_cast<uint32_t>(static_cast<uint8_t>(b)) << 8) |
         (static_cast<uint32_t>(static_cast<uint8_t>(c)) << 16) |
         (static_cast<uint32_t>(static_cast<uint8_t>(d)) << 24);
}
inline constexpr uint32_t kFourccMjpeg = fourcc('M', 'J', 'P', 'G');
inline constexpr uint32_t kFourccJpeg = fourcc('J', 'P', 'E', 'G');
inline constexpr uint32_t kFourccYuyv = fourcc('Y', 'U', 'Y', 'V');

std::string fourccToString(uint32_t code);  // "MJPG"; unprintable bytes as '?'

// v4l2_buffer.flags bits the capture loop looks at (values of linux/videodev2.h).
inline constexpr uint32_t kBufFlagError = 0x00000040;
inline constexpr uint32_t kBufFlagTimestampMask = 0x0000e000;
inline constexpr uint32_t kBufFlagTimestampUnknown = 0x00000000;
inline constexpr uint32_t kBufFlagTimestampMonotonic = 0x00002000;
inline constexpr uint32_t kBufFlagTimestampCopy = 0x00004000;

struct VideoFormat {
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t pixelformat = 0;   // fourcc
  uint32_t bytesperline = 0;  // row stride of raw formats (0 for compressed ones)
  uint32_t sizeimage = 0;     // largest frame in bytes
  double fps = 0.0;           // frames per second (0: the driver's default / unknown)
};

// One filled buffer, valid until requeue().
struct RawFrame {
  int index = -1;              // buffer index, handed back in requeue()
  const uint8_t* data = nullptr;
  std::size_t bytesused = 0;
  uint32_t sequence = 0;       // the driver's frame counter
  int64_t timestamp_us = 0;    // v4l2_buffer.timestamp in microseconds (clock: see flags)
  uint32_t flags = 0;          // v4l2_buffer.flags
};

class VideoDeviceError : public std::runtime_error {
 public:
  enum class Kind {
    kMissing,       // no such device (not plugged in)
    kDisconnected,  // went away while streaming (ENODEV, EIO)
    kBusy,          // another process holds it
    kFatal,         // not a capture device, no usable format, ...: reconnecting will not help
  };
  VideoDeviceError(Kind kind, const std::string& message, int error_number = 0)
      : std::runtime_error(message), kind_(kind), errno_(error_number) {}
  Kind kind() const { return kind_; }
  int errorNumber() const { return errno_; }
  bool retryable() const { return kind_ != Kind::kFatal; }

 private:
  Kind kind_;
  int errno_;
};

// Maps an errno of open()/ioctl() to the error kind (ENOENT, ENODEV, ENXIO: missing; EIO:
// disconnected; EBUSY: busy; the rest: fatal). `while_streaming` turns "missing" into
// "disconnected".
VideoDeviceError::Kind classifyErrno(int error_number, bool while_streaming);

class VideoDevice {
 public:
  virtual ~VideoDevice() = default;
  virtual std::string name() const = 0;
  // Opens the device and checks it can capture and stream. Throws VideoDeviceError.
  virtual void open() = 0;
  // Asks for `requested` (size, pixel format, frame rate); returns what the driver set, which may
  // differ: the caller must use the returned format.
  virtual VideoFormat setFormat(const VideoFormat& requested) = 0;
  // Allocates and queues `buffers` buffers and starts streaming.
  virtual void start(int buffers) = 0;
  // Waits up to timeout_ms for a filled buffer: true and `frame` set, false on timeout. Throws
  // VideoDeviceError (kDisconnected when the device went away).
  virtual bool dequeue(RawFrame& frame, int timeout_ms) = 0;
  // Gives a dequeued buffer back to the driver.
  virtual void requeue(const RawFrame& frame) = 0;
  // Stops streaming, frees the buffers and closes the device; never throws; safe to call twice.
  virtual void stop() = 0;
};

// The real device (/dev/videoN) through V4L2 mmap streaming.
class V4l2Device : public VideoDevice {
 public:
  explicit V4l2Device(std::string path);
  ~V4l2Device() override;
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;

  std::string name() const override { return path_; }
  void open() override;
  VideoFormat setFormat(const VideoFormat& requested) override;
  void start(int buffers) override;
  bool dequeue(RawFrame& frame, int timeout_ms) override;
  void requeue(const RawFrame& frame) override;
  void stop() override;

  // From QUERYCAP after open(): card name, driver, bus.
  const std::string& card() const { return card_; }
  const std::string& driver() const { return driver_; }
  const std::string& busInfo() const { return bus_info_; }
  // Pixel formats the device offers (ENUM_FMT), after open().
  std::vector<uint32_t> formats() const;

 private:
  [[noreturn]] void fail(const std::string& what, int error_number) const;
  int xioctl(unsigned long request, void* arg) const;

  std::string path_;
  int fd_ = -1;
  bool streaming_ = false;
  std::string card_, driver_, bus_info_;
  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  std::vector<Buffer> buffers_;
};

// Character devices /dev/video* present now (sorted); empty when there is none.
std::vector<std::string> listVideoDevices();

}  // namespace lanemap::camera
