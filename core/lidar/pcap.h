// Readers for recorded LIDAR traffic: classic libpcap files (either byte order, micro- or
// nanosecond timestamps, Ethernet link type with optional 802.1Q tags, IPv4/UDP) giving UDP
// payloads, and raw payload files (concatenated fixed-size payloads, e.g. 1206-byte Velodyne data
// packets with no headers). pcapng is not supported (recognised and rejected with a clear error).
#pragma once

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::lidar {

// Thrown for a file that cannot be opened, is not a classic pcap, has an unsupported link type,
// or is truncated in a record. The message names the file and the byte offset.
class PcapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct UdpPayload {
  uint64_t timestamp_ns = 0;  // capture time, ns since the Unix epoch
  uint32_t src_ip = 0;        // host order, e.g. 192.168.1.201 = 0xC0A801C9
  uint32_t dst_ip = 0;
  uint16_t src_port = 0;
  uint16_t dst_port = 0;
  std::vector<uint8_t> data;
};

// What a pcap held besides the UDP payloads it returned.
struct PcapStats {
  std::size_t frames = 0;          // records read
  std::size_t udp = 0;             // IPv4/UDP payloads returned
  std::size_t not_ipv4_udp = 0;    // other EtherTypes / protocols (ARP, IPv6, TCP ...)
  std::size_t fragments = 0;       // IPv4 fragments (skipped: Velodyne packets are never fragmented)
  std::size_t truncated = 0;       // frames whose captured length cuts the UDP payload short
};

// Streams a classic pcap file record by record.
class PcapReader {
 public:
  explicit PcapReader(const std::string& path);  // reads the global header; throws PcapError
  // Next IPv4/UDP payload; false at the clean end of the file. Throws PcapError on a record
  // truncated by the end of the file.
  bool next(UdpPayload& out);
  const PcapStats& stats() const { return stats_; }
  uint32_t linkType() const { return link_type_; }

 private:
  bool readRecord(std::vector<uint8_t>& frame, uint64_t& timestamp_ns);
  bool parseFrame(const std::vector<uint8_t>& frame, UdpPayload& out);
  uint32_t u32(const uint8_t* p) const;

  std::string path_;
  std::ifstream in_;
  bool swapped_ = false;   // file written on a host of the other byte order
  bool nanosecond_ = false;
  uint32_t link_type_ = 0;
  uint64_t offset_ = 0;    // byte offset of the next record
  PcapStats stats_;
};

// All UDP payloads of a pcap (optionally only those sent to `dst_port`; 0 = any port).
std::vector<UdpPayload> readPcapUdp(const std::string& path, uint16_t dst_port = 0,
                                    PcapStats* stats = nullptr);

// A file of concatenated payloads of `payload_size` bytes each. Throws PcapError if the file
// cannot be read, is empty, or its size is not a multiple of `payload_size`.
std::vector<std::vector<uint8_t>> readRawPayloadFile(const std::string& path,
                                                     std::size_t payload_size = 1206);

// True if the file starts with a classic-pcap magic number (either order, us or ns).
bool looksLikePcap(const std::string& path);

}  // namespace lanemap::lidar
