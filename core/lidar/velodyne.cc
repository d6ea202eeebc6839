// Velodyne packet encoder (VLP-16 single return, for the simulator) and decoder (VLP-16, VLP-32C,
// HDL-32E; single, last or dual return). Laser tables and timings are the user manuals'.
#include "core/lidar/velodyne.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

namespace lanemap::lidar {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr int kAzimuthTicksPerRev = 36000;  // 0.01 deg units
constexpr int kVlp16Resolution2mm = 2;

// --- laser tables ------------------------------------------------------------------------------

// VLP-16 manual, table 9-1: vertical angle per laser id (firing order).
constexpr double kVlp16Elevation[16] = {-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15};

// VLP-32C manual, table 9-1: vertical angle and azimuth offset per laser id (firing order).
constexpr double kVlp32cElevation[32] = {
    -25.0,  -1.0,   -1.667, -15.639, -11.31, 0.0,    -0.667, -8.843, -7.254, 0.333, -0.333,
    -6.148, -5.333, 1.333,  0.667,   -4.0,   -4.667, 1.667,  1.0,    -3.667, -3.333, 3.333,
    2.333,  -2.667, -3.0,   7.0,     4.667,  -2.333, -2.0,   15.0,   10.333, -1.333};
constexpr double kVlp32cAzimuthOffset[32] = {
    1.4, -4.2, 1.4, -1.4, 1.4, -1.4, 4.2, -1.4, 1.4, -4.2, 1.4, -1.4, 4.2, -1.4, 4.2, -1.4,
    1.4, -4.2, 1.4, -4.2, 4.2, -1.4, 1.4, -1.4, 1.4, -1.4, 1.4, -4.2, 4.2, -1.4, 1.4, -1.4};

// HDL-32E manual, appendix: vertical angle per laser id (firing order).
constexpr double kHdl32eElevation[32] = {
    -30.67, -9.33, -29.33, -8.00, -28.00, -6.67, -26.67, -5.33, -25.33, -4.00, -24.00,
    -2.67,  -22.67, -1.33, -21.33, 0.00,  -20.00, 1.33,  -18.67, 2.67,  -17.33, 4.00,
    -16.00, 5.33,  -14.67, 6.67,  -13.33, 8.00,  -12.00, 9.33,  -10.67, 10.67};

// Firing timing per model: a data block (single return) spans `block_us`; within it laser i of
// firing sequence s fires at s * sequence_us + (i / lasers_per_group) * group_us.
struct Timing {
  int sequences_per_block;  // VLP-16 packs two 16-laser sequences in a block, the 32s one
  double sequence_us;
  double group_us;          // between successive firing groups
  int lasers_per_group;     // VLP-32C fires lasers in pairs
  double blockUs() const { return sequences_per_block * sequence_us; }
};
constexpr Timing kVlp16Timing{2, kVlp16SequenceUs, kVlp16FiringUs, 1};
constexpr Timing kVlp32cTiming{1, 55.296, 2.304, 2};
constexpr Timing kHdl32eTiming{1, 46.08, 1.152, 1};

const Timing& timingOf(Model model) {
  switch (model) {
    case Model::kVlp16: return kVlp16Timing;
    case Model::kVlp32c: return kVlp32cTiming;
    case Model::kHdl32e: return kHdl32eTiming;
  }
  return kVlp16Timing;
}

std::vector<LaserGeometry> buildTable(const double* elevation, const double* azimuth_offset, int n,
                                      const Timing& timing) {
  std::vector<LaserGeometry> table(n);
  for (int i = 0; i < n; ++i) {
    table[i].elevation_deg = elevation[i];
    table[i].azimuth_offset_deg = azimuth_offset ? azimuth_offset[i] : 0.0;
    table[i].firing_offset_us = (i / timing.lasers_per_group) * timing.group_us;
    const double el = elevation[i] * kDegToRad;
    table[i].cos_elevation = std::cos(el);
    table[i].sin_elevation = std::sin(el);
  }
  // ring = rank by elevation (ties, none in these tables, by laser id)
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return elevation[a] < elevation[b]; });
  for (int r = 0; r < n; ++r) table[order[r]].ring = r;
  return table;
}

const std::vector<LaserGeometry>& tableOf(Model model) {
  static const std::vector<LaserGeometry> vlp16 =
      buildTable(kVlp16Elevation, nullptr, 16, kVlp16Timing);
  static const std::vector<LaserGeometry> vlp32c =
      buildTable(kVlp32cElevation, kVlp32cAzimuthOffset, 32, kVlp32cTiming);
  static const std::vector<LaserGeometry> hdl32e =
      buildTable(kHdl32eElevation, nullptr, 32, kHdl32eTiming);
  switch (model) {
    case Model::kVlp16: return vlp16;
    case Model::kVlp32c: return vlp32c;
    case Model::kHdl32e: return hdl32e;
  }
  return vlp16;
}

// --- byte helpers ------------------------------------------------------------------------------

uint16_t readU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t readU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
void writeU16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v & 0xFF);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void writeU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>((v >> (8 * i)) & 0xFF);
}

double wrapDeg360(double deg) {
  double w = std::fmod(deg, 360.0);
  if (w < 0) w += 360.0;
  if (w >= 360.0) w -= 360.0;  // fmod of -tiny + 360 can round to 360
  return w;
}

uint16_t azimuthTicks(double deg) {
  long ticks = std::lround(wrapDeg360(deg) * 100.0);
  return static_cast<uint16_t>(ticks % kAzimuthTicksPerRev);
}

uint16_t distanceTicks(float distance_m) {
  if (!std::isfinite(distance_m) || distance_m <= 0.0f) return 0;
  const double ticks = std::round(distance_m / (kVlp16Resolution2mm * 1e-3));
  return static_cast<uint16_t>(std::clamp(ticks, 1.0, 65535.0));
}

}  // namespace

// --- laser geometry API ------------------------------------------------------------------------

double vlp16ElevationDeg(int laser) {
  if (laser < 0 || laser >= kVlp16Lasers)
    throw LidarError("vlp16ElevationDeg: laser id " + std::to_string(laser) + " not in 0..15");
  return kVlp16Elevation[laser];
}

int laserCount(Model model) { return model == Model::kVlp16 ? 16 : 32; }

const LaserGeometry& laserGeometry(Model model, int laser) {
  const auto& table = tableOf(model);
  if (laser < 0 || laser >= static_cast<int>(table.size()))
    throw LidarError(std::string("laserGeometry: laser id ") + std::to_string(laser) +
                     " out of range for " + toString(model));
  return table[laser];
}

double distanceResolutionM(Model model) { return model == Model::kVlp32c ? 0.004 : 0.002; }

const char* toString(Model model) {
  switch (model) {
    case Model::kVlp16: return "vlp16";
    case Model::kVlp32c: return "vlp32c";
    case Model::kHdl32e: return "hdl32e";
  }
  return "?";
}

Model parseModel(const std::string& name) {
  for (Model m : {Model::kVlp16, Model::kVlp32c, Model::kHdl32e})
    if (name == toString(m)) return m;
  throw LidarError("unknown lidar model '" + name + "' (expected vlp16, vlp32c or hdl32e)");
}

std::optional<Model> modelFromProductId(uint8_t product_id) {
  switch (product_id) {
    case 0x21: return Model::kHdl32e;
    case 0x22: return Model::kVlp16;
    case 0x28: return Model::kVlp32c;
    default: return std::nullopt;
  }
}

std::optional<ReturnMode> returnModeFromByte(uint8_t byte) {
  switch (byte) {
    case 0x37: return ReturnMode::kStrongest;
    case 0x38: return ReturnMode::kLast;
    case 0x39: return ReturnMode::kDual;
    default: return std::nullopt;
  }
}

const char* toString(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kOk: return "ok";
    case DecodeStatus::kShort: return "short";
    case DecodeStatus::kOversize: return "oversize";
    case DecodeStatus::kBadFlag: return "bad block flag";
    case DecodeStatus::kBadAzimuth: return "azimuth > 35999";
    case DecodeStatus::kUnknownReturnMode: return "unknown return mode";
    case DecodeStatus::kUnknownModel: return "unknown product id";
  }
  return "?";
}

// --- encoder -----------------------------------------------------------------------------------

Vlp16PacketEncoder::Vlp16PacketEncoder(uint8_t product_id) : product_id_(product_id) {}

void Vlp16PacketEncoder::add(const FiringSequence& seq, uint32_t usec_past_hour) {
  if (filled_ == 0) {
    current_.fill(0);
    writeU32(&current_[kTimestampOffset], usec_past_hour);
    current_[kReturnModeOffset] = static_cast<uint8_t>(ReturnMode::kStrongest);
    current_[kProductIdOffset] = product_id_;
  }
  const int block = filled_ / 2;
  const int half = filled_ % 2;  // first or second firing sequence of the block
  uint8_t* b = &current_[block * kBlockSize];
  if (half == 0) {
    writeU16(b, kBlockFlag);
    writeU16(b + 2, azimuthTicks(seq.azimuth_deg));
  }
  for (int laser = 0; laser < kVlp16Lasers; ++laser) {
    uint8_t* rec = b + 4 + 3 * (half * kVlp16Lasers + laser);
    const uint16_t d = distanceTicks(seq.distance_m[laser]);
    writeU16(rec, d);
    rec[2] = d ? seq.intensity[laser] : 0;
  }
  if (++filled_ == kVlp16SequencesPerPacket) {
    done_.push_back(current_);
    filled_ = 0;
  }
}

std::vector<Packet> Vlp16PacketEncoder::takePackets() {
  std::vector<Packet> out;
  out.swap(done_);
  return out;
}

// --- decoder -----------------------------------------------------------------------------------

namespace {

struct Header {
  Model model;
  ReturnMode mode;
  uint8_t product_id;
  uint32_t usec;
  std::array<uint16_t, kBlocksPerPacket> azimuth;  // 0.01 deg
};

DecodeStatus parseHeader(const uint8_t* data, std::size_t size, std::optional<Model> forced,
                         Header& h) {
  if (size < static_cast<std::size_t>(kDataPacketSize)) return DecodeStatus::kShort;
  if (size > static_cast<std::size_t>(kDataPacketSize)) return DecodeStatus::kOversize;
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    const uint8_t* blk = data + b * kBlockSize;
    if (readU16(blk) != kBlockFlag) return DecodeStatus::kBadFlag;
    h.azimuth[b] = readU16(blk + 2);
    if (h.azimuth[b] >= kAzimuthTicksPerRev) return DecodeStatus::kBadAzimuth;
  }
  const auto mode = returnModeFromByte(data[kReturnModeOffset]);
  if (!mode) return DecodeStatus::kUnknownReturnMode;
  h.mode = *mode;
  h.product_id = data[kProductIdOffset];
  const auto model = forced ? forced : modelFromProductId(h.product_id);
  if (!model) return DecodeStatus::kUnknownModel;
  h.model = *model;
  h.usec = readU32(data + kTimestampOffset);
  return DecodeStatus::kOk;
}

// Rotation (deg, >= 0) from block azimuth a to b; a backwards step (jitter) counts as none.
double forwardGapDeg(uint16_t a, uint16_t b) {
  int ticks = (static_cast<int>(b) - static_cast<int>(a) + kAzimuthTicksPerRev) % kAzimuthTicksPerRev;
  if (ticks > kAzimuthTicksPerRev / 2) ticks = 0;
  return ticks * 0.01;
}

// Rotation over one block period starting at block b: towards the next block of the same return
// (two blocks on in dual mode). The packet's last block(s) have no next one: they use the mean gap
// over the whole packet, which averages out the 0.01-deg rounding of single block azimuths.
double blockGapDeg(const Header& h, int b, int stride) {
  if (b + stride < kBlocksPerPacket) return forwardGapDeg(h.azimuth[b], h.azimuth[b + stride]);
  const int first = b % stride;
  const int periods = (b - first) / stride;
  if (periods == 0) return 0.0;
  return forwardGapDeg(h.azimuth[first], h.azimuth[b]) / periods;
}

LidarPoint makePoint(double distance_m, double azimuth_deg, const LaserGeometry& g) {
  const double az = azimuth_deg * kDegToRad;
  const double horizontal = distance_m * g.cos_elevation;
  LidarPoint p;
  p.x = static_cast<float>(horizontal * std::cos(az));
  p.y = static_cast<float>(-horizontal * std::sin(az));
  p.z = static_cast<float>(distance_m * g.sin_elevation);
  p.azimuth_deg = static_cast<float>(azimuth_deg);
  p.ring = static_cast<uint8_t>(g.ring);
  return p;
}

void decodeBlock(const uint8_t* data, const Header& h, int b, std::vector<LidarPoint>& points) {
  const Timing& timing = timingOf(h.model);
  const auto& table = tableOf(h.model);
  const int lasers = laserCount(h.model);
  const bool dual = h.mode == ReturnMode::kDual;
  const int stride = dual ? 2 : 1;
  const double gap = blockGapDeg(h, b, stride);
  const double block_start_us = (b / stride) * timing.blockUs();
  const double resolution = distanceResolutionM(h.model);
  const uint8_t* blk = data + b * kBlockSize;
  for (int ch = 0; ch < kChannelsPerBlock; ++ch) {
    const uint8_t* rec = blk + 4 + 3 * ch;
    const uint16_t ticks = readU16(rec);
    if (ticks == 0) continue;
    const int seq = ch / lasers;
    const int laser = ch % lasers;
    const LaserGeometry& g = table[laser];
    const double t_in_block = seq * timing.sequence_us + g.firing_offset_us;
    const double azimuth = wrapDeg360(h.azimuth[b] * 0.01 + gap * t_in_block / timing.blockUs() +
                                      g.azimuth_offset_deg);
    LidarPoint p = makePoint(ticks * resolution, azimuth, g);
    p.intensity = rec[2];
    p.laser = static_cast<uint8_t>(laser);
    p.time_offset_s = static_cast<float>((block_start_us + t_in_block) * 1e-6);
    p.return_index = dual ? static_cast<uint8_t>(b % 2) : 0;
    points.push_back(p);
  }
}

}  // namespace

DecodeStatus decodePacket(const uint8_t* data, std::size_t size, std::optional<Model> forced_model,
                          std::vector<LidarPoint>& points, PacketInfo* info) {
  Header h{};
  if (data == nullptr) return DecodeStatus::kShort;
  const DecodeStatus status = parseHeader(data, size, forced_model, h);
  if (status != DecodeStatus::kOk) return status;
  const std::size_t before = points.size();
  for (int b = 0; b < kBlocksPerPacket; ++b) decodeBlock(data, h, b, points);
  if (info) {
    info->model = h.model;
    info->return_mode = h.mode;
    info->product_id = h.product_id;
    info->usec_past_hour = h.usec;
    info->points = static_cast<int>(points.size() - before);
  }
  return DecodeStatus::kOk;
}

PacketDecoder::PacketDecoder(std::optional<Model> forced_model) : forced_model_(forced_model) {}

DecodeStatus PacketDecoder::decode(const uint8_t* data, std::size_t size,
                                   std::vector<LidarPoint>& points, PacketInfo* info) {
  PacketInfo local;
  const DecodeStatus status = decodePacket(data, size, forced_model_, points, &local);
  ++stats_.packets;
  switch (status) {
    case DecodeStatus::kOk:
      ++stats_.decoded;
      stats_.points += static_cast<std::size_t>(local.points);
      if (info) *info = local;
      break;
    case DecodeStatus::kShort: ++stats_.short_packets; break;
    case DecodeStatus::kOversize: ++stats_.oversize; break;
    case DecodeStatus::kBadFlag: ++stats_.bad_flag; break;
    case DecodeStatus::kBadAzimuth: ++stats_.bad_azimuth; break;
    case DecodeStatus::kUnknownReturnMode: ++stats_.unknown_return_mode; break;
    case DecodeStatus::kUnknownModel: ++stats_.unknown_model; break;
  }
  return status;
}

// --- sweeps ------------------------------------------------------------------------------------

int SweepSplitter::add(const std::vector<LidarPoint>& points) {
  int completed = 0;
  for (const LidarPoint& p : points) {
    // Wrap: a drop of more than half a turn. Per-laser azimuth offsets (VLP-32C, +-4.2 deg) make
    // points jitter across 0; a new wrap only counts once the sweep has passed the far side.
    const bool wrapped = last_azimuth_ && p.azimuth_deg < *last_azimuth_ - 180.0f;
    if (wrapped && armed_ && !current_.empty()) {
      done_.push_back(std::move(current_));
      current_.clear();
      ++completed_;
      ++completed;
      armed_ = false;
    }
    if (p.azimuth_deg > 90.0f && p.azimuth_deg < 270.0f) armed_ = true;
    current_.push_back(p);
    last_azimuth_ = p.azimuth_deg;
  }
  return completed;
}

std::vector<std::vector<LidarPoint>> SweepSplitter::takeSweeps() {
  std::vector<std::vector<LidarPoint>> out;
  out.swap(done_);
  return out;
}

}  // namespace lanemap::lidar
