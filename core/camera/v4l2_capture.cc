// The camera capture loop and its pure pieces (see v4l2_capture.h).
#include "core/camera/v4l2_capture.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <thread>

namespace lanemap::camera {
namespace {

// ITU T.81 Annex K.3 tables (the ones libjpeg writes by default and MJPEG cameras assume).
const uint8_t kDcLumBits[16] = {0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0};
const uint8_t kDcChromBits[16] = {0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0};
const uint8_t kDcVals[12] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
const uint8_t kAcLumBits[16] = {0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 0x7d};
const uint8_t kAcLumVals[162] = {
    0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61,
    0x07, 0x22, 0x71, 0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52,
    0xd1, 0xf0, 0x24, 0x33, 0x62, 0x72, 0x82, 0x09, 0x0a, 0x16, 0x17, 0x18, 0x19, 0x1a, 0x25,
    0x26, 0x27, 0x28, 0x29, 0x2a, 0x34, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45,
    0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64,
    0x65, 0x66, 0x67, 0x68, 0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x83,
    0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99,
    0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6,
    0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3, 0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3,
    0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe1, 0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8,
    0xe9, 0xea, 0xf1, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa};
const uint8_t kAcChromBits[16] = {0, 2, 1, 2, 4, 4, 3, 4, 7, 5, 4, 4, 0, 1, 2, 0x77};
const uint8_t kAcChromVals[162] = {
    0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61,
    0x71, 0x13, 0x22, 0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xa1, 0xb1, 0xc1, 0x09, 0x23, 0x33,
    0x52, 0xf0, 0x15, 0x62, 0x72, 0xd1, 0x0a, 0x16, 0x24, 0x34, 0xe1, 0x25, 0xf1, 0x17, 0x18,
    0x19, 0x1a, 0x26, 0x27, 0x28, 0x29, 0x2a, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44,
    0x45, 0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63,
    0x64, 0x65, 0x66, 0x67, 0x68, 0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a,
    0x82, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97,
    0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4,
    0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3, 0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca,
    0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7,
    0xe8, 0xe9, 0xea, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa};

void appendTable(std::vector<uint8_t>& seg, uint8_t class_id, const uint8_t* bits,
                 const uint8_t* vals, std::size_t nvals) {
  seg.push_back(class_id);
  seg.insert(seg.end(), bits, bits + 16);
  seg.insert(seg.end(), vals, vals + nvals);
}

int64_t clockUs(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

std::string sizeText(const VideoFormat& f) {
  return std::to_string(f.width) + "x" + std::to_string(f.height) + " " + fourccToString(f.pixelformat);
}

bool handled(uint32_t pixelformat) {
  return pixelformat == kFourccMjpeg || pixelformat == kFourccJpeg || pixelformat == kFourccYuyv;
}

}  // namespace

void CaptureSettings::validate() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument("camera setting " + what); };
  if (format != "auto" && format != "mjpeg" && format != "yuyv") bad("format '" + format + "': auto, mjpeg or yuyv");
  if (width == 0 || height == 0 || width > 16384 || height > 16384) bad("width/height out of range");
  if (!(fps >= 0.0) || fps > 1000.0) bad("fps must be in 0..1000");
  if (jpeg_quality < 1 || jpeg_quality > 100) bad("jpeg_quality must be in 1..100");
  if (buffers < 2 || buffers > 32) bad("buffers must be in 2..32");
  if (poll_timeout_ms < 1) bad("poll_timeout_ms must be >= 1");
  if (!(stall_timeout_s > 0.0)) bad("stall_timeout_s must be > 0");
  if (max_timestamp_age_us <= 0) bad("max_timestamp_age_ms must be > 0");
  if (!(reconnect_initial_s > 0.0) || !(reconnect_max_s >= reconnect_initial_s)) {
    bad("reconnect back-off: need 0 < reconnect_initial_s <= reconnect_max_s");
  }
}

int64_t bufferTimestampToUtime(int64_t ts_us, uint32_t flags, int64_t mono_now_us,
                               int64_t wall_now_us, int64_t max_age_us, bool& fallback) {
  fallback = false;
  const uint32_t clock = flags & kBufFlagTimestampMask;
  int64_t age;
  if (clock == kBufFlagTimestampMonotonic) {
    age = mono_now_us - ts_us;
  } else if (clock == kBufFlagTimestampUnknown) {
    age = wall_now_us - ts_us;  // pre-3.10 drivers stamped with the wall clock
  } else {  // COPY (memory-to-memory devices) or a future clock: not an exposure time
    fallback = true;
    return wall_now_us;
  }
  if (age < -1000 || age > max_age_us) {
    fallback = true;
    return wall_now_us;
  }
  return wall_now_us - std::max<int64_t>(age, 0);
}

int64_t SequenceTracker::update(uint32_t sequence) {
  int64_t dropped = 0;
  if (have_last_) {
    const uint32_t step = sequence - last_;  // modulo 2^32
    // A step of 1 is the next frame; a small step forward is a gap; anything else (0, or a step so
    // large it is really a step back) is a restarted counter.
    if (step >= 2 && step < (1u << 30)) dropped = step - 1;
  }
  have_last_ = true;
  last_ = sequence;
  return dropped;
}

bool yuyvToBgr(const uint8_t* data, std::size_t bytes, uint32_t width, uint32_t height,
               uint32_t stride, cv::Mat& bgr) {
  if (width == 0 || height == 0 || width % 2 != 0) return false;
  if (stride == 0) stride = 2 * width;
  if (stride < 2 * width) return false;
  const std::size_t needed = static_cast<std::size_t>(stride) * (height - 1) + 2 * width;
  if (bytes < needed) return false;
  const cv::Mat yuyv(static_cast<int>(height), static_cast<int>(width), CV_8UC2,
                     const_cast<uint8_t*>(data), stride);
  cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
  return true;
}

std::vector<uint8_t> encodeJpeg(const cv::Mat& bgr, int quality) {
  std::vector<uint8_t> out;
  cv::imencode(".jpg", bgr, out, {cv::IMWRITE_JPEG_QUALITY, quality});
  return out;
}

const std::vector<uint8_t>& standardHuffmanTablesSegment() {
  static const std::vector<uint8_t> seg = [] {
    std::vector<uint8_t> s = {0xFF, 0xC4, 0, 0};
    appendTable(s, 0x00, kDcLumBits, kDcVals, 12);
    appendTable(s, 0x10, kAcLumBits, kAcLumVals, 162);
    appendTable(s, 0x01, kDcChromBits, kDcVals, 12);
    appendTable(s, 0x11, kAcChromBits, kAcChromVals, 162);
    const std::size_t len = s.size() - 2;  // the length field counts itself, not the marker
    s[2] = static_cast<uint8_t>(len >> 8);
    s[3] = static_cast<uint8_t>(len & 0xff);
    return s;
  }();
  return seg;
}

bool mjpegToJpeg(const uint8_t* data, std::size_t bytes, std::vector<uint8_t>& out,
                 bool& inserted_tables) {
  inserted_tables = false;
  if (bytes < 4 || data[0] != 0xFF || data[1] != 0xD8) return false;
  // Walk the header segments up to the first SOS, looking for a DHT.
  std::size_t pos = 2;
  std::size_t sos = 0;
  bool has_dht = false;
  while (pos + 4 <= bytes) {
    if (data[pos] != 0xFF) return false;  // not a marker where one must be
    const uint8_t marker = data[pos + 1];
    if (marker == 0xFF) {  // fill byte
      ++pos;
      continue;
    }
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      pos += 2;  // markers without a length
      continue;
    }
    if (marker == 0xD9) return false;  // end of image before any scan
    if (marker == 0xC4) has_dht = true;
    if (marker == 0xDA) {
      sos = pos;
      break;
    }
    const std::size_t len = (static_cast<std::size_t>(data[pos + 2]) << 8) | data[pos + 3];
    if (len < 2) return false;
    pos += 2 + len;
  }
  if (sos == 0) return false;  // no scan: truncated or not a JPEG
  // The end: the last EOI (drivers may report the whole buffer, with padding after it).
  std::size_t end = bytes;
  for (std::size_t i = bytes - 1; i > sos + 1; --i) {
    if (data[i - 1] == 0xFF && data[i] == 0xD9) {
      end = i + 1;
      break;
    }
  }
  out.clear();
  out.reserve(end + (has_dht ? 0 : standardHuffmanTablesSegment().size()));
  out.insert(out.end(), data, data + sos);
  if (!has_dht) {
    const auto& dht = standardHuffmanTablesSegment();
    out.insert(out.end(), dht.begin(), dht.end());
    inserted_tables = true;
  }
  out.insert(out.end(), data + sos, data + end);
  return true;
}

VideoFormat negotiateFormat(VideoDevice& device, const CaptureSettings& s) {
  VideoFormat want;
  want.width = s.width;
  want.height = s.height;
  want.fps = s.fps;
  want.pixelformat = s.format == "yuyv" ? kFourccYuyv : kFourccMjpeg;
  VideoFormat got = device.setFormat(want);
  if (!handled(got.pixelformat) && s.format == "auto") {
    want.pixelformat = kFourccYuyv;
    got = device.setFormat(want);
  }
  if (!handled(got.pixelformat)) {
    throw VideoDeviceError(VideoDeviceError::Kind::kFatal,
                           device.name() + ": the driver gives " + sizeText(got) + " when asked for " +
                               sizeText(want) + "; lanemap-camera-v4l2 handles MJPG and YUYV");
  }
  if (got.width == 0 || got.height == 0) {
    throw VideoDeviceError(VideoDeviceError::Kind::kFatal, device.name() + ": the driver set a zero image size");
  }
  return got;
}

CaptureClock CaptureClock::system() {
  CaptureClock c;
  c.wall_us = [] { return clockUs(CLOCK_REALTIME); };
  c.mono_us = [] { return clockUs(CLOCK_MONOTONIC); };
  c.sleep = [](double seconds, const std::function<bool()>& stop) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!stop() && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  };
  return c;
}

CameraCapture::CameraCapture(VideoDevice& device, CaptureSettings settings, FrameSink sink,
                             EventSink events, CaptureClock clock)
    : device_(device),
      settings_(std::move(settings)),
      sink_(std::move(sink)),
      events_(std::move(events)),
      clock_(std::move(clock)) {
  settings_.validate();
}

CaptureStats CameraCapture::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

VideoFormat CameraCapture::format() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return format_;
}

void CameraCapture::event(const std::string& state, const std::string& message) const {
  if (events_) events_(state, message);
}

void CameraCapture::startDevice() {
  device_.open();
  const VideoFormat got = negotiateFormat(device_, settings_);
  const bool adjusted = got.width != settings_.width || got.height != settings_.height ||
                        (settings_.format != "auto" &&
                         got.pixelformat != (settings_.format == "yuyv" ? kFourccYuyv : kFourccMjpeg));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    format_ = got;
    if (adjusted) ++stats_.format_adjusted;
  }
  device_.start(settings_.buffers);
  std::ostringstream msg;
  msg << device_.name() << ": streaming " << sizeText(got);
  if (got.fps > 0) msg << " at " << got.fps << " fps";
  if (adjusted) {
    msg << " (asked for " << settings_.width << "x" << settings_.height << " " << settings_.format
        << ": the driver's choice is used)";
  }
  event("streaming", msg.str());
}

void CameraCapture::run(const std::function<bool()>& stop) {
  double backoff = settings_.reconnect_initial_s;
  bool started_once = false;
  while (!stop()) {
    bool streaming = false;
    try {
      startDevice();
      streaming = true;
      if (started_once) {
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.restarts;
      }
      started_once = true;
      backoff = settings_.reconnect_initial_s;
      sequence_.reset();
      stream_first_frame_ = true;
      stream(stop);
      device_.stop();
      event("stopped", device_.name() + ": stopped");
      return;
    } catch (const VideoDeviceError& e) {
      device_.stop();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ++(streaming ? stats_.disconnects : stats_.open_failures);
      }
      if (!e.retryable() || !settings_.reconnect) throw;
      std::ostringstream msg;
      msg << e.what() << "; retrying in " << backoff << " s";
      event("waiting", msg.str());
      clock_.sleep(backoff, stop);
      backoff = std::min(backoff * 2.0, settings_.reconnect_max_s);
    }
  }
  event("stopped", device_.name() + ": stopped");
}

void CameraCapture::stream(const std::function<bool()>& stop) {
  int64_t last_frame_mono = clock_.mono_us();
  while (!stop()) {
    RawFrame raw;
    if (!device_.dequeue(raw, settings_.poll_timeout_ms)) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.poll_timeouts;
      }
      if (clock_.mono_us() - last_frame_mono > static_cast<int64_t>(settings_.stall_timeout_s * 1e6)) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          ++stats_.stalls;
        }
        throw VideoDeviceError(VideoDeviceError::Kind::kDisconnected,
                               device_.name() + ": no frame for " + std::to_string(settings_.stall_timeout_s) +
                                   " s (camera stalled or unplugged)");
      }
      continue;
    }
    last_frame_mono = clock_.mono_us();
    handle(raw);  // requeues the buffer
  }
}

void CameraCapture::handle(const RawFrame& raw) {
  const int64_t mono_now = clock_.mono_us();
  const int64_t wall_now = clock_.wall_us();
  VideoFormat fmt;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    fmt = format_;
  }
  const int64_t dropped = sequence_.update(raw.sequence);
  if (stream_first_frame_) {
    stream_first_frame_ = false;
    stream_first_sequence_ = raw.sequence;
    stream_seq_base_ = next_seq_;
  }
  CapturedFrame out;
  out.seq = stream_seq_base_ + static_cast<int64_t>(static_cast<uint32_t>(raw.sequence - stream_first_sequence_));
  out.width = fmt.width;
  out.height = fmt.height;
  out.source_format = fmt.pixelformat;
  bool fallback = false;
  out.utime = bufferTimestampToUtime(raw.timestamp_us, raw.flags, mono_now, wall_now,
                                     settings_.max_timestamp_age_us, fallback);
  bool ok = !(raw.flags & kBufFlagError) && raw.data != nullptr && raw.bytesused > 0;
  bool inserted = false;
  if (ok && fmt.pixelformat == kFourccYuyv) {
    cv::Mat bgr;
    ok = yuyvToBgr(raw.data, raw.bytesused, fmt.width, fmt.height, fmt.bytesperline, bgr);
    device_.requeue(raw);  // the pixels are copied: give the buffer back before encoding
    if (ok) out.jpeg = encodeJpeg(bgr, settings_.jpeg_quality);
  } else {
    if (ok) ok = mjpegToJpeg(raw.data, raw.bytesused, out.jpeg, inserted);
    device_.requeue(raw);
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.dropped += dropped;
    if (fallback) ++stats_.timestamp_fallbacks;
    if (!ok) {
      ++stats_.corrupt;
      return;
    }
    if (inserted) ++stats_.huffman_inserted;
    ++stats_.frames;
  }
  next_seq_ = out.seq + 1;
  sink_(out);
}

}  // namespace lanemap::camera
