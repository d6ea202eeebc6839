// Runs the lanemap-lidar-decode tool on the real captures: CSV rows, header and summary numbers.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>

namespace {

const std::string kDir = std::string(LANEMAP_DATA_DIR) + "/lidar/";
const std::string kTool = std::string(LANEMAP_BIN_DIR) + "/lanemap-lidar-decode";

struct ToolRun {
  int status = -1;
  std::string out;
};

ToolRun runTool(const std::string& args) {
  ToolRun r;
  FILE* pipe = popen((kTool + " " + args + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) r.out += buf.data();
  const int st = pclose(pipe);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

class LidarDecodeTool : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kTool)) GTEST_SKIP() << kTool << " not built";
  }
};

TEST_F(LidarDecodeTool, SinglePacketCsvHasOneRowPerReturn) {
  const std::string csv = ::testing::TempDir() + "lanemap_lidar_single.csv";
  const ToolRun r = runTool(kDir + "vlp16_einride_packet.bin --csv " + csv);
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("1 read, 1 decoded, 0 rejected"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("points           262"), std::string::npos) << r.out;
  std::ifstream in(csv);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "x,y,z,intensity,ring,laser,azimuth_deg,time_offset_s");
  int rows = 0;
  std::string first;
  while (std::getline(in, line)) {
    if (rows == 0) first = line;
    ++rows;
  }
  EXPECT_EQ(rows, 262);  // 384 records minus 122 zero distances
  // block 0, laser 1: see velodyne_test HandDerivedValues
  EXPECT_EQ(first, "-0.3562,-1.4918,0.0268,3,8,1,103.428,0.0000023");
  std::filesystem::remove(csv);
}

TEST_F(LidarDecodeTool, PcapSummaryCountsDataAndPositionPackets) {
  const ToolRun r = runTool(kDir + "vlp16_sample.pcap --model vlp16");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("position packets 16"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("84 read, 84 decoded, 0 rejected"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("model            vlp16 (84 packets)"), std::string::npos) << r.out;
}

TEST_F(LidarDecodeTool, RecordingCountsSweeps) {
  const ToolRun r = runTool(kDir + "vlp16_einride_recording.bin");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("sweeps           13 complete + 1 partial"), std::string::npos) << r.out;
}

TEST_F(LidarDecodeTool, BadInputFailsWithMessage) {
  const ToolRun r = runTool(kDir + "LICENSE.einride-vlp16-go");  // not 1206-byte payloads
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("not a multiple"), std::string::npos) << r.out;
  const ToolRun m = runTool(kDir + "vlp16_einride_packet.bin --model vlp64");
  EXPECT_NE(m.status, 0);
}

}  // namespace
