// lanemap-camera-v4l2: the capture loop of core/camera/v4l2_capture.h driven by a scripted fake
// VideoDevice (MJPEG and YUYV frames, a sequence gap, corrupt buffers, ENODEV mid-stream and a
// reconnect with back-off, a stall, a driver that changes the requested size or offers no usable
// format), the pure pieces (timestamp conversion, sequence drops, YUYV -> BGR with a row stride,
// MJPEG completed with the standard Huffman tables), the real V4l2Device's error paths, a real
// /dev/video* when there is one (skipped otherwise), and the driver binary's errors and STATUS.
#include "core/camera/v4l2_capture.h"
#include "core/camera/v4l2_device.h"
#include "lanemap/image_t.hpp"
#include "processes/framework/process.h"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cerrno>
#include <deque>

namespace {

using namespace lanemap::camera;
using namespace std::chrono_literals;

constexpr int64_t kWallMinusMono = 1'700'000'000'000'000;  // the fake clocks' offset (us)

// A JPEG of a smooth test pattern, as libjpeg writes it (with its DHT segments).
std::vector<uint8_t> testJpeg(int w, int h, int quality = 90) {
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>(x * 255 / w), static_cast<uint8_t>(y * 255 / h),
                                          static_cast<uint8_t>((x + y) % 256));
  std::vector<uint8_t> out;
  cv::imencode(".jpg", img, out, {cv::IMWRITE_JPEG_QUALITY, quality});
  return out;
}

// Splits a JPEG's header into segments: (marker, offset, total length incl. marker) up to SOS.
struct Segment {
  uint8_t marker;
  std::size_t offset, length;
};
std::vector<Segment> headerSegments(const std::vector<uint8_t>& j) {
  std::vector<Segment> segs;
  std::size_t pos = 2;
  while (pos + 4 <= j.size() && j[pos] == 0xFF) {
    const uint8_t m = j[pos + 1];
    const std::size_t len = (std::size_t(j[pos + 2]) << 8) | j[pos + 3];
    segs.push_back({m, pos, len + 2});
    if (m == 0xDA) break;
    pos += len + 2;
  }
  return segs;
}

std::vector<uint8_t> withoutDht(const std::vector<uint8_t>& j) {
  std::vector<uint8_t> out(j.begin(), j.begin() + 2);
  std::size_t sos = 0;
  for (const auto& s : headerSegments(j)) {
    if (s.marker == 0xDA) {
      sos = s.offset;
      break;
    }
    if (s.marker != 0xC4) out.insert(out.end(), j.begin() + s.offset, j.begin() + s.offset + s.length);
  }
  out.insert(out.end(), j.begin() + sos, j.end());
  return out;
}

// YUYV of a frame made of vertical colour bars (each bar 8 pixels wide, one (Y, U, V) each), with
// `stride` bytes per row; the padding bytes are garbage.
struct Bar {
  uint8_t y, u, v;
};
std::vector<uint8_t> yuyvBars(const std::vector<Bar>& bars, int h, int stride) {
  const int w = static_cast<int>(bars.size()) * 8;
  std::vector<uint8_t> buf(static_cast<std::size_t>(stride) * h, 0xEE);
  for (int r = 0; r < h; ++r)
    for (int x = 0; x < w; x += 2) {
      const Bar& b = bars[x / 8];
      uint8_t* p = &buf[static_cast<std::size_t>(r) * stride + 2 * x];
      p[0] = b.y;
      p[1] = b.u;
      p[2] = b.y;
      p[3] = b.v;
    }
  return buf;
}

// ITU-R BT.601, video range (Y 16..235, U/V 16..240 around 128): what YUYV cameras send.
cv::Vec3d bt601ToBgr(const Bar& b) {
  const double y = 1.164 * (b.y - 16.0), u = b.u - 128.0, v = b.v - 128.0;
  auto clip = [](double x) { return std::clamp(x, 0.0, 255.0); };
  return {clip(y + 2.018 * u), clip(y - 0.391 * u - 0.813 * v), clip(y + 1.596 * v)};
}

// The scripted device.
class FakeDevice : public VideoDevice {
 public:
  struct Step {
    enum Kind { kFrame, kTimeout, kError } kind = kFrame;
    uint32_t sequence = 0;
    std::vector<uint8_t> data;
    uint32_t flags = kBufFlagTimestampMonotonic;
    int64_t age_us = 20000;  // timestamp = the fake monotonic clock at dequeue - age
    int error = 0;
  };
  std::deque<Step> script;
  int open_failures_left = 0;           // open() fails with ENOENT this many times
  int open_error = ENOENT;
  std::optional<VideoFormat> driver_format;  // what S_FMT sets; default: what was asked
  std::vector<VideoFormat> requested;
  int opens = 0, starts = 0, stops = 0, requeues = 0, outstanding = 0;
  bool exhausted = false;
  int64_t mono_us = 5'000'000'000;  // the fake CLOCK_MONOTONIC, advanced 100 ms per dequeue
  std::vector<uint8_t> current;

  std::string name() const override { return "/dev/fake0"; }
  void open() override {
    ++opens;
    if (open_failures_left > 0) {
      --open_failures_left;
      throw VideoDeviceError(classifyErrno(open_error, false), "/dev/fake0: cannot open: missing", open_error);
    }
    is_open_ = true;
  }
  VideoFormat setFormat(const VideoFormat& want) override {
    requested.push_back(want);
    VideoFormat got = driver_format.value_or(want);
    if (got.pixelformat == kFourccYuyv && got.bytesperline == 0) got.bytesperline = 2 * got.width;
    return got;
  }
  void start(int) override {
    EXPECT_TRUE(is_open_);
    ++starts;
  }
  bool dequeue(RawFrame& f, int timeout_ms) override {
    EXPECT_TRUE(is_open_);
    EXPECT_EQ(outstanding, 0) << "the loop holds a buffer it did not requeue";
    if (script.empty()) {
      exhausted = true;
      mono_us += timeout_ms * 1000;
      return false;
    }
    Step s = std::move(script.front());
    script.pop_front();
    if (s.kind == Step::kTimeout) {
      mono_us += timeout_ms * 1000;
      return false;
    }
    if (s.kind == Step::kError) {
      throw VideoDeviceError(classifyErrno(s.error, true), "/dev/fake0: VIDIOC_DQBUF: No such device (camera unplugged?)",
                             s.error);
    }
    mono_us += 100000;
    current = std::move(s.data);
    f.index = 0;
    f.data = current.data();
    f.bytesused = current.size();
    f.sequence = s.sequence;
    f.timestamp_us = mono_us - s.age_us;
    f.flags = s.flags;
    ++outstanding;
    return true;
  }
  void requeue(const RawFrame&) override {
    ++requeues;
    --outstanding;
  }
  void stop() override {
    ++stops;
    is_open_ = false;
  }

 private:
  bool is_open_ = false;
};

struct Harness {
  FakeDevice dev;
  std::vector<CapturedFrame> frames;
  std::vector<int64_t> frame_wall_at_dequeue;  // the fake wall clock when each frame was handled
  std::vector<std::pair<std::string, std::string>> events;
  std::vector<double> sleeps;

  CaptureClock clock() {
    CaptureClock c;
    c.mono_us = [this] { return dev.mono_us; };
    c.wall_us = [this] { return dev.mono_us + kWallMinusMono; };
    c.sleep = [this](double s, const std::function<bool()>&) {
      sleeps.push_back(s);
      dev.mono_us += static_cast<int64_t>(s * 1e6);
    };
    return c;
  }
  CaptureStats run(const CaptureSettings& settings) {
    CameraCapture cap(
        dev, settings,
        [this](const CapturedFrame& f) {
          frames.push_back(f);
          frame_wall_at_dequeue.push_back(dev.mono_us + kWallMinusMono);
        },
        [this](const std::string& state, const std::string& msg) { events.emplace_back(state, msg); }, clock());
    cap.run([this] { return dev.exhausted; });
    format = cap.format();
    return cap.stats();
  }
  VideoFormat format;
};

FakeDevice::Step frame(uint32_t seq, std::vector<uint8_t> data) {
  FakeDevice::Step s;
  s.sequence = seq;
  s.data = std::move(data);
  return s;
}

CaptureSettings settings640() {
  CaptureSettings s;
  s.width = 640;
  s.height = 360;
  s.fps = 10;
  return s;
}

// --- pure pieces ---

TEST(CameraTimestamp, MonotonicBufferStampMovesToTheWallClock) {
  bool fb = true;
  // Exposure 35 ms before "now" on CLOCK_MONOTONIC: 35 ms before now on the wall clock.
  EXPECT_EQ(bufferTimestampToUtime(9'965'000, kBufFlagTimestampMonotonic, 10'000'000, 1'700'000'000'000'000, 1'000'000, fb),
            1'700'000'000'000'000 - 35'000);
  EXPECT_FALSE(fb);
  // Unknown clock (old drivers: gettimeofday): a plausible wall time is kept as it is.
  EXPECT_EQ(bufferTimestampToUtime(1'699'999'999'990'000, kBufFlagTimestampUnknown, 10'000'000, 1'700'000'000'000'000,
                                   1'000'000, fb),
            1'699'999'999'990'000);
  EXPECT_FALSE(fb);
  // Fallbacks to now: COPY (no exposure time), older than the limit, in the future, unknown junk.
  for (auto [ts, flags] : std::vector<std::pair<int64_t, uint32_t>>{{9'990'000, kBufFlagTimestampCopy},
                                                                    {8'000'000, kBufFlagTimestampMonotonic},
                                                                    {10'500'000, kBufFlagTimestampMonotonic},
                                                                    {0, kBufFlagTimestampUnknown}}) {
    EXPECT_EQ(bufferTimestampToUtime(ts, flags, 10'000'000, 1'700'000'000'000'000, 1'000'000, fb), 1'700'000'000'000'000);
    EXPECT_TRUE(fb) << ts << " flags " << flags;
  }
}

TEST(CameraSequence, GapsAreDropsAcrossWrapAndRestartsAreNot) {
  SequenceTracker t;
  EXPECT_EQ(t.update(7), 0);  // first frame
  EXPECT_EQ(t.update(8), 0);
  EXPECT_EQ(t.update(11), 2);  // 9 and 10 missing
  EXPECT_EQ(t.update(25), 13);  // 12..24 missing
  SequenceTracker w;
  EXPECT_EQ(w.update(0xFFFFFFFEu), 0);
  EXPECT_EQ(w.update(0xFFFFFFFFu), 0);
  EXPECT_EQ(w.update(1u), 1);  // 0 missing across the wrap
  EXPECT_EQ(w.update(1u), 0);  // repeated: a restart, not 4 billion drops
  EXPECT_EQ(w.update(0u), 0);  // went back: a restart
  EXPECT_EQ(w.update(2u), 1);
}

TEST(CameraYuyv, ConvertsBt601WithRowStrideAndRejectsShortBuffers) {
  const std::vector<Bar> bars = {{16, 128, 128}, {235, 128, 128}, {126, 128, 128}, {81, 90, 240},
                                 {145, 54, 34},  {41, 240, 110},  {170, 166, 16},  {106, 202, 222}};
  const int w = 64, h = 6, stride = 2 * w + 24;
  const auto buf = yuyvBars(bars, h, stride);
  cv::Mat bgr;
  ASSERT_TRUE(yuyvToBgr(buf.data(), buf.size(), w, h, stride, bgr));
  ASSERT_EQ(bgr.cols, w);
  ASSERT_EQ(bgr.rows, h);
  for (int i = 0; i < static_cast<int>(bars.size()); ++i) {
    const cv::Vec3d want = bt601ToBgr(bars[i]);
    for (int r : {0, h - 1})
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(bgr.at<cv::Vec3b>(r, 8 * i + 3)[c], want[c], 2.0) << "bar " << i << " channel " << c;
  }
  // Black and white are exact.
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 8), cv::Vec3b(255, 255, 255));
  // The last row may end without padding; one byte less is short.
  const std::size_t needed = static_cast<std::size_t>(stride) * (h - 1) + 2 * w;
  EXPECT_TRUE(yuyvToBgr(buf.data(), needed, w, h, stride, bgr));
  EXPECT_FALSE(yuyvToBgr(buf.data(), needed - 1, w, h, stride, bgr));
  EXPECT_FALSE(yuyvToBgr(buf.data(), buf.size(), w, h, 2 * w - 2, bgr));  // stride < row
  EXPECT_FALSE(yuyvToBgr(buf.data(), buf.size(), w - 1, h, stride, bgr));  // odd width
}

TEST(CameraMjpeg, StandardHuffmanTablesAreLibjpegsDefaultOnes) {
  // libjpeg (through OpenCV, no optimisation) writes exactly the ITU T.81 K.3 tables, one DHT
  // segment per table or all in one; their payloads concatenated must equal ours.
  const auto j = testJpeg(64, 48);
  std::vector<uint8_t> payload;
  for (const auto& s : headerSegments(j))
    if (s.marker == 0xC4) payload.insert(payload.end(), j.begin() + s.offset + 4, j.begin() + s.offset + s.length);
  const auto& ours = standardHuffmanTablesSegment();
  ASSERT_EQ(ours.size(), 4u + 4 * 17 + 12 + 162 + 12 + 162);
  EXPECT_EQ(ours[2] * 256 + ours[3], static_cast<int>(ours.size()) - 2);
  EXPECT_EQ(std::vector<uint8_t>(ours.begin() + 4, ours.end()), payload);
}

TEST(CameraMjpeg, FrameWithoutTablesIsCompletedAndPaddingCut) {
  const auto original = testJpeg(96, 64);
  auto stripped = withoutDht(original);
  ASSERT_LT(stripped.size(), original.size());
  const std::size_t jpeg_end = stripped.size();
  stripped.resize(stripped.size() + 3000, 0x00);  // the driver reports the whole buffer
  std::vector<uint8_t> out;
  bool inserted = false;
  ASSERT_TRUE(mjpegToJpeg(stripped.data(), stripped.size(), out, inserted));
  EXPECT_TRUE(inserted);
  EXPECT_EQ(out.size(), jpeg_end + standardHuffmanTablesSegment().size());
  EXPECT_EQ(out[out.size() - 2], 0xFF);
  EXPECT_EQ(out.back(), 0xD9);
  // Huffman coding is lossless: same tables, same pixels as the original file.
  const cv::Mat a = cv::imdecode(original, cv::IMREAD_COLOR), b = cv::imdecode(out, cv::IMREAD_COLOR);
  ASSERT_FALSE(b.empty());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  // A complete JPEG passes byte for byte.
  ASSERT_TRUE(mjpegToJpeg(original.data(), original.size(), out, inserted));
  EXPECT_FALSE(inserted);
  EXPECT_EQ(out, original);
  // Not a JPEG, or cut inside the header: refused.
  const std::vector<uint8_t> junk(500, 0x5A);
  EXPECT_FALSE(mjpegToJpeg(junk.data(), junk.size(), out, inserted));
  EXPECT_FALSE(mjpegToJpeg(original.data(), 100, out, inserted));
  EXPECT_FALSE(mjpegToJpeg(original.data(), 3, out, inserted));
}

// --- the loop over the fake device ---

TEST(CameraCaptureLoop, MjpegPassesThroughStampsAndCountsSequenceGaps) {
  Harness h;
  const auto jpeg = testJpeg(640, 360);
  for (uint32_t seq : {10u, 11u, 12u, 15u, 16u}) h.dev.script.push_back(frame(seq, jpeg));
  h.dev.script[2].age_us = 45000;
  const CaptureStats st = h.run(settings640());

  ASSERT_EQ(h.frames.size(), 5u);
  EXPECT_EQ(st.frames, 5);
  EXPECT_EQ(st.dropped, 2);  // 13, 14
  EXPECT_EQ(st.corrupt, 0);
  EXPECT_EQ(st.timestamp_fallbacks, 0);
  const std::vector<int64_t> seqs = {0, 1, 2, 5, 6};
  for (std::size_t i = 0; i < h.frames.size(); ++i) {
    const auto& f = h.frames[i];
    EXPECT_EQ(f.seq, seqs[i]);
    EXPECT_EQ(f.jpeg, jpeg) << "a complete MJPEG frame passes unchanged";
    EXPECT_EQ(f.width, 640u);
    EXPECT_EQ(f.height, 360u);
    EXPECT_EQ(f.source_format, kFourccMjpeg);
    EXPECT_EQ(f.utime, h.frame_wall_at_dequeue[i] - (i == 2 ? 45000 : 20000)) << i;
  }
  // Asked for what the settings say, MJPEG first; streamed once, every buffer given back.
  ASSERT_EQ(h.dev.requested.size(), 1u);
  EXPECT_EQ(h.dev.requested[0].pixelformat, kFourccMjpeg);
  EXPECT_EQ(h.dev.requested[0].width, 640u);
  EXPECT_DOUBLE_EQ(h.dev.requested[0].fps, 10.0);
  EXPECT_EQ(h.dev.starts, 1);
  EXPECT_EQ(h.dev.requeues, 5);
  EXPECT_EQ(st.restarts, 0);
  ASSERT_FALSE(h.events.empty());
  EXPECT_EQ(h.events.front().first, "streaming");
  EXPECT_EQ(h.events.back().first, "stopped");
}

TEST(CameraCaptureLoop, CorruptBuffersAreCountedRequeuedAndLeaveASeqGap) {
  Harness h;
  const auto jpeg = testJpeg(640, 360);
  h.dev.script.push_back(frame(0, jpeg));
  auto bad = frame(1, jpeg);
  bad.flags |= kBufFlagError;  // the driver marks a damaged frame
  h.dev.script.push_back(bad);
  h.dev.script.push_back(frame(2, std::vector<uint8_t>(4000, 0x11)));  // not a JPEG
  h.dev.script.push_back(frame(3, std::vector<uint8_t>()));            // empty
  auto stale = frame(4, jpeg);
  stale.age_us = 5'000'000;  // 5 s old: stamped with the dequeue time instead
  h.dev.script.push_back(stale);
  const CaptureStats st = h.run(settings640());
  ASSERT_EQ(h.frames.size(), 2u);
  EXPECT_EQ(st.corrupt, 3);
  EXPECT_EQ(st.dropped, 0);
  EXPECT_EQ(st.timestamp_fallbacks, 1);
  EXPECT_EQ(h.frames[0].seq, 0);
  EXPECT_EQ(h.frames[1].seq, 4);
  EXPECT_EQ(h.frames[1].utime, h.frame_wall_at_dequeue[1]);
  EXPECT_EQ(h.dev.requeues, 5);
}

TEST(CameraCaptureLoop, DriverThatChangesTheSizeAndHasOnlyYuyvIsHonoured) {
  Harness h;
  // Asked for 1280x720 MJPEG, the driver sets 320x240 YUYV with padded rows.
  VideoFormat driver;
  driver.width = 320;
  driver.height = 240;
  driver.pixelformat = kFourccYuyv;
  driver.bytesperline = 2 * 320 + 64;
  h.dev.driver_format = driver;
  std::vector<Bar> bars;
  for (int i = 0; i < 40; ++i) bars.push_back({static_cast<uint8_t>(30 + 4 * i), static_cast<uint8_t>(100 + i), 150});
  const auto yuyv = yuyvBars(bars, 240, 2 * 320 + 64);
  h.dev.script.push_back(frame(0, yuyv));
  h.dev.script.push_back(frame(1, std::vector<uint8_t>(yuyv.begin(), yuyv.begin() + 1000)));  // short
  h.dev.script.push_back(frame(2, yuyv));
  CaptureSettings s = settings640();
  s.width = 1280;
  s.height = 720;
  s.jpeg_quality = 95;
  const CaptureStats st = h.run(s);

  EXPECT_EQ(h.format.width, 320u);
  EXPECT_EQ(h.format.height, 240u);
  EXPECT_EQ(st.format_adjusted, 1);
  EXPECT_EQ(st.corrupt, 1);
  ASSERT_EQ(h.frames.size(), 2u);
  for (const auto& f : h.frames) {
    EXPECT_EQ(f.width, 320u);
    EXPECT_EQ(f.height, 240u);
    EXPECT_EQ(f.source_format, kFourccYuyv);
    const cv::Mat img = cv::imdecode(f.jpeg, cv::IMREAD_COLOR);
    ASSERT_EQ(img.cols, 320);
    ASSERT_EQ(img.rows, 240);
    // Bar centres (away from JPEG's chroma blur at the edges) hold the BT.601 colours.
    for (int i = 2; i < 40; i += 9) {
      const cv::Vec3d want = bt601ToBgr(bars[i]);
      const cv::Scalar got = cv::mean(img(cv::Rect(8 * i + 2, 100, 4, 40)));
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 4.0) << "bar " << i << " channel " << c;
    }
  }
  EXPECT_EQ(h.frames[1].seq, 2);
  // The "auto" request was MJPEG; the YUYV answer was taken without asking again.
  ASSERT_EQ(h.dev.requested.size(), 1u);
}

TEST(CameraCaptureLoop, NoUsablePixelFormatIsAFatalClearError) {
  Harness h;
  VideoFormat driver;
  driver.width = 640;
  driver.height = 360;
  driver.pixelformat = fourcc('R', 'G', 'B', '3');
  h.dev.driver_format = driver;
  CaptureSettings s = settings640();
  s.reconnect = true;  // fatal all the same
  try {
    h.run(s);
    FAIL() << "expected VideoDeviceError";
  } catch (const VideoDeviceError& e) {
    EXPECT_EQ(e.kind(), VideoDeviceError::Kind::kFatal);
    const std::string what = e.what();
    EXPECT_NE(what.find("/dev/fake0"), std::string::npos) << what;
    EXPECT_NE(what.find("RGB3"), std::string::npos) << what;
    EXPECT_NE(what.find("MJPG and YUYV"), std::string::npos) << what;
  }
  // auto asked MJPEG, then YUYV, then gave up without retrying.
  ASSERT_EQ(h.dev.requested.size(), 2u);
  EXPECT_EQ(h.dev.requested[1].pixelformat, kFourccYuyv);
  EXPECT_TRUE(h.sleeps.empty());
  EXPECT_EQ(h.dev.opens, 1);
}

TEST(CameraCaptureLoop, UnplugMidStreamReconnectsWithBackoffAndKeepsSeqContinuous) {
  Harness h;
  const auto jpeg = testJpeg(640, 360);
  for (uint32_t seq : {100u, 101u, 102u}) h.dev.script.push_back(frame(seq, jpeg));
  FakeDevice::Step unplug;
  unplug.kind = FakeDevice::Step::kError;
  unplug.error = ENODEV;
  h.dev.script.push_back(unplug);
  for (uint32_t seq : {0u, 1u, 3u}) h.dev.script.push_back(frame(seq, jpeg));  // after replug
  // The first open works; after the unplug it fails four times before the camera is back.
  int opens_before = 0;
  h.dev.open_failures_left = 0;
  CaptureSettings s = settings640();
  s.reconnect_initial_s = 0.5;
  s.reconnect_max_s = 3.0;
  // Arrange the failures once the stream broke: wrap the event sink's "waiting" to arm them.
  bool armed = false;
  CameraCapture cap(
      h.dev, s, [&](const CapturedFrame& f) { h.frames.push_back(f); },
      [&](const std::string& state, const std::string& msg) {
        h.events.emplace_back(state, msg);
        if (state == "waiting" && !armed) {
          armed = true;
          opens_before = h.dev.opens;
          h.dev.open_failures_left = 4;
        }
      },
      h.clock());
  cap.run([&] { return h.dev.exhausted; });
  const CaptureStats st = cap.stats();

  EXPECT_EQ(st.disconnects, 1);
  EXPECT_EQ(st.open_failures, 4);
  EXPECT_EQ(st.restarts, 1);
  EXPECT_EQ(h.dev.opens - opens_before, 5);
  // Back-off: 0.5 after the unplug, then doubling up to the 3 s cap.
  EXPECT_EQ(h.sleeps, (std::vector<double>{0.5, 1.0, 2.0, 3.0, 3.0}));
  // seq continues across the restart; the gap after the replug (2 missing) is one drop.
  ASSERT_EQ(h.frames.size(), 6u);
  std::vector<int64_t> seqs;
  for (const auto& f : h.frames) seqs.push_back(f.seq);
  EXPECT_EQ(seqs, (std::vector<int64_t>{0, 1, 2, 3, 4, 6}));
  EXPECT_EQ(st.dropped, 1);
  // The log said why it waits.
  int waiting = 0;
  for (const auto& [state, msg] : h.events) {
    if (state != "waiting") continue;
    ++waiting;
    EXPECT_NE(msg.find("/dev/fake0"), std::string::npos) << msg;
    EXPECT_NE(msg.find("retrying in"), std::string::npos) << msg;
  }
  EXPECT_EQ(waiting, 5);
  EXPECT_NE(h.events[1].second.find("unplugged"), std::string::npos) << h.events[1].second;
  EXPECT_EQ(h.dev.outstanding, 0);
  EXPECT_GE(h.dev.stops, 6);  // stopped after the unplug, after each failed open, at the end
}

TEST(CameraCaptureLoop, UnplugWithReconnectOffIsAClearError) {
  Harness h;
  h.dev.script.push_back(frame(0, testJpeg(640, 360)));
  FakeDevice::Step unplug;
  unplug.kind = FakeDevice::Step::kError;
  unplug.error = ENODEV;
  h.dev.script.push_back(unplug);
  CaptureSettings s = settings640();
  s.reconnect = false;
  try {
    h.run(s);
    FAIL() << "expected VideoDeviceError";
  } catch (const VideoDeviceError& e) {
    EXPECT_EQ(e.kind(), VideoDeviceError::Kind::kDisconnected);
    EXPECT_EQ(e.errorNumber(), ENODEV);
    EXPECT_NE(std::string(e.what()).find("unplugged"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(h.sleeps.empty());
  EXPECT_EQ(h.dev.opens, 1);
}

TEST(CameraCaptureLoop, MissingDeviceWithReconnectOffFailsAtOnce) {
  Harness h;
  h.dev.open_failures_left = 1;
  CaptureSettings s = settings640();
  s.reconnect = false;
  EXPECT_THROW(h.run(s), VideoDeviceError);
  EXPECT_EQ(h.dev.opens, 1);
  EXPECT_EQ(h.dev.starts, 0);
  EXPECT_TRUE(h.sleeps.empty());
}

TEST(CameraCaptureLoop, StalledStreamIsRestarted) {
  Harness h;
  const auto jpeg = testJpeg(640, 360);
  h.dev.script.push_back(frame(0, jpeg));
  for (int i = 0; i < 12; ++i) {  // 12 x 500 ms timeouts > the 5 s stall limit
    FakeDevice::Step t;
    t.kind = FakeDevice::Step::kTimeout;
    h.dev.script.push_back(t);
  }
  h.dev.script.push_back(frame(0, jpeg));
  const CaptureStats st = h.run(settings640());
  EXPECT_EQ(st.stalls, 1);
  EXPECT_EQ(st.disconnects, 1);
  EXPECT_EQ(st.restarts, 1);
  EXPECT_GE(st.poll_timeouts, 11);
  EXPECT_EQ(h.dev.starts, 2);
  ASSERT_EQ(h.frames.size(), 2u);
  EXPECT_EQ(h.frames[1].seq, 1);
}

TEST(CameraSettings, BadValuesAreRejectedByName) {
  CaptureSettings s;
  s.format = "h264";
  try {
    s.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("h264"), std::string::npos);
  }
  s = CaptureSettings();
  s.reconnect_max_s = 0.1;  // below the initial 0.5 s
  EXPECT_THROW(s.validate(), std::invalid_argument);
  s = CaptureSettings();
  s.buffers = 1;
  EXPECT_THROW(s.validate(), std::invalid_argument);
  EXPECT_NO_THROW(CaptureSettings().validate());
}

// --- the real device ---

TEST(V4l2Device, MissingPathAndNonCameraGiveClearErrors) {
  V4l2Device missing("/dev/video-lanemap-test-missing");
  try {
    missing.open();
    FAIL();
  } catch (const VideoDeviceError& e) {
    EXPECT_EQ(e.kind(), VideoDeviceError::Kind::kMissing);
    EXPECT_TRUE(e.retryable());
    const std::string what = e.what();
    EXPECT_NE(what.find("/dev/video-lanemap-test-missing"), std::string::npos) << what;
    EXPECT_NE(what.find("No such file"), std::string::npos) << what;
  }
  V4l2Device not_camera("/dev/null");
  try {
    not_camera.open();
    FAIL();
  } catch (const VideoDeviceError& e) {
    EXPECT_EQ(e.kind(), VideoDeviceError::Kind::kFatal);
    EXPECT_NE(std::string(e.what()).find("not a V4L2 device"), std::string::npos) << e.what();
  }
  EXPECT_EQ(classifyErrno(ENODEV, true), VideoDeviceError::Kind::kDisconnected);
  EXPECT_EQ(classifyErrno(ENODEV, false), VideoDeviceError::Kind::kMissing);
  EXPECT_EQ(classifyErrno(EBUSY, false), VideoDeviceError::Kind::kBusy);
  EXPECT_EQ(classifyErrno(EINVAL, false), VideoDeviceError::Kind::kFatal);
  EXPECT_EQ(fourccToString(kFourccMjpeg), "MJPG");
  EXPECT_EQ(+lanemap::image_t::PIXEL_FORMAT_MJPEG, static_cast<int32_t>(kFourccMjpeg));
  EXPECT_EQ(+lanemap::image_t::PIXEL_FORMAT_JPEG, static_cast<int32_t>(kFourccJpeg));
  EXPECT_EQ(+lanemap::image_t::PIXEL_FORMAT_YUYV, static_cast<int32_t>(kFourccYuyv));
}

TEST(V4l2Device, RealCameraStreamsFramesOfTheNegotiatedSize) {
  const auto devices = listVideoDevices();
  if (devices.empty()) GTEST_SKIP() << "no /dev/video* on this machine: the real-camera test is skipped";
  std::string used;
  std::vector<CapturedFrame> frames;
  CaptureStats stats;
  VideoFormat format;
  for (const auto& path : devices) {  // the first node that is a capture device (UVC has metadata nodes)
    V4l2Device dev(path);
    CaptureSettings s;
    s.width = 640;
    s.height = 480;
    s.fps = 10;
    s.reconnect = false;
    CameraCapture cap(dev, s, [&](const CapturedFrame& f) { frames.push_back(f); });
    try {
      cap.run([&] { return frames.size() >= 10; });
    } catch (const VideoDeviceError& e) {
      if (e.kind() == VideoDeviceError::Kind::kFatal) continue;
      GTEST_SKIP() << path << ": " << e.what();
    }
    used = path;
    stats = cap.stats();
    format = cap.format();
    break;
  }
  if (used.empty()) GTEST_SKIP() << "no /dev/video* is a capture device";
  ASSERT_EQ(frames.size(), 10u) << used;
  const int64_t now = lanemap::geo::wallUtime();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const cv::Mat img = cv::imdecode(frames[i].jpeg, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty()) << used << " frame " << i;
    EXPECT_EQ(img.cols, static_cast<int>(format.width));
    EXPECT_EQ(img.rows, static_cast<int>(format.height));
    EXPECT_LT(std::llabs(now - frames[i].utime), 5'000'000);
    if (i > 0) {
      EXPECT_GT(frames[i].seq, frames[i - 1].seq);
      EXPECT_GT(frames[i].utime, frames[i - 1].utime);
    }
  }
  EXPECT_EQ(stats.frames, 10);
}

// --- the driver binary ---

TEST(CameraDriver, MissingDeviceWithoutReconnectExitsWithAClearError) {
  const auto r = lanemap::testing::runCommand(lanemap::testing::binPath("lanemap-camera-v4l2") +
                                              " --lcm-url memq:// --device /dev/video-lanemap-test-missing --reconnect false");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/dev/video-lanemap-test-missing: cannot open: No such file or directory"), std::string::npos)
      << r.output;
  const auto bad = lanemap::testing::runCommand(lanemap::testing::binPath("lanemap-camera-v4l2") +
                                                " --lcm-url memq:// --device /dev/null --format h264");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("h264"), std::string::npos) << bad.output;
  const auto cfg = lanemap::testing::runCommand(lanemap::testing::binPath("lanemap-camera-v4l2") +
                                                " --lcm-url memq:// --config " + std::string(LANEMAP_SOURCE_DIR) +
                                                "/config/camera_v4l2.yaml --device /dev/null");
  EXPECT_EQ(cfg.exit_code, 2) << cfg.output;  // the shipped config loads; /dev/null is no camera
  EXPECT_NE(cfg.output.find("not a V4L2 device"), std::string::npos) << cfg.output;
}

TEST(CameraDriver, MissingDeviceWithReconnectWaitsAndReportsInStatus) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  ASSERT_TRUE(lcm.good());
  lanemap::testing::DriverMessages msgs(lcm);
  lanemap::testing::ChildProcess driver({lanemap::testing::binPath("lanemap-camera-v4l2"), "--lcm-url",
                                         lanemap::testing::testUdpmUrl(), "--device", "/dev/video-lanemap-test-missing",
                                         "--reconnect", "true"});
  ASSERT_TRUE(driver.started());
  // Attempts at 0, 0.5, 1.5 s (back-off 0.5, 1, 2 ...): three failures within ~2.5 s.
  ASSERT_TRUE(msgs.waitFor([&] { return msgs.counter("camera_v4l2", "open_failures") >= 3; }, 6s))
      << "open_failures " << msgs.counter("camera_v4l2", "open_failures");
  EXPECT_EQ(msgs.last_status["camera_v4l2"].state, "waiting for /dev/video-lanemap-test-missing");
  EXPECT_EQ(msgs.counter("camera_v4l2", "frames"), 0);
  EXPECT_EQ(driver.stop(), 0);  // SIGTERM while waiting: a clean exit
}

}  // namespace
