// lanemap-lidar-vlp16 over real packets, inside a private network namespace: the 1000 payloads of
// data/lidar/vlp16_einride_recording.bin sent over loopback UDP (with garbage datagrams mixed in)
// come out as complete sweeps on LIDAR_PACKETS, byte-identical; garbage is counted by reason in
// STATUS; a port already in use gives a clear error; --pcap replays through the same path.
#include "core/lidar/pcap.h"
#include "core/lidar/udp_receiver.h"
#include "core/lidar/velodyne.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"
#include "tests/common/child_process.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cstring>
#include <fstream>

namespace {

using lanemap::testing::ChildProcess;
using lanemap::testing::DriverMessages;
using namespace std::chrono_literals;

const std::string kRecording = "lidar/vlp16_einride_recording.bin";

// Where the azimuth wraps in the recording, worked out from the data (block azimuths of every
// packet; e.g. packet 53 holds blocks at 359.83 deg then 0.23 deg): the wrap happens inside
// packets 53, 129, 204, 279, 355, 430, 505, 581, 656, 731, 807, 882 and 957 (13 wraps, 75-76
// packets apart: 600 rpm at 754 packets/s). The driver ends a sweep with the packet holding the
// wrap. Packets 0..53 started mid-rotation (dropped as partial) and 958..999 never finish, so
// exactly 12 complete sweeps come out, covering packets 54..957.
constexpr int kFirstSweepPacket = 54;
constexpr int kLastSweepPacket = 957;
constexpr int kCompleteSweeps = 12;

struct UdpSender {
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  ~UdpSender() { close(fd); }
  void send(const void* data, std::size_t size, uint16_t port) const {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(sendto(fd, data, size, 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to)),
              static_cast<ssize_t>(size));
  }
};

std::vector<std::string> driverArgs(std::vector<std::string> extra) {
  std::vector<std::string> args{lanemap::testing::binPath("lanemap-lidar-vlp16"), "--lcm-url",
                                lanemap::testing::testUdpmUrl(), "--model", "vlp16"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

TEST(LidarVlp16Driver, LiveUdpGivesCompleteByteIdenticalSweepsAndCountsGarbage) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const auto payloads = lanemap::lidar::readRawPayloadFile(lanemap::testing::dataPath(kRecording));
  ASSERT_EQ(payloads.size(), 1000u);

  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  ASSERT_TRUE(lcm.good());
  DriverMessages msgs(lcm);
  ChildProcess driver(
      driverArgs({"--address", "127.0.0.1", "--port", "2368", "--position-port", "8308"}));
  ASSERT_TRUE(driver.started());
  // The driver binds its sockets before its first STATUS: wait for it.
  ASSERT_TRUE(msgs.waitFor([&] { return msgs.last_status.count("lidar_vlp16") > 0; }, 10s));

  UdpSender tx;
  const std::vector<uint8_t> short_garbage(100, 0xAB);
  std::vector<uint8_t> bad_flag(payloads[0]);
  bad_flag[0] = 0x00;  // first block flag 0x00 0xEE instead of 0xFF 0xEE
  const std::vector<uint8_t> oversize(1500, 0xFF);
  const std::string text = "hello, not a velodyne packet";
  const std::vector<uint8_t> position(512, 0x00);
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    tx.send(payloads[i].data(), payloads[i].size(), 2368);
    if (i == 100) tx.send(short_garbage.data(), short_garbage.size(), 2368);
    if (i == 300) tx.send(bad_flag.data(), bad_flag.size(), 2368);
    if (i == 500) tx.send(oversize.data(), oversize.size(), 2368);
    if (i == 700) tx.send(text.data(), text.size(), 2368);
    if (i % 300 == 0) tx.send(position.data(), position.size(), 8308);  // i = 0, 300, 600, 900
    // ~4 packets per ms (5x the sensor's rate) keeps the default-size socket buffer from
    // overflowing.
    if (i % 4 == 3) std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(msgs.waitFor(
      [&] {
        return msgs.packets.size() >= kCompleteSweeps &&
               msgs.counter("lidar_vlp16", "packets") == 1000;
      },
      10s))
      << "sweeps " << msgs.packets.size() << ", packets counted "
      << msgs.counter("lidar_vlp16", "packets") << ", driver socket buffer "
      << msgs.counter("lidar_vlp16", "receive_buffer_bytes") << " bytes";
  EXPECT_EQ(driver.stop(), 0);

  // Sweeps: exactly the 12 complete rotations, their packets byte-identical and in order.
  ASSERT_EQ(msgs.packets.size(), static_cast<std::size_t>(kCompleteSweeps));
  int next = kFirstSweepPacket;
  int64_t last_utime = 0;
  for (const auto& sweep : msgs.packets) {
    EXPECT_EQ(sweep.model, "VLP-16");
    EXPECT_EQ(sweep.packet_size, 1206);
    EXPECT_TRUE(sweep.num_packets == 75 || sweep.num_packets == 76) << sweep.num_packets;
    ASSERT_EQ(sweep.data.size(), static_cast<std::size_t>(sweep.num_packets));
    ASSERT_EQ(sweep.packet_utime.size(), static_cast<std::size_t>(sweep.num_packets));
    EXPECT_EQ(sweep.utime, sweep.packet_utime.front());
    for (int k = 0; k < sweep.num_packets; ++k, ++next) {
      ASSERT_LT(next, 1000);
      EXPECT_EQ(sweep.data[k], payloads[next]) << "file packet " << next;
      EXPECT_GE(sweep.packet_utime[k], last_utime);  // receive times never go back
      last_utime = sweep.packet_utime[k];
    }
  }
  EXPECT_EQ(next, kLastSweepPacket + 1);

  // STATUS: every real packet accepted, every garbage datagram rejected under its reason.
  EXPECT_EQ(msgs.counter("lidar_vlp16", "datagrams"), 1004);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "packets"), 1000);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "rejected_short"), 2);  // 100 bytes and the text
  EXPECT_EQ(msgs.counter("lidar_vlp16", "rejected_bad_flag"), 1);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "rejected_oversize"), 1);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "position_packets"), 4);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "sweeps_published"), kCompleteSweeps);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "sweeps_partial"), 1);  // the leading one
}

TEST(LidarVlp16Driver, PortInUseGivesClearError) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  lanemap::lidar::UdpReceiver squatter("127.0.0.1", 2368);
  const auto r = lanemap::testing::runCommand(
      "timeout 10 " + lanemap::testing::binPath("lanemap-lidar-vlp16") + " --lcm-url '" +
      lanemap::testing::testUdpmUrl() + "' --address 127.0.0.1 --port 2368 --position-port 0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot bind UDP 127.0.0.1:2368"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Address already in use"), std::string::npos) << r.output;
}

TEST(LidarVlp16Driver, BadConfigValuesGiveClearErrors) {
  // No sockets are opened: the driver refuses the arguments before anything else.
  const std::string bin = lanemap::testing::binPath("lanemap-lidar-vlp16");
  auto r = lanemap::testing::runCommand("timeout 10 " + bin + " --lcm-url memq:// --model vlp99");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("model 'vlp99' unknown"), std::string::npos) << r.output;
  r = lanemap::testing::runCommand("timeout 10 " + bin +
                                   " --lcm-url memq:// --pcap /nonexistent.pcap");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot read capture file '/nonexistent.pcap'"), std::string::npos)
      << r.output;
  // A file that is neither a pcap nor whole 1206-byte payloads (this test's own config).
  const std::string not_capture = std::string(LANEMAP_DATA_DIR) + "/../config/lidar_vlp16.yaml";
  r = lanemap::testing::runCommand("timeout 10 " + bin + " --lcm-url memq:// --pcap " +
                                   not_capture);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is neither a classic pcap nor raw 1206-byte payloads"),
            std::string::npos)
      << r.output;
}

TEST(LidarVlp16Driver, ShippedConfigLoadsAndUnknownKeysAreRejected) {
  // memq:// keeps everything in the process: no sockets for LCM; --pcap opens none for data.
  const std::string bin = "timeout 20 " + lanemap::testing::binPath("lanemap-lidar-vlp16") +
                          " --lcm-url memq:// --rate-scale 0 --pcap " +
                          lanemap::testing::dataPath("lidar/vlp16_sample.pcap");
  const std::string config = std::string(LANEMAP_DATA_DIR) + "/../config/lidar_vlp16.yaml";
  auto r = lanemap::testing::runCommand(bin + " --config " + config);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  lanemap::testing::TempDir dir("lidar-config");
  std::ofstream(dir.str("bad.yaml")) << "model: vlp16\ndata_prot: 2368\n";
  r = lanemap::testing::runCommand(bin + " --config " + dir.str("bad.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown key 'data_prot'"), std::string::npos) << r.output;
}

TEST(LidarVlp16Driver, ReplayPublishesTheSameSweepsAndTheirPoints) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  // Independent expectation: the core decoder + splitter over the whole file.
  const auto payloads = lanemap::lidar::readRawPayloadFile(lanemap::testing::dataPath(kRecording));
  lanemap::lidar::PacketDecoder decoder(lanemap::lidar::Model::kVlp16);
  lanemap::lidar::SweepSplitter splitter;
  for (const auto& p : payloads) {
    std::vector<lanemap::lidar::LidarPoint> pts;
    ASSERT_EQ(decoder.decode(p.data(), p.size(), pts), lanemap::lidar::DecodeStatus::kOk);
    splitter.add(pts);
  }
  const auto rotations = splitter.takeSweeps();
  ASSERT_EQ(rotations.size(),
            static_cast<std::size_t>(kCompleteSweeps + 1));  // + the leading partial

  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  ASSERT_TRUE(lcm.good());
  DriverMessages msgs(lcm);
  ChildProcess driver(driverArgs(
      {"--pcap", lanemap::testing::dataPath(kRecording), "--rate-scale", "0", "--publish-points"}));
  ASSERT_TRUE(driver.started());
  EXPECT_EQ(driver.waitExit(15s), 0);  // exits by itself at the end of the capture
  msgs.waitFor(
      [&] {
        return msgs.last_status.count("lidar_vlp16") &&
               msgs.last_status["lidar_vlp16"].state == "stopped";
      },
      5s);

  ASSERT_EQ(msgs.packets.size(), static_cast<std::size_t>(kCompleteSweeps));
  ASSERT_EQ(msgs.points.size(), static_cast<std::size_t>(kCompleteSweeps));
  int next = kFirstSweepPacket;
  for (const auto& sweep : msgs.packets) {
    for (int k = 0; k < sweep.num_packets; ++k, ++next) EXPECT_EQ(sweep.data[k], payloads[next]);
  }
  EXPECT_EQ(next, kLastSweepPacket + 1);
  for (int s = 0; s < kCompleteSweeps; ++s) {
    const auto& got = msgs.points[s];
    const auto& want = rotations[s + 1];
    ASSERT_EQ(got.num_points, static_cast<int32_t>(want.size())) << "sweep " << s;
    // Same points in the same order (float copies: exact).
    for (std::size_t i = 0; i < want.size(); i += 997) {
      EXPECT_EQ(got.x[i], want[i].x);
      EXPECT_EQ(got.y[i], want[i].y);
      EXPECT_EQ(got.z[i], want[i].z);
      EXPECT_EQ(got.ring[i], static_cast<int8_t>(want[i].ring));
    }
    // One rotation at 600 rpm lasts 0.1 s: the last firing is 0.095..0.105 s after the first.
    EXPECT_NEAR(got.time_offset.back(), 0.1, 0.005) << "sweep " << s;
    EXPECT_EQ(got.time_offset.front(), 0.0f);
  }
  EXPECT_EQ(msgs.counter("lidar_vlp16", "packets"), 1000);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "sweeps_partial"), 2);  // leading + unfinished tail
}

TEST(LidarVlp16Driver, StuckAzimuthIsDroppedNotAccumulated) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  // 3001 copies of one packet: the azimuth only ever steps back by 4 deg, never wraps. The
  // bundler must give up after kMaxPacketsPerSweep (3000) packets instead of growing forever.
  const auto payloads = lanemap::lidar::readRawPayloadFile(lanemap::testing::dataPath(kRecording));
  lanemap::testing::TempDir dir("lidar-stuck");
  {
    std::ofstream out(dir.str("stuck.bin"), std::ios::binary);
    for (int i = 0; i < 3001; ++i) {
      out.write(reinterpret_cast<const char*>(payloads[0].data()),
                static_cast<std::streamsize>(payloads[0].size()));
    }
  }
  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  DriverMessages msgs(lcm);
  ChildProcess driver(driverArgs({"--pcap", dir.str("stuck.bin"), "--rate-scale", "0"}));
  EXPECT_EQ(driver.waitExit(15s), 0);
  msgs.waitFor(
      [&] {
        return msgs.last_status.count("lidar_vlp16") &&
               msgs.last_status["lidar_vlp16"].state == "stopped";
      },
      5s);
  EXPECT_EQ(msgs.packets.size(), 0u);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "packets"), 3001);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "sweeps_overlong"), 1);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "sweeps_partial"),
            2);  // the overlong one + the 1-packet tail
}

TEST(LidarVlp16Driver, PcapReplayCountsPositionPackets) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  // Independent count of what the sample capture holds per destination port.
  const auto pcap = lanemap::testing::dataPath("lidar/vlp16_sample.pcap");
  const auto data = lanemap::lidar::readPcapUdp(pcap, 2368);
  const auto position = lanemap::lidar::readPcapUdp(pcap, 8308);
  ASSERT_GT(data.size(), 0u);

  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  DriverMessages msgs(lcm);
  ChildProcess driver(driverArgs({"--pcap", pcap, "--rate-scale", "0"}));
  EXPECT_EQ(driver.waitExit(15s), 0);
  msgs.waitFor(
      [&] {
        return msgs.last_status.count("lidar_vlp16") &&
               msgs.last_status["lidar_vlp16"].state == "stopped";
      },
      5s);
  EXPECT_EQ(msgs.counter("lidar_vlp16", "packets"), static_cast<int64_t>(data.size()));
  EXPECT_EQ(msgs.counter("lidar_vlp16", "position_packets"), static_cast<int64_t>(position.size()));
}

}  // namespace
