// Tests of the Velodyne packet decoder and the VLP-16 encoder: values derived by hand from the
// bytes of a real VLP-16 packet and the manual, properties of a real 1000-packet recording,
// encode -> decode round trips, synthetic VLP-32C / dual-return packets, and corrupted input.
#include "core/lidar/pcap.h"
#include "core/lidar/velodyne.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace lanemap::lidar {
namespace {

const std::string kDir = std::string(LANEMAP_DATA_DIR) + "/lidar/";

std::vector<uint8_t> singlePacket() {
  auto p = readRawPayloadFile(kDir + "vlp16_einride_packet.bin");
  return p.at(0);
}

uint16_t le16(const std::vector<uint8_t>& d, std::size_t at) {
  return static_cast<uint16_t>(d[at] | (d[at + 1] << 8));
}

// Count of channel records with a non-zero distance, read straight from the bytes.
int nonZeroRecords(const std::vector<uint8_t>& d) {
  int n = 0;
  for (int b = 0; b < 12; ++b)
    for (int c = 0; c < 32; ++c) n += le16(d, b * 100 + 4 + 3 * c) != 0;
  return n;
}

double wrap180(double deg) { return std::remainder(deg, 360.0); }

double rangeM(const LidarPoint& p) {
  return std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
}
double elevationDeg(const LidarPoint& p) { return std::asin(p.z / rangeM(p)) * 180.0 / M_PI; }

// ------------------------------------------------------------------------ laser tables

TEST(LaserTables, Vlp16ElevationsAndRings) {
  EXPECT_DOUBLE_EQ(vlp16ElevationDeg(0), -15.0);
  EXPECT_DOUBLE_EQ(vlp16ElevationDeg(1), 1.0);
  EXPECT_DOUBLE_EQ(vlp16ElevationDeg(15), 15.0);
  EXPECT_THROW(vlp16ElevationDeg(16), LidarError);
  EXPECT_THROW(vlp16ElevationDeg(-1), LidarError);
  // ring = rank by elevation: -15 -> 0, -1 (laser 14) -> 7, +1 (laser 1) -> 8, +15 -> 15.
  EXPECT_EQ(laserGeometry(Model::kVlp16, 0).ring, 0);
  EXPECT_EQ(laserGeometry(Model::kVlp16, 14).ring, 7);
  EXPECT_EQ(laserGeometry(Model::kVlp16, 1).ring, 8);
  EXPECT_EQ(laserGeometry(Model::kVlp16, 15).ring, 15);
  EXPECT_DOUBLE_EQ(laserGeometry(Model::kVlp16, 5).firing_offset_us, 5 * 2.304);
  EXPECT_THROW(laserGeometry(Model::kVlp32c, 32), LidarError);
}

TEST(LaserTables, RingsArePermutationsSortedByElevation) {
  for (Model m : {Model::kVlp16, Model::kVlp32c, Model::kHdl32e}) {
    const int n = laserCount(m);
    std::vector<int> laser_of_ring(n, -1);
    for (int l = 0; l < n; ++l) {
      const int r = laserGeometry(m, l).ring;
      ASSERT_GE(r, 0);
      ASSERT_LT(r, n);
      EXPECT_EQ(laser_of_ring[r], -1) << toString(m) << " ring " << r << " used twice";
      laser_of_ring[r] = l;
    }
    for (int r = 1; r < n; ++r)
      EXPECT_LT(laserGeometry(m, laser_of_ring[r - 1]).elevation_deg,
                laserGeometry(m, laser_of_ring[r]).elevation_deg);
  }
  // VLP-32C: lowest -25 deg is laser 0, highest +15 deg is laser 29 (manual table 9-1).
  EXPECT_EQ(laserGeometry(Model::kVlp32c, 0).ring, 0);
  EXPECT_EQ(laserGeometry(Model::kVlp32c, 29).ring, 31);
  EXPECT_DOUBLE_EQ(laserGeometry(Model::kVlp32c, 1).azimuth_offset_deg, -4.2);
  EXPECT_DOUBLE_EQ(laserGeometry(Model::kVlp32c, 3).firing_offset_us, 2.304);  // fires in pairs
  EXPECT_DOUBLE_EQ(laserGeometry(Model::kHdl32e, 0).elevation_deg, -30.67);
}

TEST(LaserTables, ModelNamesAndProductIds) {
  EXPECT_EQ(parseModel("vlp32c"), Model::kVlp32c);
  EXPECT_THROW(parseModel("vlp64"), LidarError);
  EXPECT_EQ(modelFromProductId(0x22), Model::kVlp16);
  EXPECT_EQ(modelFromProductId(0x28), Model::kVlp32c);
  EXPECT_EQ(modelFromProductId(0x21), Model::kHdl32e);
  EXPECT_FALSE(modelFromProductId(0x99).has_value());
}

// ------------------------------------------------------------------------ the real single packet

TEST(RealVlp16Packet, HandDerivedValues) {
  const auto bytes = singlePacket();
  std::vector<LidarPoint> pts;
  PacketInfo info;
  ASSERT_EQ(decodePacket(bytes.data(), bytes.size(), std::nullopt, pts, &info), DecodeStatus::kOk);
  EXPECT_EQ(info.model, Model::kVlp16);             // product byte 0x22
  EXPECT_EQ(info.return_mode, ReturnMode::kStrongest);  // 0x37
  EXPECT_EQ(info.usec_past_hour, 2666163099u);      // bytes 9b 6b ea 9e little endian
  // 384 records, of which 122 have distance 0 (counted by a python one-liner and below).
  EXPECT_EQ(nonZeroRecords(bytes), 262);
  ASSERT_EQ(pts.size(), 262u);
  EXPECT_EQ(info.points, 262);

  // Block 0: azimuth 10342 -> 103.42 deg; block 1 is 10382, a 0.40 deg gap. Channel 0 has
  // distance 0 (no point), so the first point is channel 1 = laser 1 (+1 deg), distance
  // 767 * 2 mm = 1.534 m, reflectivity 3, fired 2.304 us after the block start:
  // azimuth 103.42 + 0.40 * 2.304 / 110.592 = 103.428333 deg.
  // x = 1.534 cos(1) cos(103.4283) = -0.356185, y = -1.534 cos(1) sin(103.4283) = -1.491835,
  // z = 1.534 sin(1) = 0.026772. Tolerance 1e-5 m / 1e-4 deg: float storage only.
  const LidarPoint& p = pts[0];
  EXPECT_EQ(p.laser, 1);
  EXPECT_EQ(p.ring, 8);
  EXPECT_FLOAT_EQ(p.intensity, 3.0f);
  EXPECT_NEAR(p.azimuth_deg, 103.428333, 1e-4);
  EXPECT_NEAR(p.x, -0.356185, 1e-5);
  EXPECT_NEAR(p.y, -1.491835, 1e-5);
  EXPECT_NEAR(p.z, 0.026772, 1e-5);
  EXPECT_NEAR(p.time_offset_s, 2.304e-6, 1e-9);

  // Block 11 (azimuth 10781, the packet's last block, so its gap is the packet's mean gap
  // (10781 - 10342) / 11 = 0.399091 deg), channel 19 = laser 3 (+3 deg) of the SECOND sequence,
  // distance 846 * 2 mm = 1.692 m, reflectivity 72. Azimuth 107.81 + 0.399091 * (55.296 +
  // 3*2.304) / 110.592 = 108.034489 deg; time 11*110.592 + 55.296 + 3*2.304 = 1278.72 us.
  auto it = std::find_if(pts.begin(), pts.end(), [](const LidarPoint& q) {
    return std::abs(q.time_offset_s - 1278.72e-6f) < 1e-9f;
  });
  ASSERT_NE(it, pts.end());
  EXPECT_EQ(it->laser, 3);
  EXPECT_FLOAT_EQ(it->intensity, 72.0f);
  EXPECT_NEAR(it->azimuth_deg, 108.034489, 1e-4);
  EXPECT_NEAR(it->x, -0.523107, 1e-5);
  EXPECT_NEAR(it->y, -1.606668, 1e-5);
  EXPECT_NEAR(it->z, 0.088552, 1e-5);
}

TEST(RealVlp16Packet, PointsRespectElevationTable) {
  const auto bytes = singlePacket();
  std::vector<LidarPoint> pts;
  ASSERT_EQ(decodePacket(bytes.data(), bytes.size(), std::nullopt, pts), DecodeStatus::kOk);
  for (const auto& p : pts) {
    EXPECT_NEAR(elevationDeg(p), vlp16ElevationDeg(p.laser), 1e-3);  // float x,y,z -> ~1e-5 rad
    // azimuth from x, y in our frame (x forward, y left, Velodyne azimuth clockwise)
    const double az = std::atan2(-p.y, p.x) * 180.0 / M_PI;
    EXPECT_NEAR(wrap180(az - p.azimuth_deg), 0.0, 1e-3);
  }
}

// ------------------------------------------------------------------------ the real recording

struct Recording {
  std::vector<std::vector<uint8_t>> payloads;
  std::vector<std::vector<LidarPoint>> points;  // per packet
  std::vector<PacketInfo> info;
  DecodeStats stats;
};

const Recording& recording() {
  static const Recording rec = [] {
    Recording r;
    r.payloads = readRawPayloadFile(kDir + "vlp16_einride_recording.bin");
    PacketDecoder dec;
    for (const auto& p : r.payloads) {
      r.points.emplace_back();
      r.info.emplace_back();
      dec.decode(p.data(), p.size(), r.points.back(), &r.info.back());
    }
    r.stats = dec.stats();
    return r;
  }();
  return rec;
}

TEST(RealVlp16Recording, AllPacketsDecodeWithExpectedPointCounts) {
  const auto& r = recording();
  ASSERT_EQ(r.payloads.size(), 1000u);
  EXPECT_EQ(r.stats.decoded, 1000u);
  EXPECT_EQ(r.stats.rejected(), 0u);
  std::size_t total = 0;
  for (std::size_t i = 0; i < r.payloads.size(); ++i) {
    const int expected = nonZeroRecords(r.payloads[i]);
    EXPECT_EQ(static_cast<int>(r.points[i].size()), expected) << "packet " << i;
    EXPECT_LE(expected, 384);
    total += expected;
  }
  EXPECT_EQ(r.stats.points, total);
}

TEST(RealVlp16Recording, TimestampsStepOnePacketPeriod) {
  // 12 blocks x 2 sequences x 55.296 us = 1327.104 us; stamps are whole microseconds.
  const auto& r = recording();
  for (std::size_t i = 1; i < r.info.size(); ++i) {
    const int64_t dt = int64_t(r.info[i].usec_past_hour) - int64_t(r.info[i - 1].usec_past_hour);
    EXPECT_GE(dt, 1326) << "packet " << i;
    EXPECT_LE(dt, 1328) << "packet " << i;
  }
}

TEST(RealVlp16Recording, AzimuthMonotonicAboutPointTwoDegreesPerSequenceAt10Hz) {
  const auto& r = recording();
  // Block azimuths, in order: every step forward (mod 360), ~0.4 deg per block = 0.2 deg per
  // 55.296 us sequence at 10 Hz (3600 deg/s * 55.296 us = 0.199 deg).
  std::vector<double> steps;
  double prev = -1;
  int wraps = 0;
  for (const auto& p : r.payloads) {
    for (int b = 0; b < 12; ++b) {
      const double az = le16(p, b * 100 + 2) * 0.01;
      if (prev >= 0) {
        const double step = az - prev + (az < prev ? 360.0 : 0.0);
        wraps += az < prev;
        steps.push_back(step / 2.0);  // per firing sequence
      }
      prev = az;
    }
  }
  for (double s : steps) {
    EXPECT_GT(s, 0.0);
    EXPECT_LT(s, 0.3);
  }
  std::sort(steps.begin(), steps.end());
  EXPECT_NEAR(steps[steps.size() / 2], 0.2, 0.01);
  EXPECT_EQ(wraps, 13);  // 1000 x 1.327 ms = 1.33 s at ~10 Hz

  // Decoded points (interpolated per laser) are monotonic too, and each point's azimuth advances
  // from the previous point's by the rotation rate times the firing-time difference (no-return
  // records leave gaps, so consecutive points can be far apart in time). The rate is measured
  // over the recording. Tolerance: 0.01 deg azimuth quantisation of the bytes, plus 6 % of the
  // advance because the real block steps vary 0.38..0.42 deg (+-5 % around the mean 0.40), plus
  // 0.02 deg where a packet's last block (extrapolated with the packet's mean step) meets the
  // next packet's first block azimuth.
  const double t_first = r.info.front().usec_past_hour;
  const double t_last = r.info.back().usec_past_hour + 11 * 110.592;
  const double travelled = 2.0 * std::accumulate(steps.begin(), steps.end(), 0.0);
  const double rate = travelled / (t_last - t_first);  // deg per us
  EXPECT_NEAR(rate * 1e6, 3600.0, 100.0);               // ~10 Hz
  const LidarPoint* last = nullptr;
  double last_t = 0;
  for (std::size_t i = 0; i < r.points.size(); ++i)
    for (const auto& p : r.points[i]) {
      const double t = r.info[i].usec_past_hour + p.time_offset_s * 1e6;
      if (last) {
        const double d = wrap180(p.azimuth_deg - last->azimuth_deg);
        EXPECT_GE(d, -1e-3);
        EXPECT_NEAR(d, rate * (t - last_t), 0.03 + 0.06 * rate * (t - last_t));
      }
      last = &p;
      last_t = t;
    }
}

TEST(RealVlp16Recording, SweepSplitterFindsRotations) {
  const auto& r = recording();
  SweepSplitter splitter;
  int completed = 0;
  for (const auto& pts : r.points) completed += splitter.add(pts);
  EXPECT_EQ(completed, 13);
  const auto sweeps = splitter.takeSweeps();
  ASSERT_EQ(sweeps.size(), 13u);
  // Complete sweeps (all but the first, which started mid-rotation) span ~0..360 deg.
  for (std::size_t i = 1; i < sweeps.size(); ++i) {
    EXPECT_LT(sweeps[i].front().azimuth_deg, 1.0f);
    EXPECT_GT(sweeps[i].back().azimuth_deg, 359.0f);
  }
  EXPECT_TRUE(splitter.takeSweeps().empty());
}

// ------------------------------------------------------------------------ encoder round trip

TEST(Vlp16Encoder, RoundTripReproducesDistancesAzimuthsAndTimes) {
  const double rate_deg_per_us = 3600.0 * 1e-6;  // 10 Hz
  const int packets = 40;
  const int sequences = packets * kVlp16SequencesPerPacket + 5;  // 5 left pending
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> dist(0.4f, 130.0f);
  std::uniform_int_distribution<int> refl(0, 255);
  std::bernoulli_distribution no_return(0.2);

  Vlp16PacketEncoder enc;
  std::vector<FiringSequence> seqs(sequences);
  const uint32_t t0 = 3599000000u;  // near the end of the hour
  const double az0 = 357.3;         // crosses 360 -> 0 in the first packets
  for (int k = 0; k < sequences; ++k) {
    FiringSequence& s = seqs[k];
    s.azimuth_deg = std::fmod(az0 + k * kVlp16SequenceUs * rate_deg_per_us, 360.0);
    for (int l = 0; l < kVlp16Lasers; ++l) {
      s.distance_m[l] = no_return(rng) ? 0.0f : dist(rng);
      s.intensity[l] = static_cast<uint8_t>(refl(rng));
    }
    enc.add(s, t0 + static_cast<uint32_t>(std::lround(k * kVlp16SequenceUs)));
  }
  const auto pkts = enc.takePackets();
  ASSERT_EQ(static_cast<int>(pkts.size()), packets);
  EXPECT_EQ(enc.pendingSequences(), 5);
  EXPECT_TRUE(enc.takePackets().empty());

  PacketDecoder dec;
  std::size_t checked = 0;
  double max_distance_err = 0, max_azimuth_err = 0;
  for (int i = 0; i < packets; ++i) {
    std::vector<LidarPoint> pts;
    PacketInfo info;
    ASSERT_EQ(dec.decode(pkts[i], pts, &info), DecodeStatus::kOk);
    EXPECT_EQ(pkts[i][1204], 0x37);
    EXPECT_EQ(pkts[i][1205], 0x22);
    EXPECT_EQ(info.usec_past_hour, t0 + std::lround(i * 24 * kVlp16SequenceUs));
    int expected_points = 0;
    for (int s = 0; s < 24; ++s)
      for (int l = 0; l < 16; ++l) expected_points += seqs[i * 24 + s].distance_m[l] > 0;
    ASSERT_EQ(static_cast<int>(pts.size()), expected_points);
    for (const auto& p : pts) {
      // which sequence of the packet fired this point: from its time offset
      const double t_us = p.time_offset_s * 1e6 - p.laser * kVlp16FiringUs;
      const int s = static_cast<int>(std::lround(t_us / kVlp16SequenceUs));
      ASSERT_GE(s, 0);
      ASSERT_LT(s, 24);
      const FiringSequence& in = seqs[i * 24 + s];
      const double r = rangeM(p);
      // 2 mm quantisation rounds to within 1 mm; 2 mm leaves room for float x,y,z at 130 m.
      EXPECT_NEAR(r, in.distance_m[p.laser], 0.002);
      max_distance_err = std::max(max_distance_err, std::abs(r - in.distance_m[p.laser]));
      EXPECT_EQ(p.intensity, in.intensity[p.laser]);
      // 0.01 deg: block azimuths are rounded to 0.005 deg, the second sequence's interpolated
      // midpoint is exact for a steady rotation, float storage adds ~1e-5 deg.
      const double expected_az = in.azimuth_deg + rate_deg_per_us * p.laser * kVlp16FiringUs;
      EXPECT_NEAR(wrap180(p.azimuth_deg - expected_az), 0.0, 0.01);
      max_azimuth_err = std::max(max_azimuth_err, std::abs(wrap180(p.azimuth_deg - expected_az)));
      ++checked;
    }
  }
  EXPECT_GT(checked, 40u * 24 * 16 * 7 / 10);
  std::printf("round trip: %zu points, max distance error %.5f m, max azimuth error %.5f deg\n",
              checked, max_distance_err, max_azimuth_err);
}

TEST(Vlp16Encoder, ClampsAndDropsBadDistances) {
  Vlp16PacketEncoder enc(0x21);
  FiringSequence s;
  s.azimuth_deg = -0.004;  // wraps to 359.996 -> rounds to 0.00
  s.distance_m[0] = std::nanf("");
  s.distance_m[1] = -3.0f;
  s.distance_m[2] = 500.0f;  // beyond 65535 * 2 mm
  s.distance_m[3] = 0.0005f; // rounds to 0 ticks but is a return: kept as 1 tick
  s.intensity.fill(9);
  for (int k = 0; k < 24; ++k) enc.add(s, 7);
  const auto pkts = enc.takePackets();
  ASSERT_EQ(pkts.size(), 1u);
  const Packet& p = pkts[0];
  EXPECT_EQ(p[1205], 0x21);
  EXPECT_EQ(p[2] | (p[3] << 8), 0);           // azimuth 0
  EXPECT_EQ(p[4] | (p[5] << 8), 0);           // NaN -> no return
  EXPECT_EQ(p[6], 0);                         // no return carries no intensity
  EXPECT_EQ(p[7] | (p[8] << 8), 0);           // negative -> no return
  EXPECT_EQ(p[10] | (p[11] << 8), 65535);     // clamped
  EXPECT_EQ(p[13] | (p[14] << 8), 1);
  std::vector<LidarPoint> pts;
  ASSERT_EQ(decodePacket(p.data(), p.size(), Model::kVlp16, pts), DecodeStatus::kOk);
  EXPECT_EQ(pts.size(), 24u * 2);
}

// ------------------------------------------------------------------------ synthetic packets

Packet syntheticPacket(uint8_t mode, uint8_t product, const std::vector<uint16_t>& azimuths,
                       uint16_t distance_ticks) {
  Packet p{};
  for (int b = 0; b < 12; ++b) {
    uint8_t* blk = &p[b * 100];
    blk[0] = 0xFF;
    blk[1] = 0xEE;
    blk[2] = azimuths[b] & 0xFF;
    blk[3] = azimuths[b] >> 8;
    for (int c = 0; c < 32; ++c) {
      blk[4 + 3 * c] = distance_ticks & 0xFF;
      blk[5 + 3 * c] = distance_ticks >> 8;
      blk[6 + 3 * c] = static_cast<uint8_t>(b * 10 + c);
    }
  }
  p[1200] = 0x10;  // timestamp 0x10
  p[1204] = mode;
  p[1205] = product;
  return p;
}

TEST(SyntheticPackets, Vlp32cGeometryResolutionAndTiming) {
  std::vector<uint16_t> az(12);
  for (int b = 0; b < 12; ++b) az[b] = static_cast<uint16_t>(10000 + 20 * b);  // 0.2 deg/block
  const Packet pk = syntheticPacket(0x37, 0x28, az, 2500);
  std::vector<LidarPoint> pts;
  PacketInfo info;
  ASSERT_EQ(decodePacket(pk.data(), pk.size(), std::nullopt, pts, &info), DecodeStatus::kOk);
  EXPECT_EQ(info.model, Model::kVlp32c);
  ASSERT_EQ(pts.size(), 384u);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& p = pts[i];
    const int b = static_cast<int>(i / 32), c = static_cast<int>(i % 32);
    EXPECT_EQ(p.laser, c);
    EXPECT_NEAR(rangeM(p), 2500 * 0.004, 1e-5);  // VLP-32C distances are 4 mm units
    const double elev = elevationDeg(p);
    EXPECT_GE(elev, -25.0 - 1e-3);
    EXPECT_LE(elev, 15.0 + 1e-3);
    EXPECT_NEAR(elev, laserGeometry(Model::kVlp32c, c).elevation_deg, 1e-3);
    // lasers fire in pairs every 2.304 us; a block (one sequence) lasts 55.296 us
    const double t = b * 55.296 + (c / 2) * 2.304;
    EXPECT_NEAR(p.time_offset_s * 1e6, t, 1e-3);
    // azimuth = block azimuth + 0.2 deg * t_in_block / 55.296 + per-laser offset (+-1.4/4.2)
    const double expect = 100.0 + 0.2 * b + 0.2 * ((c / 2) * 2.304) / 55.296 +
                          laserGeometry(Model::kVlp32c, c).azimuth_offset_deg;
    EXPECT_NEAR(p.azimuth_deg, expect, 1e-4);
  }
  EXPECT_NEAR(pts[1].azimuth_deg, 100.0 - 4.2, 1e-4);  // laser 1: offset -4.2, fires at t = 0
}

TEST(SyntheticPackets, Vlp16DualReturnPairsBlocks) {
  std::vector<uint16_t> az(12);
  for (int b = 0; b < 12; ++b) az[b] = static_cast<uint16_t>(35960 + 40 * (b / 2)) % 36000;
  const Packet pk = syntheticPacket(0x39, 0x22, az, 1000);
  std::vector<LidarPoint> pts;
  PacketInfo info;
  ASSERT_EQ(decodePacket(pk.data(), pk.size(), std::nullopt, pts, &info), DecodeStatus::kOk);
  EXPECT_EQ(info.return_mode, ReturnMode::kDual);
  ASSERT_EQ(pts.size(), 384u);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const int b = static_cast<int>(i / 32), c = static_cast<int>(i % 32);
    const auto& p = pts[i];
    EXPECT_EQ(p.return_index, b % 2);            // last, then strongest
    const double t = (b / 2) * 110.592 + (c / 16) * 55.296 + (c % 16) * 2.304;
    EXPECT_NEAR(p.time_offset_s * 1e6, t, 1e-3);  // both returns share firing times
    // pair k starts at 359.60 + 0.40 k (wrapping past 0); interpolated across the pair period
    const double expect = 359.6 + 0.4 * (b / 2) + 0.4 * (t - (b / 2) * 110.592) / 110.592;
    EXPECT_NEAR(wrap180(p.azimuth_deg - expect), 0.0, 1e-4);
    EXPECT_GE(p.azimuth_deg, 0.0f);
    EXPECT_LT(p.azimuth_deg, 360.0f);
  }
}

// ------------------------------------------------------------------------ corrupted input

TEST(CorruptedPackets, AreCountedByReasonNotCrashedOn) {
  const auto good = singlePacket();
  PacketDecoder dec;
  std::vector<LidarPoint> pts;

  EXPECT_EQ(dec.decode(good.data(), 1205, pts), DecodeStatus::kShort);
  EXPECT_EQ(dec.decode(good.data(), 0, pts), DecodeStatus::kShort);
  EXPECT_EQ(dec.decode(nullptr, 1206, pts), DecodeStatus::kShort);
  std::vector<uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_EQ(dec.decode(longer.data(), longer.size(), pts), DecodeStatus::kOversize);

  auto bad_flag = good;
  bad_flag[5 * 100 + 1] = 0xDD;  // block 5 flag 0xFFDD
  EXPECT_EQ(dec.decode(bad_flag.data(), bad_flag.size(), pts), DecodeStatus::kBadFlag);

  auto bad_az = good;
  bad_az[7 * 100 + 2] = 0xA0;  // 0x8CA0 = 36000
  bad_az[7 * 100 + 3] = 0x8C;
  EXPECT_EQ(dec.decode(bad_az.data(), bad_az.size(), pts), DecodeStatus::kBadAzimuth);

  auto bad_mode = good;
  bad_mode[1204] = 0x40;
  EXPECT_EQ(dec.decode(bad_mode.data(), bad_mode.size(), pts), DecodeStatus::kUnknownReturnMode);

  auto bad_product = good;
  bad_product[1205] = 0x99;
  EXPECT_EQ(dec.decode(bad_product.data(), bad_product.size(), pts), DecodeStatus::kUnknownModel);
  EXPECT_TRUE(pts.empty());  // nothing appended by rejected packets

  // forcing the model accepts an unknown product id
  PacketDecoder forced(Model::kVlp16);
  EXPECT_EQ(forced.decode(bad_product.data(), bad_product.size(), pts), DecodeStatus::kOk);
  EXPECT_EQ(pts.size(), 262u);

  const DecodeStats& s = dec.stats();
  EXPECT_EQ(s.packets, 8u);
  EXPECT_EQ(s.short_packets, 3u);
  EXPECT_EQ(s.oversize, 1u);
  EXPECT_EQ(s.bad_flag, 1u);
  EXPECT_EQ(s.bad_azimuth, 1u);
  EXPECT_EQ(s.unknown_return_mode, 1u);
  EXPECT_EQ(s.unknown_model, 1u);
  EXPECT_EQ(s.rejected(), 8u);
  EXPECT_EQ(s.decoded, 0u);
}

TEST(CorruptedPackets, RandomGarbageNeverCrashes) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  PacketDecoder dec;
  std::vector<LidarPoint> pts;
  const auto good = singlePacket();
  for (int i = 0; i < 2000; ++i) {
    std::vector<uint8_t> buf = good;
    // flip 1..20 random bytes (sometimes the headers), or truncate
    const int flips = 1 + i % 20;
    for (int f = 0; f < flips; ++f) buf[rng() % buf.size()] = static_cast<uint8_t>(byte(rng));
    if (i % 5 == 0) buf.resize(rng() % buf.size());
    pts.clear();
    const DecodeStatus st = dec.decode(buf.data(), buf.size(), pts);
    for (const auto& p : pts) {
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      ASSERT_LE(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 131.1f);  // 65535 * 2 mm
      ASSERT_GE(p.azimuth_deg, 0.0f);
      ASSERT_LT(p.azimuth_deg, 360.0f);
    }
    if (st != DecodeStatus::kOk) {
      ASSERT_TRUE(pts.empty());
    }
  }
  EXPECT_EQ(dec.stats().packets, 2000u);
  EXPECT_EQ(dec.stats().decoded + dec.stats().rejected(), 2000u);
  EXPECT_EQ(dec.stats().short_packets, 400u);  // every 5th was truncated
  EXPECT_GT(dec.stats().decoded, 0u);
}

}  // namespace
}  // namespace lanemap::lidar
