// lanemap-pose-nmea end to end, inside a private network namespace: NMEA from a file, a serial
// device (a pseudo-terminal standing in for the receiver's port) and UDP becomes POSE messages
// with the expected values; bad lines are counted by reason in STATUS; a missing device gives a
// clear error.
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"
#include "tests/common/child_process.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <sys/socket.h>

#include <cmath>
#include <ctime>
#include <fstream>

namespace {

using lanemap::testing::ChildProcess;
using lanemap::testing::DriverMessages;
using namespace std::chrono_literals;

// Independent NMEA checksum: XOR of the body, two hex digits.
std::string nmea(const std::string& body) {
  unsigned x = 0;
  for (unsigned char c : body) x ^= c;
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", x);
  return "$" + body + "*" + hex;
}

// Epoch k (k = 0, 1, 2 ...) of an RTK receiver at 10 Hz driving north at 5 m/s (9.719 kn),
// heading 0 deg, latitude growing by 0.001 arc-minute per epoch.
std::string epoch(int k) {
  char time[16], lat[16];
  std::snprintf(time, sizeof(time), "101500.%02d", 10 * k);
  std::snprintf(lat, sizeof(lat), "3748.%04d", 4500 + 10 * k);  // 37 deg 48.45xx min
  const std::string t(time), la(lat);
  return nmea("GNGGA," + t + "," + la + ",N,12218.0000,W,4,14,0.7,10.0,M,-32.0,M,1.0,0000") +
         "\r\n" + nmea("GNRMC," + t + ",A," + la + ",N,12218.0000,W,9.719222,0.0,231126,,,R") +
         "\r\n" + nmea("GNHDT,0.0,T") + "\r\n";
}

int64_t unixUtime(int y, int mo, int d, int h, int mi, double s) {
  std::tm tm{};
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  return static_cast<int64_t>(timegm(&tm)) * 1000000 + static_cast<int64_t>(std::llround(s * 1e6));
}

// The values every pose of epoch(k) must carry.
void expectEpochPose(const lanemap::pose_t& p, int k) {
  EXPECT_EQ(p.utime, unixUtime(2026, 11, 23, 10, 15, 0.1 * k)) << "epoch " << k;
  EXPECT_NEAR(p.latitude, 37.0 + (48.45 + 0.001 * k) / 60.0, 1e-12);
  EXPECT_NEAR(p.longitude, -(122.0 + 18.0 / 60.0), 1e-12);
  EXPECT_NEAR(p.altitude, 10.0 - 32.0, 1e-9);  // MSL + geoid separation
  EXPECT_EQ(static_cast<int>(p.status), static_cast<int>(lanemap::pose_t::STATUS_RTK_FIXED));
  // Heading 0 (north) -> yaw +90 deg: q = (cos 45, 0, 0, sin 45).
  EXPECT_NEAR(p.orientation[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(p.orientation[3], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(p.velocity_enu[0], 0.0, 1e-9);
  EXPECT_NEAR(p.velocity_enu[1], 5.0, 1e-5);                              // 9.719222 kn
  EXPECT_NEAR(p.position_covariance[0], std::pow(0.7 * 0.02, 2), 1e-12);  // HDOP x RTK UERE
}

std::vector<std::string> driverArgs(std::vector<std::string> extra) {
  std::vector<std::string> args{lanemap::testing::binPath("lanemap-pose-nmea"), "--lcm-url",
                                lanemap::testing::testUdpmUrl()};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

TEST(PoseNmeaDriver, FileGivesOnePosePerEpochAndCountsBadLines) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  lanemap::testing::TempDir dir("pose-nmea");
  const std::string file = dir.str("drive.nmea");
  {
    std::ofstream out(file);
    std::string bad =
        nmea("GNGGA,101500.00,3748.4500,N,12218.0000,W,4,14,0.7,10.0,M,-32.0,M,1.0,0000");
    bad.back() = bad.back() == '0' ? '1' : '0';
    out << epoch(0) << bad << "\r\n"  // wrong checksum
        << epoch(1) << "$GNGGA,101500.15,3748.45"
        << "\r\n"                                           // truncated
        << "\x07\x13garbage from a baud-rate mismatch\r\n"  // garbage
        << nmea("GPGSV,1,1,01,03,03,111,00") << "\r\n"      // valid, unused
        << epoch(2);
  }
  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  ASSERT_TRUE(lcm.good());
  DriverMessages msgs(lcm);
  ChildProcess driver(driverArgs({"--file", file}));
  ASSERT_TRUE(driver.started());
  EXPECT_EQ(driver.waitExit(10s), 0);  // file mode ends by itself
  msgs.waitFor(
      [&] {
        return msgs.poses.size() >= 3 && msgs.last_status.count("pose_nmea") &&
               msgs.last_status["pose_nmea"].state == "stopped";
      },
      5s);
  ASSERT_EQ(msgs.poses.size(), 3u);
  for (int k = 0; k < 3; ++k) expectEpochPose(msgs.poses[k], k);
  EXPECT_EQ(msgs.counter("pose_nmea", "sentences"), 9);
  EXPECT_EQ(msgs.counter("pose_nmea", "sentences_GGA"), 3);
  EXPECT_EQ(msgs.counter("pose_nmea", "rejected_bad_checksum"), 1);
  EXPECT_EQ(msgs.counter("pose_nmea", "rejected_truncated"), 1);
  EXPECT_EQ(msgs.counter("pose_nmea", "rejected_no_start"), 1);
  EXPECT_EQ(msgs.counter("pose_nmea", "rejected"), 3);
  EXPECT_EQ(msgs.counter("pose_nmea", "ignored"), 1);
  EXPECT_EQ(msgs.counter("pose_nmea", "poses_published"), 3);
}

TEST(PoseNmeaDriver, SerialDeviceThroughAPseudoTerminal) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(grantpt(master), 0);
  ASSERT_EQ(unlockpt(master), 0);
  const std::string slave = ptsname(master);

  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  DriverMessages msgs(lcm);
  ChildProcess driver(driverArgs({"--serial", slave, "--baud", "9600"}));
  ASSERT_TRUE(msgs.waitFor([&] { return msgs.last_status.count("pose_nmea") > 0; }, 10s));
  // Bytes come in arbitrary pieces, as from a UART.
  const std::string stream = epoch(0) + epoch(1) + epoch(2);
  for (std::size_t i = 0; i < stream.size(); i += 37) {
    const std::string piece = stream.substr(i, 37);
    ASSERT_EQ(write(master, piece.data(), piece.size()), static_cast<ssize_t>(piece.size()));
    std::this_thread::sleep_for(1ms);
  }
  // Epoch 0 is emitted when epoch 1 starts; 1 and 2 as soon as their HDT completes them.
  EXPECT_TRUE(msgs.waitFor([&] { return msgs.poses.size() >= 3; }, 5s));
  EXPECT_EQ(driver.stop(), 0);
  close(master);
  ASSERT_EQ(msgs.poses.size(), 3u);
  for (int k = 0; k < 3; ++k) expectEpochPose(msgs.poses[k], k);
}

TEST(PoseNmeaDriver, UdpDatagrams) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  DriverMessages msgs(lcm);
  ChildProcess driver(driverArgs({"--udp-port", "10110"}));
  ASSERT_TRUE(msgs.waitFor([&] { return msgs.last_status.count("pose_nmea") > 0; }, 10s));
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(10110);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  for (int k = 0; k < 3; ++k) {  // one datagram per epoch, as GNSS receivers send them
    const std::string d = epoch(k);
    sendto(fd, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  }
  const std::string junk = "\xff\xfe not nmea";
  sendto(fd, junk.data(), junk.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  close(fd);
  EXPECT_TRUE(msgs.waitFor(
      [&] { return msgs.poses.size() >= 3 && msgs.counter("pose_nmea", "rejected_no_start") == 1; },
      5s));
  EXPECT_EQ(driver.stop(), 0);
  ASSERT_EQ(msgs.poses.size(), 3u);
  for (int k = 0; k < 3; ++k) expectEpochPose(msgs.poses[k], k);
}

TEST(PoseNmeaDriver, RealtimeFilePacesEpochsAndShippedConfigLoads) {
  lanemap::testing::TempDir dir("pose-nmea-rt");
  const std::string file = dir.str("drive.nmea");
  {
    std::ofstream out(file);
    for (int k = 0; k < 6; ++k) out << epoch(k);  // epochs 0.0 .. 0.5 s
  }
  const std::string config = std::string(LANEMAP_DATA_DIR) + "/../config/pose_nmea.yaml";
  const auto start = std::chrono::steady_clock::now();
  const auto r = lanemap::testing::runCommand(
      "timeout 20 " + lanemap::testing::binPath("lanemap-pose-nmea") +
      " --lcm-url memq:// --config " + config + " --realtime --file " + file);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // Paced by NMEA time: at least the 0.5 s the epochs span (less 20 ms of timer slack); the
  // upper bound only guards against pacing gone wrong (e.g. by whole seconds).
  EXPECT_GE(s, 0.48);
  EXPECT_LT(s, 3.0);
}

TEST(PoseNmeaDriver, MissingDeviceAndBadArgumentsGiveClearErrors) {
  const std::string bin =
      "timeout 10 " + lanemap::testing::binPath("lanemap-pose-nmea") + " --lcm-url memq:// ";
  auto r = lanemap::testing::runCommand(bin + "--serial /dev/nonexistent-gnss");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot open serial device '/dev/nonexistent-gnss': No such file"),
            std::string::npos)
      << r.output;
  r = lanemap::testing::runCommand(bin + "--serial /dev/null --baud 12345");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("baud rate 12345 not supported"), std::string::npos) << r.output;
  r = lanemap::testing::runCommand(bin + "--serial /dev/null");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("'/dev/null' is not a serial device"), std::string::npos) << r.output;
  r = lanemap::testing::runCommand(bin + "--file /nonexistent.nmea");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot read NMEA file '/nonexistent.nmea'"), std::string::npos)
      << r.output;
}

}  // namespace
