// core/lidar/udp_receiver.h inside a private network namespace: datagrams arrive whole with a
// kernel receive time, oversize ones are flagged with their real size, a taken port or a bad
// address gives an error naming it.
#include "core/lidar/udp_receiver.h"
#include "tests/common/netns.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>

namespace {

using lanemap::lidar::Datagram;
using lanemap::lidar::UdpError;
using lanemap::lidar::UdpReceiver;

int64_t nowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void sendTo(uint16_t port, const std::vector<uint8_t>& data) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(
      sendto(fd, data.data(), data.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to)),
      static_cast<ssize_t>(data.size()));
  close(fd);
}

TEST(UdpReceiver, ReceivesWholeDatagramsWithTimestampsAndFlagsOversize) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  UdpReceiver rx("127.0.0.1", 0, 1 << 20, 2048);  // port 0: any free one
  ASSERT_GT(rx.port(), 0);
  EXPECT_EQ(rx.describe(), "udp://127.0.0.1:" + std::to_string(rx.port()));
  Datagram d;
  EXPECT_FALSE(rx.receive(d));  // nothing queued: returns at once

  std::vector<uint8_t> packet(1206);
  for (std::size_t i = 0; i < packet.size(); ++i) packet[i] = static_cast<uint8_t>(i * 31);
  const int64_t before = nowUs();
  sendTo(rx.port(), packet);
  sendTo(rx.port(), std::vector<uint8_t>(3000, 7));
  std::vector<UdpReceiver*> both{&rx};
  ASSERT_EQ(lanemap::lidar::waitReadable(both, 2000), std::vector<std::size_t>{0});

  ASSERT_TRUE(rx.receive(d));
  EXPECT_EQ(d.data, packet);
  EXPECT_EQ(d.size, 1206u);
  EXPECT_FALSE(d.truncated);
  EXPECT_EQ(d.src_ip, 0x7F000001u);
  // Kernel receive time: after the send started, and not in the future (1 s slack for a busy CI).
  EXPECT_GE(d.receive_utime, before - 1000);
  EXPECT_LE(d.receive_utime, nowUs());
  EXPECT_LT(d.receive_utime - before, 1000000);

  ASSERT_TRUE(rx.receive(d));
  EXPECT_TRUE(d.truncated);
  EXPECT_EQ(d.size, 3000u);         // the real length ...
  EXPECT_EQ(d.data.size(), 2048u);  // ... of which the buffer holds the first 2048 bytes
  EXPECT_FALSE(rx.receive(d));
}

TEST(UdpReceiver, PortInUseAndBadAddressThrowClearErrors) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  UdpReceiver first("127.0.0.1", 0);
  try {
    UdpReceiver second("127.0.0.1", first.port());
    FAIL() << "bound a port that is in use";
  } catch (const UdpError& e) {
    EXPECT_NE(
        std::string(e.what()).find("cannot bind UDP 127.0.0.1:" + std::to_string(first.port())),
        std::string::npos)
        << e.what();
  }
  try {
    UdpReceiver bad("300.1.2.3", 2368);
    FAIL() << "accepted an invalid address";
  } catch (const UdpError& e) {
    EXPECT_NE(std::string(e.what()).find("invalid IPv4 address '300.1.2.3'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
