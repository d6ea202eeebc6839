// V4l2Device: Video4Linux2 mmap streaming (see v4l2_device.h).
#include "core/camera/v4l2_device.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>

namespace lanemap::camera {

static_assert(kFourccMjpeg == V4L2_PIX_FMT_MJPEG);
static_assert(kFourccJpeg == V4L2_PIX_FMT_JPEG);
static_assert(kFourccYuyv == V4L2_PIX_FMT_YUYV);
static_assert(kBufFlagError == V4L2_BUF_FLAG_ERROR);
static_assert(kBufFlagTimestampMask == V4L2_BUF_FLAG_TIMESTAMP_MASK);
static_assert(kBufFlagTimestampMonotonic == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC);
static_assert(kBufFlagTimestampCopy == V4L2_BUF_FLAG_TIMESTAMP_COPY);

std::string fourccToString(uint32_t code) {
  std::string s(4, '?');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xff);
    if (c >= 0x20 && c < 0x7f) s[i] = c;
  }
  return s;
}

VideoDeviceError::Kind classifyErrno(int e, bool while_streaming) {
  using K = VideoDeviceError::Kind;
  switch (e) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return while_streaming ? K::kDisconnected : K::kMissing;
    case EIO:
    case EPIPE:
      return K::kDisconnected;
    case EBUSY:
      return K::kBusy;
    default:
      return K::kFatal;
  }
}

V4l2Device::V4l2Device(std::string path) : path_(std::move(path)) {}

V4l2Device::~V4l2Device() { stop(); }

void V4l2Device::fail(const std::string& what, int e) const {
  std::string msg = path_ + ": " + what + ": " + std::strerror(e);
  const auto kind = classifyErrno(e, streaming_);
  if (kind == VideoDeviceError::Kind::kMissing) msg += " (camera not plugged in, or wrong device path?)";
  if (kind == VideoDeviceError::Kind::kDisconnected) msg += " (camera unplugged?)";
  if (kind == VideoDeviceError::Kind::kBusy) msg += " (another program is using the camera)";
  throw VideoDeviceError(kind, msg, e);
}

int V4l2Device::xioctl(unsigned long request, void* arg) const {
  int r;
  do {
    r = ::ioctl(fd_, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

void V4l2Device::open() {
  stop();
  fd_ = ::open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) fail("cannot open", errno);
  struct stat st {};
  if (fstat(fd_, &st) != 0 || !S_ISCHR(st.st_mode)) {
    stop();
    throw VideoDeviceError(VideoDeviceError::Kind::kFatal, path_ + ": not a character device");
  }
  v4l2_capability cap{};
  if (xioctl(VIDIOC_QUERYCAP, &cap) != 0) {
    const int e = errno;
    stop();
    if (e == ENOTTY || e == EINVAL) {
      throw VideoDeviceError(VideoDeviceError::Kind::kFatal,
                             path_ + ": not a V4L2 device (VIDIOC_QUERYCAP: " + std::strerror(e) + ")", e);
    }
    fail("VIDIOC_QUERYCAP", e);
  }
  card_ = reinterpret_cast<const char*>(cap.card);
  driver_ = reinterpret_cast<const char*>(cap.driver);
  bus_info_ = reinterpret_cast<const char*>(cap.bus_info);
  const uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    stop();
    throw VideoDeviceError(VideoDeviceError::Kind::kFatal,
                           path_ + " (" + card_ + "): not a video capture device (a metadata node? try the other /dev/video*)");
  }
  if (!(caps & V4L2_CAP_STREAMING)) {
    stop();
    throw VideoDeviceError(VideoDeviceError::Kind::kFatal, path_ + " (" + card_ + "): no streaming I/O");
  }
}

std::vector<uint32_t> V4l2Device::formats() const {
  std::vector<uint32_t> out;
  if (fd_ < 0) return out;
  for (uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_ENUM_FMT, &d) != 0) break;
    out.push_back(d.pixelformat);
  }
  return out;
}

VideoFormat V4l2Device::setFormat(const VideoFormat& requested) {
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = requested.width;
  fmt.fmt.pix.height = requested.height;
  fmt.fmt.pix.pixelformat = requested.pixelformat;
  fmt.fmt.pix.field = V4L2_FIELD_ANY;
  if (xioctl(VIDIOC_S_FMT, &fmt) != 0) fail("VIDIOC_S_FMT", errno);
  VideoFormat got;
  got.width = fmt.fmt.pix.width;
  got.height = fmt.fmt.pix.height;
  got.pixelformat = fmt.fmt.pix.pixelformat;
  got.bytesperline = fmt.fmt.pix.bytesperline;
  got.sizeimage = fmt.fmt.pix.sizeimage;

  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (requested.fps > 0 && xioctl(VIDIOC_G_PARM, &parm) == 0 &&
      (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator =
        static_cast<uint32_t>(std::lround(requested.fps * 1000.0));
    xioctl(VIDIOC_S_PARM, &parm);  // the driver rounds to a rate it has; read back below
  }
  std::memset(&parm, 0, sizeof(parm));
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0) {
    got.fps = static_cast<double>(parm.parm.capture.timeperframe.denominator) /
              parm.parm.capture.timeperframe.numerator;
  }
  return got;
}

void V4l2Device::start(int count) {
  v4l2_requestbuffers req{};
  req.count = static_cast<uint32_t>(std::max(2, count));
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(VIDIOC_REQBUFS, &req) != 0) {
    if (errno == EINVAL) {
      throw VideoDeviceError(VideoDeviceError::Kind::kFatal, path_ + ": no mmap streaming (VIDIOC_REQBUFS)", EINVAL);
    }
    fail("VIDIOC_REQBUFS", errno);
  }
  if (req.count < 2) {
    throw VideoDeviceError(VideoDeviceError::Kind::kFatal,
                           path_ + ": driver gave " + std::to_string(req.count) + " buffers, need 2");
  }
  buffers_.assign(req.count, {});
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(VIDIOC_QUERYBUF, &b) != 0) fail("VIDIOC_QUERYBUF", errno);
    void* p = mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) fail("mmap", errno);
    buffers_[i] = {p, b.length};
  }
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(VIDIOC_QBUF, &b) != 0) fail("VIDIOC_QBUF", errno);
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_STREAMON, &type) != 0) fail("VIDIOC_STREAMON", errno);
  streaming_ = true;
}

bool V4l2Device::dequeue(RawFrame& frame, int timeout_ms) {
  pollfd pfd{fd_, POLLIN, 0};
  int r;
  do {
    r = ::poll(&pfd, 1, timeout_ms);
  } while (r < 0 && errno == EINTR);
  if (r < 0) fail("poll", errno);
  if (r == 0) return false;
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (xioctl(VIDIOC_DQBUF, &b) != 0) {
    if (errno == EAGAIN) {
      // POLLERR/POLLHUP without a buffer: the driver's way of saying the device is gone.
      if (pfd.revents & (POLLERR | POLLHUP)) fail("poll", ENODEV);
      return false;
    }
    fail("VIDIOC_DQBUF", errno);
  }
  if (b.index >= buffers_.size()) fail("VIDIOC_DQBUF returned a bad index", EINVAL);
  frame.index = static_cast<int>(b.index);
  frame.data = static_cast<const uint8_t*>(buffers_[b.index].start);
  frame.bytesused = std::min<std::size_t>(b.bytesused, buffers_[b.index].length);
  frame.sequence = b.sequence;
  frame.timestamp_us = static_cast<int64_t>(b.timestamp.tv_sec) * 1000000 + b.timestamp.tv_usec;
  frame.flags = b.flags;
  return true;
}

void V4l2Device::requeue(const RawFrame& frame) {
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = static_cast<uint32_t>(frame.index);
  if (xioctl(VIDIOC_QBUF, &b) != 0) fail("VIDIOC_QBUF", errno);
}

void V4l2Device::stop() {
  if (fd_ >= 0 && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(VIDIOC_STREAMOFF, &type);
  }
  streaming_ = false;
  for (auto& b : buffers_) {
    if (b.start) munmap(b.start, b.length);
  }
  buffers_.clear();
  if (fd_ >= 0) {
    // Free the driver's buffers (REQBUFS 0) so that the next open can set a new format.
    v4l2_requestbuffers req{};
    req.count = 0;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(VIDIOC_REQBUFS, &req);
    ::close(fd_);
  }
  fd_ = -1;
}

std::vector<std::string> listVideoDevices() {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("video", 0) != 0) continue;
    struct stat st {};
    if (stat(e.path().c_str(), &st) == 0 && S_ISCHR(st.st_mode)) out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace lanemap::camera
