// Hostile message contents (issue 18), the fixes behind fuzz/regressions/lcm_decode:
//  - lcm-gen's decode with sizes that disagree with the data (cmake/lcm_guard.cmake): decode()
//    returns -1 instead of throwing std::length_error (which killed the process) or allocating
//    gigabytes; a valid message still decodes;
//  - a JPEG or PNG that lies about its size (core/io/image_header.h): refused from its header,
//    before cv::imdecode allocates for the size it claims;
//  - a corrupt OSM PBF: no file descriptor leaks (core/osm readOsm, around libosmium 2.18).
#include "core/bev/bev_builder.h"
#include "core/io/image_header.h"
#include "core/osm/osm_data.h"
#include "core/seg/segmenter.h"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"
#include "lanemap/status_t.hpp"
#include "tests/common/read_file.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

using namespace lanemap;

std::vector<uint8_t> be32(int32_t v) {
  const uint32_t u = static_cast<uint32_t>(v);
  return {static_cast<uint8_t>(u >> 24), static_cast<uint8_t>(u >> 16), static_cast<uint8_t>(u >> 8),
          static_cast<uint8_t>(u)};
}

template <typename T>
std::vector<uint8_t> withHash(std::vector<uint8_t> body) {
  std::vector<uint8_t> buf(8);
  int64_t hash = T::getHash();
  __int64_t_encode_array(buf.data(), 0, 8, &hash, 1);
  buf.insert(buf.end(), body.begin(), body.end());
  return buf;
}

template <typename T>
int decode(const std::vector<uint8_t>& buf) {
  T m;
  return m.decode(buf.data(), 0, static_cast<int>(buf.size()));
}

TEST(HostileLcm, ArrayCountsThatDisagreeWithTheDataFailToDecode) {
  for (int32_t n : {-1, -100000, 0x7fffffff, 1000}) {
    std::vector<uint8_t> body(8, 0);  // utime
    const auto count = be32(n);
    body.insert(body.end(), count.begin(), count.end());
    body.resize(body.size() + 40, 0);  // 40 bytes where n points would need 25 n
    EXPECT_EQ(decode<lidar_points_t>(withHash<lidar_points_t>(body)), -1) << "num_points " << n;
  }
  // A consistent message still decodes, and gives its points back.
  lidar_points_t ok{};
  ok.num_points = 2;
  ok.x = {1, 2};
  ok.y = {3, 4};
  ok.z = {5, 6};
  ok.intensity = {7, 8};
  ok.ring = {0, 1};
  ok.time_offset = {0, 0.1f};
  std::vector<uint8_t> buf(static_cast<size_t>(ok.getEncodedSize()));
  ASSERT_EQ(ok.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  lidar_points_t back;
  ASSERT_EQ(back.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_EQ(back.z, ok.z);
  // Shortened by one byte it does not.
  EXPECT_EQ(back.decode(buf.data(), 0, static_cast<int>(buf.size()) - 1), -1);
}

TEST(HostileLcm, StringLengthsOfZeroOrLessFailToDecode) {
  for (int32_t len : {0, -1, -7}) {
    std::vector<uint8_t> body(32, 0);  // utime, road_id, from_node, to_node
    const auto l = be32(len);
    body.insert(body.end(), l.begin(), l.end());
    body.resize(body.size() + 40, 0);
    EXPECT_EQ(decode<bev_road_t>(withHash<bev_road_t>(body)), -1) << "path length " << len;
  }
  // status_t: a counter name (an element of a string array) of length 0.
  std::vector<uint8_t> body(8, 0);
  for (int k = 0; k < 2; ++k) {  // process, host: ""
    const auto one = be32(1);
    body.insert(body.end(), one.begin(), one.end());
    body.push_back(0);
  }
  body.insert(body.end(), 4, 0);  // pid
  const auto one = be32(1);
  body.insert(body.end(), one.begin(), one.end());  // state ""
  body.push_back(0);
  body.insert(body.end(), one.begin(), one.end());  // num_counters = 1
  const auto zero = be32(0);
  body.insert(body.end(), zero.begin(), zero.end());  // counter_names[0] length 0
  body.resize(body.size() + 40, 0);
  EXPECT_EQ(decode<status_t>(withHash<status_t>(body)), -1);
}

TEST(HostileLcm, APacketSizeOfMinusOneFailsToDecode) {
  std::vector<uint8_t> body(8, 0);
  for (int32_t v : {1}) {
    const auto b = be32(v);
    body.insert(body.end(), b.begin(), b.end());
  }
  body.push_back(0);  // model ""
  for (int32_t v : {1, -1}) {  // num_packets, packet_size
    const auto b = be32(v);
    body.insert(body.end(), b.begin(), b.end());
  }
  body.resize(body.size() + 8 + 16, 0);  // packet_utime[0] and some bytes
  EXPECT_EQ(decode<lidar_packets_t>(withHash<lidar_packets_t>(body)), -1);
}

cv::Mat testImage() {
  cv::Mat bgr(16, 32, CV_8UC3);
  for (int r = 0; r < bgr.rows; ++r)
    for (int c = 0; c < bgr.cols; ++c) bgr.at<cv::Vec3b>(r, c) = cv::Vec3b(r * 8, c * 4, 100);
  return bgr;
}

// Sets the size in the first SOF marker of a JPEG.
void patchJpegSize(std::vector<uint8_t>& jpg, int width, int height) {
  for (size_t i = 2; i + 9 < jpg.size(); ++i) {
    if (jpg[i] == 0xFF && (jpg[i + 1] == 0xC0 || jpg[i + 1] == 0xC2)) {
      jpg[i + 5] = static_cast<uint8_t>(height >> 8);
      jpg[i + 6] = static_cast<uint8_t>(height);
      jpg[i + 7] = static_cast<uint8_t>(width >> 8);
      jpg[i + 8] = static_cast<uint8_t>(width);
      return;
    }
  }
  FAIL() << "no SOF marker";
}

TEST(HostileImages, HeadersGiveTheSizeWithoutDecoding) {
  std::vector<uint8_t> jpg, png;
  ASSERT_TRUE(cv::imencode(".jpg", testImage(), jpg));
  ASSERT_TRUE(cv::imencode(".png", testImage(), png));
  const auto j = io::jpegSize(jpg.data(), jpg.size());
  ASSERT_TRUE(j);
  EXPECT_EQ(j->width, 32);
  EXPECT_EQ(j->height, 16);
  const auto p = io::pngSize(png.data(), png.size());
  ASSERT_TRUE(p);
  EXPECT_EQ(p->width, 32);
  EXPECT_EQ(p->height, 16);
  EXPECT_FALSE(io::jpegSize(jpg.data(), 3));
  EXPECT_FALSE(io::jpegSize(png.data(), png.size()));
  EXPECT_FALSE(io::pngSize(jpg.data(), jpg.size()));
  EXPECT_FALSE(io::pngSize(png.data(), 20));
  EXPECT_FALSE(io::jpegSize(nullptr, 0));
}

TEST(HostileImages, AJpegThatLiesAboutItsSizeIsAWrongSizeFrame) {
  std::vector<uint8_t> jpg;
  ASSERT_TRUE(cv::imencode(".jpg", testImage(), jpg));
  const cv::Mat ok = seg::decodeFrame(image_t::PIXEL_FORMAT_JPEG, 32, 16, 0, jpg.data(), jpg.size());
  EXPECT_EQ(ok.cols, 32);
  // 2 kB that claim 65000 x 65000 (12 GB decoded): refused from the header, with the message the
  // segmenter counts as frames_wrong_size.
  patchJpegSize(jpg, 65000, 65000);
  try {
    seg::decodeFrame(image_t::PIXEL_FORMAT_JPEG, 32, 16, 0, jpg.data(), jpg.size());
    FAIL() << "decoded a lying JPEG";
  } catch (const seg::FrameError& e) {
    EXPECT_NE(std::string(e.what()).find("JPEG is 65000x65000 but the message says 32x16 (from its header; not decoded)"), std::string::npos)
        << e.what();
  }
  // The same lie told to the message too is refused as too large (the segmenter's 16384 limit).
  EXPECT_THROW(seg::decodeFrame(image_t::PIXEL_FORMAT_JPEG, 65000, 65000, 0, jpg.data(), jpg.size()),
               seg::FrameError);
  // Garbage that is not a JPEG at all.
  const std::vector<uint8_t> junk(100, 0xAB);
  EXPECT_THROW(seg::decodeFrame(image_t::PIXEL_FORMAT_MJPEG, 32, 16, 0, junk.data(), junk.size()), seg::FrameError);
}

TEST(HostileImages, LabelPngsThatLieAboutTheirSizeAreRefused) {
  cv::Mat labels(16, 32, CV_8UC1, cv::Scalar(3));
  std::vector<uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", labels, png));
  cv::Mat out;
  EXPECT_TRUE(bev::decodeLabelImage(bev::LabelEncoding::kPng, png.data(), png.size(), 32, 16, &out));
  EXPECT_EQ(seg::decodeLabels(1, 32, 16, png).cols, 32);
  // IHDR says 60000 x 60000 (3.6 GB).
  std::vector<uint8_t> lie = png;
  for (int k : {16, 20}) {
    lie[k] = 0;
    lie[k + 1] = 0;
    lie[k + 2] = 0xEA;
    lie[k + 3] = 0x60;
  }
  EXPECT_FALSE(bev::decodeLabelImage(bev::LabelEncoding::kPng, lie.data(), lie.size(), 32, 16, &out));
  EXPECT_THROW(seg::decodeLabels(1, 32, 16, lie), seg::FrameError);
  // Told to the message too, the size is over the 16384 limit (no decode is tried).
  EXPECT_FALSE(bev::decodeLabelImage(bev::LabelEncoding::kPng, lie.data(), lie.size(), 60000, 60000, &out));
  EXPECT_THROW(seg::decodeLabels(1, 60000, 60000, lie), seg::FrameError);
}

TEST(HostileImages, RawFramesOfAnOddShapeAreFrameErrorsOnly) {
  // YUYV with an odd width, GREY with a stride shorter than the row: FrameError or a frame of the
  // size asked for, never another exception (the segmenter's worker catches only FrameError).
  const std::vector<uint8_t> data(33 * 2 * 16, 0x80);
  for (int32_t fmt : std::vector<int32_t>{image_t::PIXEL_FORMAT_YUYV, image_t::PIXEL_FORMAT_GRAY, image_t::PIXEL_FORMAT_RGB}) {
    for (int stride : {0, 10, 66}) {
      try {
        const cv::Mat m = seg::decodeFrame(fmt, 33, 16, stride, data.data(), data.size());
        EXPECT_EQ(m.cols, 33);
        EXPECT_EQ(m.rows, 16);
      } catch (const seg::FrameError&) {
      }
    }
  }
}

}  // namespace

namespace {

size_t openDescriptors() {
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) {
    (void)e;
    ++n;
  }
  return n;
}

// libosmium 2.18 leaked the file descriptor of every corrupt PBF it failed to parse (found by
// fuzz/harness/osm_pbf.cc); readOsm closes it now. 50 corrupt files: no descriptor more.
TEST(HostileOsm, ACorruptPbfLeavesNoOpenDescriptor) {
  const std::string pbf = lanemap::testing::readFile(std::string(LANEMAP_DATA_DIR) + "/osm/monaco.osm.pbf");
  ASSERT_GT(pbf.size(), 5000u);
  const lanemap::testing::TempDir dir("hostile-pbf");
  const std::string path = dir.str("cut.osm.pbf");
  const size_t before = openDescriptors();
  for (int i = 0; i < 50; ++i) {
    std::vector<char> bad(pbf.begin(), pbf.begin() + 3000 + 37 * i);  // cut inside a blob
    if (i % 2) bad[20 + i] ^= 0x55;                                       // or a broken header
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bad.data(), static_cast<std::streamsize>(bad.size()));
    EXPECT_THROW(osm::readOsm(path), osm::OsmError) << i;
  }
  EXPECT_EQ(openDescriptors(), before);
  // A good file still reads (and leaves nothing open either).
  EXPECT_FALSE(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/monaco.osm.pbf").ways.empty());
  EXPECT_EQ(openDescriptors(), before);
}

}  // namespace
