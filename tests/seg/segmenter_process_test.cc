// lanemap-segmenter over LCM, inside a private network namespace (tests/common/netns.h): frames
// in, SEMANTIC_FRONT out with the source frame's utime/seq, the same labels as the in-process
// Segmenter; corrupt and wrong-size frames counted and skipped while it keeps running; a burst
// against a slow model drops the OLDEST frames (counted, the queue stays at its bound, the newest
// frame is always segmented); --oracle republishes the truth; a missing / non-ONNX model exits 2.
#include "core/seg/segmenter.h"
#include "core/seg/sim_frames.h"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <fstream>
#include <thread>

using namespace lanemap;
using lanemap::testing::ChildProcess;
using lanemap::testing::DriverMessages;

namespace {

const std::string kRoot = LANEMAP_SOURCE_DIR;
const std::string kBinary = std::string(LANEMAP_BIN_DIR) + "/lanemap-segmenter";

std::vector<seg::SimFrame> frames(int n) {
  seg::SimFrameOptions o;
  o.osm_path = kRoot + "/data/osm/west-oakland.osm";
  o.vehicle_yaml = kRoot + "/config/vehicle.yaml";
  o.seed = 4244;
  o.max_frames = n;
  o.frame_spacing_s = 3.0;
  std::vector<seg::SimFrame> out;
  seg::renderSimFrames(o, [&](const seg::SimFrame& f) {
    out.push_back(f);
    return true;
  });
  return out;
}

image_t jpegMessage(const std::vector<uint8_t>& jpeg, int w, int h, int64_t seq) {
  image_t m;
  m.utime = 1767225600000000 + seq * 100000;
  m.seq = seq;
  m.width = w;
  m.height = h;
  m.row_stride = 0;
  m.pixelformat = image_t::PIXEL_FORMAT_JPEG;
  m.data = jpeg;
  m.size = static_cast<int32_t>(jpeg.size());
  return m;
}

struct Labels {
  std::vector<label_image_t> msgs;
  void on(const lcm::ReceiveBuffer*, const std::string&, const label_image_t* m) { msgs.push_back(*m); }
};

// A config like config/segmenter.yaml with some keys changed.
std::string writeConfig(const lanemap::testing::TempDir& dir, const std::string& extra) {
  YAML::Node c = YAML::Load(lanemap::testing::readFile(kRoot + "/config/segmenter.yaml"));
  const YAML::Node e = YAML::Load(extra);
  for (const auto& kv : e) c[kv.first.as<std::string>()] = kv.second;
  std::ofstream out(dir.str("segmenter.yaml"));
  out << c;
  return dir.str("segmenter.yaml");
}

}  // namespace

TEST(SegmenterProcess, SegmentsFramesAndSkipsBadOnes) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const auto fs = frames(3);
  ASSERT_EQ(fs.size(), 3u);
  const std::string url = lanemap::testing::testUdpmUrl(7691);
  ChildProcess proc({kBinary, "--config", kRoot + "/config/segmenter.yaml", "--lcm-url", url});
  ASSERT_TRUE(proc.started());
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  DriverMessages bus(lcm);
  Labels labels;
  lcm.subscribe("SEMANTIC_FRONT", &Labels::on, &labels)->setQueueCapacity(100);
  ASSERT_TRUE(bus.waitFor([&] { return bus.counter("segmenter", "frames_received") == 0; }, std::chrono::seconds(20)))
      << "no STATUS from the segmenter";

  // A corrupt JPEG and a wrong-size frame (a valid 320x180 JPEG): counted, skipped, still running.
  std::vector<uint8_t> corrupt = fs[0].jpeg;
  corrupt.resize(corrupt.size() / 3);
  for (size_t i = 20; i < corrupt.size(); i += 7) corrupt[i] ^= 0xff;
  const image_t corrupt_msg = jpegMessage(corrupt, 640, 360, 100);
  lcm.publish("CAMERA_FRONT", &corrupt_msg);
  cv::Mat small;
  cv::resize(fs[0].bgr, small, cv::Size(320, 180));
  std::vector<uint8_t> small_jpeg;
  cv::imencode(".jpg", small, small_jpeg);
  ASSERT_TRUE(bus.waitFor([&] { return bus.counter("segmenter", "frames_corrupt") == 1; }, std::chrono::seconds(10)));
  const image_t small_msg = jpegMessage(small_jpeg, 320, 180, 101);
  lcm.publish("CAMERA_FRONT", &small_msg);
  ASSERT_TRUE(bus.waitFor([&] { return bus.counter("segmenter", "frames_wrong_size") == 1; }, std::chrono::seconds(10)));

  // Good frames, one at a time (no drops): labels with the frame's utime/seq, as in-process.
  seg::Segmenter local(seg::ModelConfig::fromYaml(YAML::LoadFile(kRoot + "/config/segmenter.yaml")["model"], kRoot));
  for (size_t i = 0; i < fs.size(); ++i) {
    const image_t msg = jpegMessage(fs[i].jpeg, 640, 360, static_cast<int64_t>(i));
    lcm.publish("CAMERA_FRONT", &msg);
    ASSERT_TRUE(bus.waitFor([&] { return labels.msgs.size() == i + 1; }, std::chrono::seconds(20))) << "frame " << i;
    const label_image_t& out = labels.msgs.back();
    EXPECT_EQ(out.utime, msg.utime);
    EXPECT_EQ(out.seq, msg.seq);
    EXPECT_EQ(out.source, "lanesegnet-v3");
    EXPECT_EQ(+out.encoding, +label_image_t::ENCODING_PNG);
    const cv::Mat got = seg::decodeLabels(out.encoding, out.width, out.height, out.data);
    const cv::Mat want = local.segment(fs[i].bgr);
    EXPECT_EQ(cv::countNonZero(got != want), 0) << "frame " << i;
    // And they are labels, not noise: most pixels agree with the truth.
    EXPECT_GT(cv::countNonZero(got == fs[i].labels), 0.85 * got.total()) << "frame " << i;
  }
  ASSERT_TRUE(bus.waitFor([&] { return bus.counter("segmenter", "labels_published") == 3; }, std::chrono::seconds(5)));
  EXPECT_EQ(bus.counter("segmenter", "frames_received"), 5);
  EXPECT_EQ(bus.counter("segmenter", "frames_segmented"), 3);
  EXPECT_EQ(bus.counter("segmenter", "frames_corrupt"), 1);
  EXPECT_EQ(bus.counter("segmenter", "frames_wrong_size"), 1);
  EXPECT_EQ(bus.counter("segmenter", "frames_dropped"), 0);
  EXPECT_EQ(proc.stop(), 0);
}

TEST(SegmenterProcess, DropsTheOldestFramesUnderLoad) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const auto fs = frames(1);
  ASSERT_EQ(fs.size(), 1u);
  lanemap::testing::TempDir dir("segmenter-drop");
  // A slow model: 400 ms more per frame; one frame may wait.
  const std::string config = writeConfig(dir, "{debug_delay_ms: 400, queue_frames: 1, encoding: raw}");
  const std::string url = lanemap::testing::testUdpmUrl(7692);
  ChildProcess proc({kBinary, "--config", config, "--lcm-url", url});
  ASSERT_TRUE(proc.started());
  lcm::LCM lcm(url);
  DriverMessages bus(lcm);
  Labels labels;
  lcm.subscribe("SEMANTIC_FRONT", &Labels::on, &labels)->setQueueCapacity(100);
  ASSERT_TRUE(bus.waitFor([&] { return bus.counter("segmenter", "frames_received") == 0; }, std::chrono::seconds(20)));

  const int kBurst = 20;  // 20 frames in 0.4 s: 50 Hz against a model of ~2.5 Hz
  for (int i = 0; i < kBurst; ++i) {
    const image_t msg = jpegMessage(fs[0].jpeg, 640, 360, i);
    lcm.publish("CAMERA_FRONT", &msg);
    lcm.handleTimeout(20);
  }
  ASSERT_TRUE(bus.waitFor(
      [&] {
        const int64_t d = bus.counter("segmenter", "frames_dropped"), p = bus.counter("segmenter", "labels_published");
        return d >= 0 && p >= 0 && d + p == kBurst && !labels.msgs.empty() && labels.msgs.back().seq == kBurst - 1;
      },
      std::chrono::seconds(30)));
  const int64_t dropped = bus.counter("segmenter", "frames_dropped");
  const int64_t published = bus.counter("segmenter", "labels_published");
  std::printf("burst of %d frames: %lld segmented, %lld dropped, queue max depth %lld\n", kBurst,
              static_cast<long long>(published), static_cast<long long>(dropped),
              static_cast<long long>(bus.counter("segmenter", "queue_max_depth")));
  EXPECT_EQ(bus.counter("segmenter", "frames_received"), kBurst);
  EXPECT_GE(dropped, kBurst / 2);
  EXPECT_LE(bus.counter("segmenter", "queue_max_depth"), 1);  // bounded
  EXPECT_EQ(static_cast<int64_t>(labels.msgs.size()), published);
  // Drop-oldest: what is segmented comes in order and the newest frame is always among it.
  for (size_t i = 1; i < labels.msgs.size(); ++i) EXPECT_GT(labels.msgs[i].seq, labels.msgs[i - 1].seq);
  EXPECT_EQ(labels.msgs.back().seq, kBurst - 1);
  EXPECT_EQ(+labels.msgs.back().encoding, +label_image_t::ENCODING_RAW);
  EXPECT_EQ(labels.msgs.back().size, 640 * 360);
  EXPECT_EQ(proc.stop(), 0);
}

TEST(SegmenterProcess, OracleRepublishesTheTruth) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const std::string url = lanemap::testing::testUdpmUrl(7693);
  ChildProcess proc({kBinary, "--config", kRoot + "/config/segmenter.yaml", "--oracle", "--model",
                     "/nonexistent.onnx", "--lcm-url", url});  // the oracle loads no model
  ASSERT_TRUE(proc.started());
  lcm::LCM lcm(url);
  DriverMessages bus(lcm);
  Labels labels;
  lcm.subscribe("SEMANTIC_FRONT", &Labels::on, &labels);
  ASSERT_TRUE(bus.waitFor([&] { return bus.counter("segmenter", "truth_received") == 0; }, std::chrono::seconds(20)));
  cv::Mat truth(36, 64, CV_8UC1);
  for (int i = 0; i < 36 * 64; ++i) truth.data[i] = static_cast<uint8_t>(i % 11);
  label_image_t t;
  t.utime = 1767225600123456;
  t.seq = 42;
  t.width = 64;
  t.height = 36;
  t.encoding = label_image_t::ENCODING_PNG;
  t.data = seg::encodeLabelsPng(truth);
  t.size = static_cast<int32_t>(t.data.size());
  t.source = "sim-truth";
  lcm.publish("SEMANTIC_FRONT_TRUTH", &t);
  ASSERT_TRUE(bus.waitFor([&] { return labels.msgs.size() == 1; }, std::chrono::seconds(10)));
  EXPECT_EQ(labels.msgs[0].utime, t.utime);
  EXPECT_EQ(labels.msgs[0].seq, 42);
  EXPECT_EQ(labels.msgs[0].source, "sim-truth");
  EXPECT_EQ(cv::countNonZero(seg::decodeLabels(1, 64, 36, labels.msgs[0].data) != truth), 0);
  EXPECT_EQ(proc.stop(), 0);
}

TEST(SegmenterProcess, BadModelExitsNonZeroWithAClearMessage) {
  lanemap::testing::TempDir dir("segmenter-model");
  {
    std::ofstream f(dir.str("garbage.onnx"));
    f << "not a model";
  }
  // The model is loaded before any LCM traffic, so memq:// keeps this off every network.
  const std::string base = kBinary + " --config " + kRoot + "/config/segmenter.yaml --lcm-url memq:// ";
  auto r = lanemap::testing::runCommand(base + "--model /nonexistent/model.onnx");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("'/nonexistent/model.onnx' does not exist"), std::string::npos) << r.output;
  r = lanemap::testing::runCommand(base + "--model " + dir.str("garbage.onnx"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is not an ONNX model"), std::string::npos) << r.output;
}
