#include "core/io/lane_map_json.h"

#include "core/io/atomic_file.h"
#include "core/io/json_file.h"

namespace lanemap::io {

namespace {

using nlohmann::json;

json points(const std::vector<Eigen::Vector3d>& pts) {
  json a = json::array();
  for (const auto& p : pts) a.push_back({p.x(), p.y(), p.z()});
  return a;
}
std::vector<Eigen::Vector3d> points(const json& a) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(a.size());
  for (const auto& p : a) out.emplace_back(p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>());
  return out;
}

}  // namespace

json laneMapToJson(const map::LaneMap& m) {
  json j = {{"lanemap_lane_map_json", 1}, {"origin", {m.origin_lat, m.origin_lon, m.origin_alt}}};
  json& lines = j["lines"] = json::array();
  for (const auto& l : m.lines) lines.push_back({{"id", l.id}, {"type", static_cast<int>(l.type)}, {"points", points(l.points)}});
  json& lanelets = j["lanelets"] = json::array();
  for (const auto& l : m.lanelets) {
    json e = {{"id", l.id},          {"kind", static_cast<int>(l.kind)}, {"left", l.left_id},
              {"right", l.right_id}, {"centre", points(l.centre)},        {"successors", l.successors},
              {"turn", static_cast<int>(l.turn)}, {"road_id", l.road_id},  {"from", l.from_node},
              {"to", l.to_node},     {"intersection_id", l.intersection_id}, {"index_from_left", l.index_from_left}};
    if (l.stop_line_id) e["stop_line"] = *l.stop_line_id;
    if (l.partial) e["partial"] = {l.partial->station_m, l.partial->road_length_m};
    if (l.confidence) e["confidence"] = *l.confidence;
    lanelets.push_back(std::move(e));
  }
  json& elements = j["regulatory_elements"] = json::array();
  for (const auto& r : m.regulatory_elements) {
    elements.push_back({{"id", r.id}, {"kind", static_cast<int>(r.kind)}, {"stop_line", r.stop_line_id},
                        {"lanelets", r.lanelets}, {"priority", r.priority}, {"light", points(r.light)},
                        {"light_height_m", r.light_height_m}, {"light_estimated", r.light_estimated}, {"osm_node", r.osm_node}});
  }
  json& crosswalks = j["crosswalks"] = json::array();
  for (const auto& c : m.crosswalks) {
    crosswalks.push_back({{"id", c.id}, {"left", points(c.left)}, {"right", points(c.right)}, {"crossing", c.crossing}, {"road_id", c.road_id}});
  }
  return j;
}

map::LaneMap laneMapFromJson(const json& j) {
  if (!j.is_object() || j.value("lanemap_lane_map_json", 0) != 1) throw IoError("not a lanemap lane map (JSON, version 1)");
  try {
    map::LaneMap m;
    m.origin_lat = j.at("origin").at(0).get<double>();
    m.origin_lon = j.at("origin").at(1).get<double>();
    m.origin_alt = j.at("origin").at(2).get<double>();
    for (const auto& e : j.at("lines")) {
      m.lines.push_back({e.at("id").get<int64_t>(), static_cast<map::LineType>(e.at("type").get<int>()), points(e.at("points"))});
    }
    for (const auto& e : j.at("lanelets")) {
      map::Lanelet l;
      l.id = e.at("id").get<int64_t>();
      l.kind = static_cast<map::LaneletKind>(e.at("kind").get<int>());
      l.left_id = e.at("left").get<int64_t>();
      l.right_id = e.at("right").get<int64_t>();
      l.centre = points(e.at("centre"));
      l.successors = e.at("successors").get<std::vector<int64_t>>();
      l.turn = static_cast<map::TurnDirection>(e.at("turn").get<int>());
      l.road_id = e.at("road_id").get<int64_t>();
      l.from_node = e.at("from").get<int64_t>();
      l.to_node = e.at("to").get<int64_t>();
      l.intersection_id = e.at("intersection_id").get<int64_t>();
      l.index_from_left = e.at("index_from_left").get<int>();
      if (e.contains("stop_line")) l.stop_line_id = e.at("stop_line").get<int64_t>();
      if (e.contains("partial")) l.partial = map::PartialRoad{e.at("partial").at(0).get<double>(), e.at("partial").at(1).get<double>()};
      if (e.contains("confidence")) l.confidence = e.at("confidence").get<double>();
      m.lanelets.push_back(std::move(l));
    }
    for (const auto& e : j.at("regulatory_elements")) {
      map::RegulatoryElement r;
      r.id = e.at("id").get<int64_t>();
      r.kind = static_cast<map::RegulatoryKind>(e.at("kind").get<int>());
      r.stop_line_id = e.at("stop_line").get<int64_t>();
      r.lanelets = e.at("lanelets").get<std::vector<int64_t>>();
      r.priority = e.at("priority").get<std::vector<int64_t>>();
      r.light = points(e.at("light"));
      r.light_height_m = e.at("light_height_m").get<double>();
      r.light_estimated = e.at("light_estimated").get<bool>();
      r.osm_node = e.at("osm_node").get<int64_t>();
      m.regulatory_elements.push_back(std::move(r));
    }
    for (const auto& e : j.at("crosswalks")) {
      m.crosswalks.push_back({e.at("id").get<int64_t>(), points(e.at("left")), points(e.at("right")),
                              e.at("crossing").get<std::vector<int64_t>>(), e.at("road_id").get<int64_t>()});
    }
    return m;
  } catch (const json::exception& e) {
    throw IoError(std::string("a lanemap lane map with a missing or mistyped field: ") + e.what());
  }
}

void writeLaneMapJson(const map::LaneMap& map, const std::string& path) {
  writeFileAtomically(path, laneMapToJson(map).dump() + "\n");
}

map::LaneMap readLaneMapJson(const std::string& path) {
  return readJsonFile(path, laneMapFromJson);
}

}  // namespace lanemap::io
