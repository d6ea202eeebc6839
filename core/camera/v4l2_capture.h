// The capture loop of lanemap-camera-v4l2, over any VideoDevice (core/camera/v4l2_device.h), and
// the pure pieces it is made of:
//   - format negotiation that honours what the driver returns (size, pixel format, frame rate);
//   - MJPEG frames passed through as complete JPEG files (trimmed at the end-of-image marker; the
//     standard Huffman tables inserted when the camera left them out, as most UVC cameras do);
//   - YUYV frames converted to BGR (row stride honoured) and JPEG-encoded with OpenCV;
//   - the kernel buffer timestamp (CLOCK_MONOTONIC when V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC is set)
//     converted to utime (microseconds since the epoch);
//   - drops counted from gaps in the driver's `sequence` counter;
//   - a device that is missing, unplugged or stalls: a clear error, or (reconnect on) a retry with
//     exponential back-off.
// No LCM here: the driver (drivers/camera_v4l2) publishes each CapturedFrame as image_t.
#pragma once

#include "core/camera/v4l2_device.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace lanemap::camera {

struct CaptureSettings {
  std::string format = "auto";  // mjpeg | yuyv | auto (MJPEG, else YUYV)
  uint32_t width = 1280;
  uint32_t height = 720;
  double fps = 10.0;            // asked through S_PARM; 0 = the driver's default
  int jpeg_quality = 90;        // YUYV frames are encoded at this quality
  int buffers = 4;              // mmap buffers
  int poll_timeout_ms = 500;    // one poll() wait
  double stall_timeout_s = 5.0; // no frame for this long while streaming: treated as unplugged
  int64_t max_timestamp_age_us = 1000000;  // buffer timestamp older (or newer) than this vs now: use now
  bool reconnect = true;        // retry a missing / unplugged / busy device
  double reconnect_initial_s = 0.5;  // first back-off; doubles after every failed attempt ...
  double reconnect_max_s = 8.0;      // ... up to this

  void validate() const;  // throws std::invalid_argument naming the setting
};

struct CapturedFrame {
  int64_t utime = 0;          // exposure time, microseconds since the epoch
  int64_t seq = 0;            // continuous across restarts; gaps = dropped frames
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t source_format = 0; // the device's pixel format (MJPG or YUYV)
  std::vector<uint8_t> jpeg;  // a complete JPEG file
};

struct CaptureStats {
  int64_t frames = 0;               // frames handed to the sink
  int64_t dropped = 0;              // missing from the driver's sequence
  int64_t corrupt = 0;              // V4L2_BUF_FLAG_ERROR, short YUYV, data that is no JPEG
  int64_t huffman_inserted = 0;     // MJPEG frames that lacked their Huffman tables
  int64_t timestamp_fallbacks = 0;  // buffer timestamp unusable: stamped with the dequeue time
  int64_t poll_timeouts = 0;
  int64_t stalls = 0;               // stall_timeout_s without a frame
  int64_t disconnects = 0;          // errors while streaming (unplugged)
  int64_t open_failures = 0;        // failed attempts to open / set up the device
  int64_t restarts = 0;             // successful starts after the first
  int64_t format_adjusted = 0;      // the driver changed the size or pixel format asked for
};

// --- pure pieces ---

// The buffer timestamp as utime. A CLOCK_MONOTONIC stamp is moved to the wall clock by the offset
// between the two clocks now; an "unknown" stamp is taken as wall-clock time (old drivers used
// gettimeofday) when it is plausible. Anything older than max_age_us or in the future (by more than
// 1 ms) gives wall_now_us and sets `fallback`.
int64_t bufferTimestampToUtime(int64_t timestamp_us, uint32_t flags, int64_t mono_now_us,
                               int64_t wall_now_us, int64_t max_age_us, bool& fallback);

// Counts frames missing from the driver's 32-bit sequence counter (wrap-around handled).
class SequenceTracker {
 public:
  // Frames dropped just before this one. A counter that goes back (or repeats) means the stream
  // restarted: no drop is counted.
  int64_t update(uint32_t sequence);
  void reset() { have_last_ = false; }

 private:
  bool have_last_ = false;
  uint32_t last_ = 0;
};

// YUYV 4:2:2 (Y0 U Y1 V per pixel pair) -> BGR (BT.601, as OpenCV's COLOR_YUV2BGR_YUYV), rows
// `stride` bytes apart. False when `bytes` is too short for the frame or the sizes are bad.
bool yuyvToBgr(const uint8_t* data, std::size_t bytes, uint32_t width, uint32_t height,
               uint32_t stride, cv::Mat& bgr);

std::vector<uint8_t> encodeJpeg(const cv::Mat& bgr, int quality);

// An MJPEG buffer as a complete JPEG: must start with SOI (FF D8); cut after its last EOI (FF D9)
// when the driver reports padding; the standard Huffman tables (ITU T.81 K.3) inserted before the
// first SOS when no DHT segment precedes it. False (out untouched) when it is no JPEG.
bool mjpegToJpeg(const uint8_t* data, std::size_t bytes, std::vector<uint8_t>& out,
                 bool& inserted_tables);

// The DHT segment (marker included) of the four standard tables.
const std::vector<uint8_t>& standardHuffmanTablesSegment();

// Sets the device's format per `settings`, honouring what the driver returns. Throws
// VideoDeviceError (kFatal) when the driver offers no pixel format lanemap can use.
VideoFormat negotiateFormat(VideoDevice& device, const CaptureSettings& settings);

// --- the loop ---

struct CaptureClock {
  std::function<int64_t()> wall_us;  // CLOCK_REALTIME
  std::function<int64_t()> mono_us;  // CLOCK_MONOTONIC
  // Waits `seconds` (the reconnect back-off), returning early once stop() is true.
  std::function<void(double seconds, const std::function<bool()>& stop)> sleep;
  static CaptureClock system();
};

class CameraCapture {
 public:
  using FrameSink = std::function<void(const CapturedFrame&)>;
  // (state, message): state is "streaming", "waiting" (for the device) or "stopped"; the message
  // says what happened, for the log.
  using EventSink = std::function<void(const std::string& state, const std::string& message)>;

  CameraCapture(VideoDevice& device, CaptureSettings settings, FrameSink sink,
                EventSink events = {}, CaptureClock clock = CaptureClock::system());

  // Captures until stop() is true. Throws VideoDeviceError when the device fails for good: a fatal
  // error, or any error with reconnect off.
  void run(const std::function<bool()>& stop);

  CaptureStats stats() const;
  VideoFormat format() const;  // as negotiated (zero before the first start)

 private:
  void startDevice();
  void stream(const std::function<bool()>& stop);
  void handle(const RawFrame& raw);
  void event(const std::string& state, const std::string& message) const;

  VideoDevice& device_;
  CaptureSettings settings_;
  FrameSink sink_;
  EventSink events_;
  CaptureClock clock_;
  mutable std::mutex mutex_;
  CaptureStats stats_;
  VideoFormat format_;
  SequenceTracker sequence_;
  bool stream_first_frame_ = true;
  uint32_t stream_first_sequence_ = 0;
  int64_t stream_seq_base_ = 0;
  int64_t next_seq_ = 0;
};

}  // namespace lanemap::camera
