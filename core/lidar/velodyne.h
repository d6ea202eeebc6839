// Velodyne VLP-16 / VLP-32C / HDL-32E data packets: an encoder (the simulator turns ray-cast
// firings into real 1206-byte VLP-16 packets) and a decoder (drivers and tools turn packets from a
// sensor, a pcap or a raw payload file into points).
//
// Packet layout (Velodyne VLP-16 / VLP-32C / HDL-32E user manuals, data packet format):
//   12 data blocks x 100 bytes: flag 0xFF 0xEE, azimuth uint16 LE in 0.01 deg (0..35999),
//   32 channel records of distance uint16 LE (2 mm units; 4 mm on the VLP-32C) + reflectivity uint8;
//   then a timestamp uint32 LE (microseconds past the hour, time of the packet's first firing)
//   and two factory bytes: return mode (0x37 strongest, 0x38 last, 0x39 dual) and product id
//   (0x21 HDL-32E, 0x22 VLP-16, 0x28 VLP-32C).
//
// POINT FRAME used by this module (and by everything downstream): sensor frame with
//   x forward, y left, z up (right-handed, the vehicle convention of DESIGN.md).
// Velodyne's own manual frame has y forward and x right; we convert:
//   x =  d cos(elev) cos(az),  y = -d cos(elev) sin(az),  z = d sin(elev),
// where az is the Velodyne azimuth: 0 deg straight ahead (the cable side is the back), increasing
// CLOCKWISE seen from above (the sensor spins clockwise). LidarPoint::azimuth_deg keeps that
// Velodyne convention in [0, 360) so it matches the bytes of the packet.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::lidar {

// Thrown on bad arguments (laser id out of range, unknown model name, unreadable file).
class LidarError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kDataPacketSize = 1206;
inline constexpr int kBlocksPerPacket = 12;
inline constexpr int kBlockSize = 100;
inline constexpr int kChannelsPerBlock = 32;
inline constexpr uint16_t kBlockFlag = 0xEEFF;        // bytes 0xFF 0xEE read little endian
inline constexpr int kTimestampOffset = 1200;
inline constexpr int kReturnModeOffset = 1204;
inline constexpr int kProductIdOffset = 1205;
inline constexpr uint16_t kDataPort = 2368;           // default UDP ports of the sensors
inline constexpr uint16_t kPositionPort = 8308;

inline constexpr int kVlp16Lasers = 16;
inline constexpr double kVlp16SequenceUs = 55.296;   // one firing sequence of 16 lasers
inline constexpr double kVlp16FiringUs = 2.304;      // between lasers within a sequence
inline constexpr int kVlp16SequencesPerPacket = 24;  // 12 blocks x 2 sequences (single return)

double vlp16ElevationDeg(int laser);                 // laser id 0..15 in firing order

using Packet = std::array<uint8_t, kDataPacketSize>;

struct FiringSequence {                              // one firing of all 16 lasers
  // Azimuth at which laser 0 of the sequence fires, [0, 360). Laser i fires i * kVlp16FiringUs
  // later; the decoder places it by interpolating the rotation between block azimuths, so a
  // simulator should ray-cast laser i at azimuth_deg + rate * i * kVlp16FiringUs.
  double azimuth_deg = 0.0;
  std::array<float, kVlp16Lasers> distance_m{};      // 0 = no return
  std::array<uint8_t, kVlp16Lasers> intensity{};
};

// Builds VLP-16 single (strongest) return packets: two sequences per data block, 24 per packet.
// Distances are rounded to 2 mm (clamped to 131.07 m, non-finite or <= 0 -> no return); azimuths
// to 0.01 deg. Only the azimuth of a block's first sequence is stored in the packet (as on the real
// sensor); the decoder interpolates the second one halfway to the next block.
class Vlp16PacketEncoder {                           // single (strongest) return mode
 public:
  explicit Vlp16PacketEncoder(uint8_t product_id = 0x22);
  // Adds one sequence fired at `usec_past_hour`; a packet's timestamp is that of its first sequence.
  void add(const FiringSequence& seq, uint32_t usec_past_hour);
  std::vector<Packet> takePackets();                 // the packets completed so far
  int pendingSequences() const { return filled_; }   // sequences in the unfinished packet

 private:
  uint8_t product_id_;
  Packet current_{};
  int filled_ = 0;
  std::vector<Packet> done_;
};

// ---------------------------------------------------------------------------------------------
// Decoder

enum class Model : uint8_t { kVlp16, kVlp32c, kHdl32e };
enum class ReturnMode : uint8_t { kStrongest = 0x37, kLast = 0x38, kDual = 0x39 };

const char* toString(Model model);                   // "vlp16", "vlp32c", "hdl32e"
Model parseModel(const std::string& name);           // inverse of toString; throws LidarError
std::optional<Model> modelFromProductId(uint8_t product_id);
std::optional<ReturnMode> returnModeFromByte(uint8_t byte);

// Fixed geometry of one laser (channel) of a model.
struct LaserGeometry {
  double elevation_deg = 0.0;        // vertical angle
  double azimuth_offset_deg = 0.0;   // added to the firing azimuth (VLP-32C only)
  double firing_offset_us = 0.0;     // time after the start of its firing sequence
  int ring = 0;                      // index sorted by elevation, 0 = lowest
  double cos_elevation = 1.0, sin_elevation = 0.0;  // of elevation_deg, computed once per laser
};

int laserCount(Model model);                          // 16 or 32
const LaserGeometry& laserGeometry(Model model, int laser);  // throws LidarError if out of range
double distanceResolutionM(Model model);              // 0.002, or 0.004 for the VLP-32C

struct LidarPoint {
  float x = 0, y = 0, z = 0;       // metres, sensor frame x forward, y left, z up (see top)
  float intensity = 0;             // calibrated reflectivity byte, 0..255
  uint8_t ring = 0;                // laser index sorted by elevation, 0 = lowest
  uint8_t laser = 0;               // laser id in firing order (channel within the sequence)
  float azimuth_deg = 0;           // precise firing azimuth, Velodyne convention, [0, 360)
  float time_offset_s = 0;         // firing time after the packet timestamp
  uint8_t return_index = 0;        // 0: single mode, or the last return in dual mode (first block
                                   // of a pair); 1: strongest (or 2nd strongest) in dual mode
};

enum class DecodeStatus : uint8_t {
  kOk,
  kShort,               // fewer than 1206 bytes
  kOversize,            // more than 1206 bytes (not a bare data payload)
  kBadFlag,             // a block does not start with 0xFF 0xEE
  kBadAzimuth,          // a block azimuth > 35999
  kUnknownReturnMode,   // return-mode byte not 0x37/0x38/0x39
  kUnknownModel,        // product id unknown and no model forced
};
const char* toString(DecodeStatus status);

// Header facts of one decoded packet.
struct PacketInfo {
  Model model = Model::kVlp16;
  ReturnMode return_mode = ReturnMode::kStrongest;
  uint8_t product_id = 0;
  uint32_t usec_past_hour = 0;     // timestamp of the first firing
  int points = 0;                  // points appended by this packet
};

// Decodes one data packet, APPENDING its points to `points` (zero distances give no point).
// `forced_model` overrides the product-id byte (some sensors, e.g. the sample VLP-16 pcap, report
// 0x21). On any status other than kOk nothing is appended and `info` is left unspecified.
DecodeStatus decodePacket(const uint8_t* data, std::size_t size, std::optional<Model> forced_model,
                          std::vector<LidarPoint>& points, PacketInfo* info = nullptr);

// Counts of what a stream of packets gave.
struct DecodeStats {
  std::size_t packets = 0;          // offered
  std::size_t decoded = 0;          // kOk
  std::size_t short_packets = 0;
  std::size_t oversize = 0;
  std::size_t bad_flag = 0;
  std::size_t bad_azimuth = 0;
  std::size_t unknown_return_mode = 0;
  std::size_t unknown_model = 0;
  std::size_t points = 0;
  std::size_t rejected() const {
    return short_packets + oversize + bad_flag + bad_azimuth + unknown_return_mode + unknown_model;
  }
};

// Stateful wrapper: decodes packets, keeps DecodeStats, remembers the model it settled on.
class PacketDecoder {
 public:
  explicit PacketDecoder(std::optional<Model> forced_model = std::nullopt);
  DecodeStatus decode(const uint8_t* data, std::size_t size, std::vector<LidarPoint>& points,
                      PacketInfo* info = nullptr);
  DecodeStatus decode(const Packet& packet, std::vector<LidarPoint>& points,
                      PacketInfo* info = nullptr) {
    return decode(packet.data(), packet.size(), points, info);
  }
  const DecodeStats& stats() const { return stats_; }

 private:
  std::optional<Model> forced_model_;
  DecodeStats stats_;
};

// Splits a stream of points (in firing order) into sweeps (one full rotation each): a new sweep
// starts where the azimuth wraps from near 360 back to near 0.
class SweepSplitter {
 public:
  // Appends points to the current sweep; returns how many sweeps were completed by this call.
  int add(const std::vector<LidarPoint>& points);
  std::vector<std::vector<LidarPoint>> takeSweeps();     // completed sweeps
  const std::vector<LidarPoint>& current() const { return current_; }
  std::size_t completed() const { return completed_; }   // total completed so far

 private:
  std::vector<LidarPoint> current_;
  std::vector<std::vector<LidarPoint>> done_;
  std::optional<float> last_azimuth_;
  bool armed_ = true;  // a wrap may end the current sweep (it has passed 90..270 deg)
  std::size_t completed_ = 0;
};

}  // namespace lanemap::lidar
