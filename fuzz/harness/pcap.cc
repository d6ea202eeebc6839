// pcap files (core/lidar/pcap): PcapReader over the whole file (either byte order, us/ns, VLAN,
// truncated records), readPcapUdp, and the raw payload reader; every UDP payload found is decoded
// as a Velodyne packet, as lanemap-lidar-decode and the LIDAR driver's replay do. Input: a file.
// Properties: errors are PcapError only; payloads are no larger than the frame they came from; the
// counts add up.
#include "core/lidar/pcap.h"
#include "core/lidar/velodyne.h"
#include "fuzz/fuzz_util.h"

using namespace lanemap::lidar;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = lanemap::fuzz::scratchFile(data, size, "pcap", ".pcap");
  PacketDecoder decoder;
  std::vector<LidarPoint> points;
  if (looksLikePcap(path)) {
    try {
      PcapReader reader(path);
      UdpPayload p;
      size_t n = 0;
      while (reader.next(p)) {
        ++n;
        FUZZ_CHECK(p.data.size() <= size);
        decoder.decode(p.data.data(), p.data.size(), points);
        points.clear();
      }
      const PcapStats& s = reader.stats();
      FUZZ_CHECK(s.udp == n);
      FUZZ_CHECK(s.udp + s.not_ipv4_udp + s.fragments + s.truncated <= s.frames);
    } catch (const PcapError&) {
    }
  }
  try {
    const auto payloads = readRawPayloadFile(path, kDataPacketSize);
    FUZZ_CHECK(payloads.size() * kDataPacketSize == size);
    for (const auto& p : payloads) decoder.decode(p.data(), p.size(), points);
  } catch (const PcapError&) {
  }
  return 0;
}
