// lanemap-lidar-decode: decodes Velodyne data packets from a pcap or a raw payload file into
// points (CSV, sensor frame x forward / y left / z up) and prints a summary of what was read.
#include "core/lidar/pcap.h"
#include "core/lidar/velodyne.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace lanemap::lidar;

struct Input {
  bool is_pcap = false;
  std::vector<std::vector<uint8_t>> data_payloads;
  std::size_t position_payloads = 0;
  std::size_t other_udp = 0;
  PcapStats pcap;
};

Input readInput(const std::string& path, uint16_t data_port, uint16_t position_port) {
  Input in;
  in.is_pcap = looksLikePcap(path);
  if (!in.is_pcap) {
    in.data_payloads = readRawPayloadFile(path, kDataPacketSize);
    return in;
  }
  for (auto& p : readPcapUdp(path, 0, &in.pcap)) {
    if (p.dst_port == data_port) in.data_payloads.push_back(std::move(p.data));
    else if (p.dst_port == position_port) ++in.position_payloads;
    else ++in.other_udp;
  }
  return in;
}

struct Summary {
  std::map<std::string, std::size_t> models, return_modes;
  float min_distance = std::numeric_limits<float>::infinity();
  float max_distance = 0.0f;
  std::optional<uint32_t> first_usec, last_usec;
};

void writeCsvRows(std::FILE* csv, const std::vector<LidarPoint>& points) {
  for (const LidarPoint& p : points)
    std::fprintf(csv, "%.4f,%.4f,%.4f,%.0f,%u,%u,%.3f,%.7f\n", p.x, p.y, p.z, p.intensity,
                 unsigned{p.ring}, unsigned{p.laser}, p.azimuth_deg, p.time_offset_s);
}

const char* returnModeName(ReturnMode m) {
  switch (m) {
    case ReturnMode::kStrongest: return "strongest";
    case ReturnMode::kLast: return "last";
    case ReturnMode::kDual: return "dual";
  }
  return "?";
}

void printSummary(const std::string& path, const Input& in, const DecodeStats& s,
                  const Summary& sum, const SweepSplitter& sweeps) {
  std::printf("input            %s (%s)\n", path.c_str(), in.is_pcap ? "pcap" : "raw payloads");
  if (in.is_pcap)
    std::printf("pcap frames      %zu (udp %zu, position packets %zu, other udp %zu, non-udp %zu)\n",
                in.pcap.frames, in.pcap.udp, in.position_payloads, in.other_udp,
                in.pcap.not_ipv4_udp + in.pcap.fragments + in.pcap.truncated);
  std::printf("data packets     %zu read, %zu decoded, %zu rejected\n", s.packets, s.decoded,
              s.rejected());
  std::printf("  rejected       short %zu, oversize %zu, bad flag %zu, bad azimuth %zu, "
              "unknown return mode %zu, unknown product id %zu\n",
              s.short_packets, s.oversize, s.bad_flag, s.bad_azimuth, s.unknown_return_mode,
              s.unknown_model);
  for (const auto& [name, n] : sum.models) std::printf("model            %s (%zu packets)\n", name.c_str(), n);
  for (const auto& [name, n] : sum.return_modes)
    std::printf("return mode      %s (%zu packets)\n", name.c_str(), n);
  std::printf("points           %zu\n", s.points);
  std::printf("sweeps           %zu complete%s\n", sweeps.completed(),
              sweeps.current().empty() ? "" : " + 1 partial");
  if (s.points > 0)
    std::printf("distance range   %.3f .. %.3f m\n", sum.min_distance, sum.max_distance);
  if (sum.first_usec)
    std::printf("timestamps       %u .. %u us past the hour\n", *sum.first_usec, *sum.last_usec);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "lanemap-lidar-decode: decode Velodyne VLP-16 / VLP-32C / HDL-32E data packets.\n"
      "INPUT is a classic pcap (UDP payloads to --port are data packets, to 8308 position\n"
      "packets) or a raw file of concatenated 1206-byte payloads. Points are in the sensor frame\n"
      "x forward, y left, z up; azimuth_deg is Velodyne's (0 ahead, clockwise); time_offset_s is\n"
      "after the packet's timestamp. Zero distances (no return) give no point.");
  std::string input, csv_path, model_name = "auto";
  uint16_t data_port = kDataPort;
  app.add_option("input", input, "pcap or raw payload file")->required()->check(CLI::ExistingFile);
  app.add_option("--csv", csv_path,
                 "write points here: x,y,z,intensity,ring,laser,azimuth_deg,time_offset_s");
  app.add_option("--model", model_name,
                 "vlp16|vlp32c|hdl32e, or auto = from the product-id byte (0x22 VLP-16, "
                 "0x28 VLP-32C, 0x21 HDL-32E; some VLP-16s report 0x21: force vlp16 then)")
      ->check(CLI::IsMember({"auto", "vlp16", "vlp32c", "hdl32e"}))
      ->capture_default_str();
  app.add_option("--port", data_port, "UDP destination port of data packets in a pcap")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    std::optional<Model> forced;
    if (model_name != "auto") forced = parseModel(model_name);
    const Input in = readInput(input, data_port, kPositionPort);

    std::unique_ptr<std::FILE, int (*)(std::FILE*)> csv(nullptr, &std::fclose);
    if (!csv_path.empty()) {
      csv.reset(std::fopen(csv_path.c_str(), "w"));
      if (!csv) throw LidarError("cannot write CSV file '" + csv_path + "'");
      std::fprintf(csv.get(), "x,y,z,intensity,ring,laser,azimuth_deg,time_offset_s\n");
    }

    PacketDecoder decoder(forced);
    SweepSplitter sweeps;
    Summary sum;
    std::vector<LidarPoint> points;
    for (const auto& payload : in.data_payloads) {
      points.clear();
      PacketInfo info;
      if (decoder.decode(payload.data(), payload.size(), points, &info) != DecodeStatus::kOk)
        continue;
      ++sum.models[toString(info.model)];
      ++sum.return_modes[returnModeName(info.return_mode)];
      if (!sum.first_usec) sum.first_usec = info.usec_past_hour;
      sum.last_usec = info.usec_past_hour;
      for (const LidarPoint& p : points) {
        const float d = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
        sum.min_distance = std::min(sum.min_distance, d);
        sum.max_distance = std::max(sum.max_distance, d);
      }
      sweeps.add(points);
      sweeps.takeSweeps();  // only counted here
      if (csv) writeCsvRows(csv.get(), points);
    }
    printSummary(input, in, decoder.stats(), sum, sweeps);
    if (csv && std::ferror(csv.get())) throw LidarError("error writing '" + csv_path + "'");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lanemap-lidar-decode: %s\n", e.what());
    return 1;
  }
  return 0;
}
