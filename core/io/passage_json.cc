#include "core/io/passage_json.h"

#include "core/io/atomic_file.h"
#include "core/io/json_file.h"

namespace lanemap::io {

using nlohmann::json;

json passageToJson(const intersections::DrivenPassage& p) {
  json path = json::array();
  for (const auto& q : p.path) path.push_back({q.x(), q.y()});
  return {{"lanemap_passage_json", 1}, {"intersection_id", p.intersection_id}, {"from_road", p.from_road},
          {"to_road", p.to_road}, {"path", path}};
}

intersections::DrivenPassage passageFromJson(const json& j) {
  if (!j.is_object() || j.value("lanemap_passage_json", 0) != 1) throw IoError("not a lanemap driven passage (JSON, version 1)");
  try {
    intersections::DrivenPassage p;
    p.intersection_id = j.at("intersection_id").get<int64_t>();
    p.from_road = j.at("from_road").get<int64_t>();
    p.to_road = j.at("to_road").get<int64_t>();
    for (const auto& q : j.at("path")) p.path.emplace_back(q.at(0).get<double>(), q.at(1).get<double>());
    return p;
  } catch (const json::exception& e) {
    throw IoError(std::string("a lanemap driven passage with a missing or mistyped field: ") + e.what());
  }
}

void writePassageJson(const intersections::DrivenPassage& passage, const std::string& path) {
  writeFileAtomically(path, passageToJson(passage).dump() + "\n");
}

intersections::DrivenPassage readPassageJson(const std::string& path) {
  return readJsonFile(path, passageFromJson);
}

}  // namespace lanemap::io
