// Classic pcap and raw payload file readers (see pcap.h).
#include "core/lidar/pcap.h"

#include <array>
#include <filesystem>

namespace lanemap::lidar {
namespace {

constexpr uint32_t kMagicMicro = 0xA1B2C3D4;
constexpr uint32_t kMagicNano = 0xA1B23C4D;
constexpr uint32_t kMagicPcapng = 0x0A0D0D0A;
constexpr uint32_t kLinkEthernet = 1;
constexpr std::size_t kGlobalHeaderSize = 24;
constexpr std::size_t kRecordHeaderSize = 16;
constexpr uint32_t kMaxRecordSize = 256 * 1024;  // larger than any snaplen in practice
constexpr uint16_t kEtherIpv4 = 0x0800;
constexpr uint16_t kEtherVlan = 0x8100;
constexpr uint16_t kEtherQinQ = 0x88A8;
constexpr uint8_t kProtoUdp = 17;

uint32_t bswap32(uint32_t v) {
  return ((v & 0xFF) << 24) | ((v & 0xFF00) << 8) | ((v >> 8) & 0xFF00) | (v >> 24);
}
uint32_t readLe32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
uint16_t readBe16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }
uint32_t readBe32(const uint8_t* p) {
  return (static_cast<uint32_t>(p[0]) << 24) | (static_cast<uint32_t>(p[1]) << 16) |
         (static_cast<uint32_t>(p[2]) << 8) | static_cast<uint32_t>(p[3]);
}

}  // namespace

PcapReader::PcapReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
  if (!in_) throw PcapError("cannot open pcap file '" + path + "'");
  std::array<uint8_t, kGlobalHeaderSize> header{};
  in_.read(reinterpret_cast<char*>(header.data()), header.size());
  if (in_.gcount() < 4) throw PcapError("'" + path + "' is not a pcap file (too short)");
  const uint32_t magic = readLe32(header.data());
  if (magic == kMagicPcapng)
    throw PcapError("'" + path + "' is pcapng; only classic pcap is supported "
                    "(convert with: editcap -F pcap in.pcapng out.pcap)");
  if (magic == kMagicMicro || magic == kMagicNano) {
    swapped_ = false;
  } else if (bswap32(magic) == kMagicMicro || bswap32(magic) == kMagicNano) {
    swapped_ = true;
  } else {
    throw PcapError("'" + path + "' is not a pcap file (bad magic number)");
  }
  nanosecond_ = (swapped_ ? bswap32(magic) : magic) == kMagicNano;
  if (in_.gcount() < static_cast<std::streamsize>(kGlobalHeaderSize))
    throw PcapError("'" + path + "' is truncated inside the 24-byte pcap global header");
  link_type_ = u32(header.data() + 20) & 0x0FFFFFFF;  // upper bits may carry FCS flags
  if (link_type_ != kLinkEthernet)
    throw PcapError("'" + path + "': unsupported pcap link type " + std::to_string(link_type_) +
                    " (only Ethernet, 1)");
  offset_ = kGlobalHeaderSize;
}

uint32_t PcapReader::u32(const uint8_t* p) const {
  const uint32_t v = readLe32(p);
  return swapped_ ? bswap32(v) : v;
}

bool PcapReader::readRecord(std::vector<uint8_t>& frame, uint64_t& timestamp_ns) {
  std::array<uint8_t, kRecordHeaderSize> rh{};
  in_.read(reinterpret_cast<char*>(rh.data()), rh.size());
  const std::streamsize got = in_.gcount();
  if (got == 0) return false;  // clean end of file
  if (got < static_cast<std::streamsize>(kRecordHeaderSize))
    throw PcapError("'" + path_ + "' is truncated: record header at byte " +
                    std::to_string(offset_) + " has only " + std::to_string(got) + " of 16 bytes");
  const uint32_t sec = u32(rh.data());
  const uint32_t frac = u32(rh.data() + 4);
  const uint32_t incl = u32(rh.data() + 8);
  if (incl > kMaxRecordSize)
    throw PcapError("'" + path_ + "': record at byte " + std::to_string(offset_) +
                    " claims " + std::to_string(incl) + " bytes (corrupt file?)");
  frame.resize(incl);
  in_.read(reinterpret_cast<char*>(frame.data()), incl);
  if (in_.gcount() < static_cast<std::streamsize>(incl))
    throw PcapError("'" + path_ + "' is truncated: record at byte " + std::to_string(offset_) +
                    " needs " + std::to_string(incl) + " bytes, file has " +
                    std::to_string(in_.gcount()));
  timestamp_ns = static_cast<uint64_t>(sec) * 1000000000ull +
                 static_cast<uint64_t>(frac) * (nanosecond_ ? 1ull : 1000ull);
  offset_ += kRecordHeaderSize + incl;
  ++stats_.frames;
  return true;
}

// Ethernet (+ VLAN tags) / IPv4 / UDP; false for anything else (counted in stats_).
bool PcapReader::parseFrame(const std::vector<uint8_t>& frame, UdpPayload& out) {
  std::size_t pos = 12;
  if (frame.size() < pos + 2) { ++stats_.not_ipv4_udp; return false; }
  uint16_t ether_type = readBe16(&frame[pos]);
  while ((ether_type == kEtherVlan || ether_type == kEtherQinQ) && frame.size() >= pos + 6) {
    pos += 4;
    ether_type = readBe16(&frame[pos]);
  }
  pos += 2;
  if (ether_type != kEtherIpv4 || frame.size() < pos + 20) { ++stats_.not_ipv4_udp; return false; }
  const uint8_t* ip = &frame[pos];
  const std::size_t ihl = static_cast<std::size_t>(ip[0] & 0x0F) * 4;
  if ((ip[0] >> 4) != 4 || ihl < 20 || ip[9] != kProtoUdp) { ++stats_.not_ipv4_udp; return false; }
  const uint16_t frag = readBe16(ip + 6);
  if ((frag & 0x2000) || (frag & 0x1FFF)) { ++stats_.fragments; return false; }
  const std::size_t udp_pos = pos + ihl;
  if (frame.size() < udp_pos + 8) { ++stats_.truncated; return false; }
  const uint8_t* udp = &frame[udp_pos];
  const std::size_t udp_len = readBe16(udp + 4);
  if (udp_len < 8 || frame.size() < udp_pos + udp_len) { ++stats_.truncated; return false; }
  out.src_ip = readBe32(ip + 12);
  out.dst_ip = readBe32(ip + 16);
  out.src_port = readBe16(udp);
  out.dst_port = readBe16(udp + 2);
  out.data.assign(udp + 8, udp + udp_len);
  ++stats_.udp;
  return true;
}

bool PcapReader::next(UdpPayload& out) {
  std::vector<uint8_t> frame;
  uint64_t ts = 0;
  while (readRecord(frame, ts)) {
    if (parseFrame(frame, out)) {
      out.timestamp_ns = ts;
      return true;
    }
  }
  return false;
}

std::vector<UdpPayload> readPcapUdp(const std::string& path, uint16_t dst_port, PcapStats* stats) {
  PcapReader reader(path);
  std::vector<UdpPayload> out;
  UdpPayload p;
  while (reader.next(p))
    if (dst_port == 0 || p.dst_port == dst_port) out.push_back(std::move(p));
  if (stats) *stats = reader.stats();
  return out;
}

std::vector<std::vector<uint8_t>> readRawPayloadFile(const std::string& path,
                                                     std::size_t payload_size) {
  if (payload_size == 0) throw PcapError("readRawPayloadFile: payload size must be > 0");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw PcapError("cannot open raw payload file '" + path + "'");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw PcapError("cannot read size of '" + path + "': " + ec.message());
  if (size == 0) throw PcapError("raw payload file '" + path + "' is empty");
  if (size % payload_size != 0)
    throw PcapError("raw payload file '" + path + "' has " + std::to_string(size) +
                    " bytes, not a multiple of the " + std::to_string(payload_size) +
                    "-byte payload (truncated, or not raw payloads?)");
  std::vector<std::vector<uint8_t>> out(size / payload_size, std::vector<uint8_t>(payload_size));
  for (auto& p : out) {
    in.read(reinterpret_cast<char*>(p.data()), static_cast<std::streamsize>(payload_size));
    if (in.gcount() != static_cast<std::streamsize>(payload_size))
      throw PcapError("short read in raw payload file '" + path + "'");
  }
  return out;
}

bool looksLikePcap(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  uint8_t m[4] = {0, 0, 0, 0};
  if (!in.read(reinterpret_cast<char*>(m), 4)) return false;
  const uint32_t magic = readLe32(m);
  return magic == kMagicMicro || magic == kMagicNano || bswap32(magic) == kMagicMicro ||
         bswap32(magic) == kMagicNano;
}

}  // namespace lanemap::lidar
