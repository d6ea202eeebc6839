// Velodyne data packets (core/lidar/velodyne): decodePacket with the product-id byte and with each
// model forced, PacketDecoder's counts and SweepSplitter. Input: the payload of one UDP packet
// (the seeds are real 1206-byte VLP-16 packets). Properties: a packet either decodes to at most
// 12 x 32 finite points with azimuths in [0, 360) or is rejected with nothing appended.
#include "core/lidar/velodyne.h"
#include "fuzz/fuzz_util.h"

#include <cmath>

using namespace lanemap::lidar;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  PacketDecoder decoder;
  SweepSplitter splitter;
  const std::optional<Model> models[] = {std::nullopt, Model::kVlp16, Model::kVlp32c, Model::kHdl32e};
  for (const auto& forced : models) {
    std::vector<LidarPoint> points(3);  // decodePacket appends: what is there must stay
    PacketInfo info;
    const DecodeStatus st = decodePacket(data, size, forced, points, &info);
    if (st != DecodeStatus::kOk) {
      FUZZ_CHECK(points.size() == 3);
      continue;
    }
    FUZZ_CHECK(size == static_cast<size_t>(kDataPacketSize));
    FUZZ_CHECK(info.points >= 0 && info.points <= kBlocksPerPacket * kChannelsPerBlock);
    FUZZ_CHECK(points.size() == 3 + static_cast<size_t>(info.points));
    for (size_t i = 3; i < points.size(); ++i) {
      const LidarPoint& p = points[i];
      FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      FUZZ_CHECK(p.azimuth_deg >= 0.0f && p.azimuth_deg < 360.0f);
      FUZZ_CHECK(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) < 263.0f);  // 65535 x 4 mm
      FUZZ_CHECK(p.ring < laserCount(info.model));
    }
    std::vector<LidarPoint> more;
    decoder.decode(data, size, more);
    splitter.add(more);
  }
  const DecodeStats& s = decoder.stats();
  FUZZ_CHECK(s.decoded + s.rejected() == s.packets);
  // A packet cut by one byte is a short one, with one byte more an oversize one.
  std::vector<LidarPoint> none;
  if (size == static_cast<size_t>(kDataPacketSize)) {
    FUZZ_CHECK(decodePacket(data, size - 1, std::nullopt, none) == DecodeStatus::kShort && none.empty());
  }
  return 0;
}
