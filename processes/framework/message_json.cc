#include "processes/framework/message_json.h"

#include "core/bev/bev_grid.h"
#include "core/seg/segmenter.h"
#include "lanemap/bev_preview_t.hpp"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/log_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace lanemap {
namespace {

template <class M>
M decode(const std::string& channel, const void* data, int size) {
  M m;
  if (m.decode(data, 0, size) != size) throw std::runtime_error("message on " + channel + " does not decode as its registry type");
  return m;
}

std::string fileName(const std::string& path) { return path.empty() ? path : std::filesystem::path(path).filename().string(); }

uint64_t fnv1a(const void* data, int size) {
  uint64_t h = 1469598103934665603ull;
  const auto* p = static_cast<const unsigned char*>(data);
  for (int i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

nlohmann::json polyline(const polyline_t& p) {
  nlohmann::json pts = nlohmann::json::array();
  for (int i = 0; i < p.num_points; ++i) pts.push_back({p.east[i], p.north[i], p.up[i]});
  return {{"type", p.type}, {"points", pts}};
}

}  // namespace

nlohmann::json messageJson(const std::string& channel, const void* data, int size) {
  const auto* spec = channels::find(channel);
  const std::string_view type = spec ? spec->type : "";
  if (type == "lanemap.road_event_t") {
    const auto m = decode<road_event_t>(channel, data, size);
    return {{"utime", m.utime}, {"type", m.type}, {"road_id", m.road_id}, {"from_node", m.from_node}, {"to_node", m.to_node},
            {"previous_road_id", m.previous_road_id}, {"intersection_id", m.intersection_id}, {"distance_m", m.distance_m},
            {"detail", m.detail}};
  }
  if (type == "lanemap.bev_road_t") {
    const auto m = decode<bev_road_t>(channel, data, size);
    nlohmann::json grid;  // the grid file it names, as it is now: per layer, the sum of its counts
    std::error_code ec;
    if (!m.path.empty() && std::filesystem::is_regular_file(m.path, ec)) {
      const bev::BevGrid g = bev::BevGrid::load(m.path);
      std::vector<int64_t> sums(bev::kNumLayers, 0);
      const int cells = g.options().tile_cells * g.options().tile_cells;
      g.forEachTile([&](const bev::BevGrid::Cell&, const uint16_t* counts) {
        for (int l = 0; l < bev::kNumLayers; ++l) {
          for (int i = 0; i < cells; ++i) sums[l] += counts[l * cells + i];
        }
      });
      grid = {{"frames", g.frames()}, {"tiles", g.tileCount()}};
      for (int l = 0; l < bev::kNumLayers; ++l) grid[bev::toString(static_cast<bev::Layer>(l))] = sums[l];
    }
    return {{"grid", grid}, {"utime", m.utime}, {"road_id", m.road_id}, {"from_node", m.from_node}, {"to_node", m.to_node},
            {"path", fileName(m.path)}, {"origin_east", m.origin_east}, {"origin_north", m.origin_north},
            {"resolution_m", m.resolution_m}, {"width", m.width}, {"height", m.height}, {"num_frames", m.num_frames}};
  }
  if (type == "lanemap.lane_map_t") {
    const auto m = decode<lane_map_t>(channel, data, size);
    nlohmann::json lanes = nlohmann::json::array();
    for (const auto& l : m.lanes) {
      lanes.push_back({{"lane_id", l.lane_id}, {"index_from_left", l.index_from_left}, {"centre", polyline(l.centre)},
                       {"left_boundary", polyline(l.left_boundary)}, {"right_boundary", polyline(l.right_boundary)},
                       {"successors", l.successors}, {"confidence", l.confidence}});
    }
    return {{"utime", m.utime}, {"kind", m.kind}, {"id", m.id}, {"origin_latitude", m.origin_latitude},
            {"origin_longitude", m.origin_longitude}, {"origin_altitude", m.origin_altitude}, {"lanes", lanes},
            {"map_path", fileName(m.map_path)}, {"partial_station_m", m.partial_station_m},
            {"partial_road_length_m", m.partial_road_length_m}};
  }
  if (type == "lanemap.label_image_t") {
    // The labels as pixels per class (a model's argmax may differ in a few pixels between CPUs; a
    // hash of the PNG would not say by how much).
    const auto m = decode<label_image_t>(channel, data, size);
    nlohmann::json classes = nlohmann::json::array();
    try {
      const cv::Mat labels = seg::decodeLabels(m.encoding, m.width, m.height, m.data);
      std::vector<int64_t> n(label_image_t::NUM_CLASSES + 1, 0);  // the last: ids beyond the classes
      for (int r = 0; r < labels.rows; ++r) {
        for (int c = 0; c < labels.cols; ++c) ++n[std::min<int>(labels.at<uint8_t>(r, c), label_image_t::NUM_CLASSES)];
      }
      classes = n;
    } catch (const std::exception& e) {
      classes = std::string("undecodable: ") + e.what();
    }
    return {{"utime", m.utime}, {"seq", m.seq}, {"width", m.width}, {"height", m.height}, {"encoding", m.encoding},
            {"source", m.source}, {"class_pixels", classes}};
  }
  if (type == "lanemap.bev_preview_t") {
    const auto m = decode<bev_preview_t>(channel, data, size);
    return {{"road_id", m.road_id}, {"num_frames", m.num_frames}, {"west", m.west}, {"south", m.south},
            {"east", m.east}, {"north", m.north}, {"png_bytes", m.size}};  // utime is the wall clock
  }
  if (type == "lanemap.pose_t") {
    const auto m = decode<pose_t>(channel, data, size);
    auto array = [](const double* v, int n) { return nlohmann::json(std::vector<double>(v, v + n)); };
    return {{"utime", m.utime}, {"latitude", m.latitude}, {"longitude", m.longitude}, {"altitude", m.altitude},
            {"orientation", array(m.orientation, 4)}, {"velocity_enu", array(m.velocity_enu, 3)},
            {"angular_rate", array(m.angular_rate, 3)}, {"position_covariance", array(m.position_covariance, 9)},
            {"orientation_covariance", array(m.orientation_covariance, 9)}, {"status", m.status}};
  }
  if (type == "lanemap.lidar_packets_t") {
    // The packets are the sensor's bytes, passed through: their hash; their times as numbers.
    const auto m = decode<lidar_packets_t>(channel, data, size);
    uint64_t h = 1469598103934665603ull;
    for (const auto& p : m.data) h = (h ^ fnv1a(p.data(), static_cast<int>(p.size()))) * 1099511628211ull;
    return {{"utime", m.utime}, {"model", m.model}, {"num_packets", m.num_packets}, {"packet_size", m.packet_size},
            {"first_packet_utime", m.packet_utime.empty() ? 0 : m.packet_utime.front()},
            {"last_packet_utime", m.packet_utime.empty() ? 0 : m.packet_utime.back()}, {"packets_fnv1a", h}};
  }
  if (type == "lanemap.lidar_points_t") {
    // The decoded points summarised: count, per-ring counts, sums and extremes of each coordinate.
    const auto m = decode<lidar_points_t>(channel, data, size);
    auto summary = [](const std::vector<float>& v) {
      double sum = 0.0, lo = 0.0, hi = 0.0;
      for (size_t i = 0; i < v.size(); ++i) {
        sum += v[i];
        lo = i ? std::min<double>(lo, v[i]) : v[i];
        hi = i ? std::max<double>(hi, v[i]) : v[i];
      }
      return nlohmann::json{{"sum", sum}, {"min", lo}, {"max", hi}};
    };
    std::vector<int64_t> rings;
    for (const int8_t r : m.ring) {
      if (r >= 0 && static_cast<size_t>(r) >= rings.size()) rings.resize(static_cast<size_t>(r) + 1, 0);
      if (r >= 0) ++rings[static_cast<size_t>(r)];
    }
    return {{"utime", m.utime}, {"num_points", m.num_points}, {"x", summary(m.x)}, {"y", summary(m.y)},
            {"z", summary(m.z)}, {"intensity", summary(m.intensity)}, {"time_offset", summary(m.time_offset)},
            {"points_per_ring", rings}};
  }
  return {{"bytes", size}, {"fnv1a", fnv1a(data, size)}};
}

std::string logJsonLines(const std::string& path) {
  LogReader in(path);
  std::string out;
  while (const lcm::LogEvent* ev = in.next()) {
    const nlohmann::json line{{"t", ev->timestamp}, {"channel", ev->channel}, {"msg", messageJson(ev->channel, ev->data, ev->datalen)}};
    out += line.dump() + "\n";
  }
  return out;
}

namespace {

std::vector<nlohmann::json> parseLines(const std::string& text, const char* which) {
  std::vector<nlohmann::json> out;
  size_t start = 0;
  int n = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++n;
    if (end > start) {
      auto j = nlohmann::json::parse(text.substr(start, end - start), nullptr, false);
      if (j.is_discarded()) throw std::runtime_error(std::string(which) + " line " + std::to_string(n) + " is not JSON");
      out.push_back(std::move(j));
    }
    start = end + 1;
  }
  return out;
}

std::string brief(const nlohmann::json& j) {
  std::string s = j.dump();
  return s.size() > 80 ? s.substr(0, 77) + "..." : s;
}

void compareValue(const nlohmann::json& ref, const nlohmann::json& act, const std::string& where, double abs_tol,
                  double rel_tol, std::vector<std::string>& out, size_t max_lines) {
  if (out.size() >= max_lines) return;
  if (ref.is_number() && act.is_number()) {
    const double a = ref.get<double>(), b = act.get<double>();
    if (!(std::abs(a - b) <= abs_tol + rel_tol * std::abs(a))) out.push_back(where + ": " + brief(ref) + " -> " + brief(act));
    return;
  }
  if (ref.type() != act.type()) {
    out.push_back(where + ": " + brief(ref) + " -> " + brief(act));
    return;
  }
  if (ref.is_object()) {
    for (auto it = ref.begin(); it != ref.end(); ++it) {
      if (!act.contains(it.key())) {
        out.push_back(where + "." + it.key() + ": missing");
      } else {
        compareValue(it.value(), act[it.key()], where + "." + it.key(), abs_tol, rel_tol, out, max_lines);
      }
    }
    for (auto it = act.begin(); it != act.end(); ++it) {
      if (!ref.contains(it.key())) out.push_back(where + "." + it.key() + ": new, " + brief(it.value()));
    }
    return;
  }
  if (ref.is_array()) {
    if (ref.size() != act.size()) {
      out.push_back(where + ": " + std::to_string(ref.size()) + " items -> " + std::to_string(act.size()));
      return;
    }
    for (size_t i = 0; i < ref.size(); ++i) compareValue(ref[i], act[i], where + "[" + std::to_string(i) + "]", abs_tol, rel_tol, out, max_lines);
    return;
  }
  if (ref != act) out.push_back(where + ": " + brief(ref) + " -> " + brief(act));
}

}  // namespace

std::vector<std::string> compareJsonLines(const std::string& reference, const std::string& actual, double abs_tol, double rel_tol,
                                          size_t max_lines) {
  const auto ref = parseLines(reference, "reference");
  const auto act = parseLines(actual, "output");
  std::vector<std::string> out;
  const size_t n = std::min(ref.size(), act.size());
  for (size_t i = 0; i < n && out.size() < max_lines; ++i) {
    // A message's line is named by its channel; a line a process wrote itself by its first key.
    const std::string name = ref[i].contains("channel") ? ref[i].value("channel", std::string("?"))
                             : ref[i].is_object() && !ref[i].empty() ? ref[i].begin().key()
                                                                     : std::string("?");
    const std::string where = "line " + std::to_string(i + 1) + " (" + name + ")";
    compareValue(ref[i], act[i], where, abs_tol, rel_tol, out, max_lines);
  }
  if (ref.size() != act.size() && out.size() < max_lines) {
    out.push_back(std::to_string(ref.size()) + " messages in the reference, " + std::to_string(act.size()) + " published" +
                  (act.size() > ref.size() ? "; the first new: " + brief(act[ref.size()]) : "; the first missing: " + brief(ref[act.size()])));
  }
  return out;
}

}  // namespace lanemap
