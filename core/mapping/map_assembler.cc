#include "core/mapping/map_assembler.h"

#include <set>
#include <utility>

namespace lanemap::mapping {

MapAssembler::MapAssembler(const skeleton::Skeleton& skeleton, intersections::IntersectionOptions options,
                           std::vector<osm::Restriction> restrictions)
    : skeleton_(skeleton), options_(std::move(options)), restrictions_(std::move(restrictions)) {}

void MapAssembler::setRoad(int64_t road_id, map::LaneMap lanes) { roads_[road_id] = std::move(lanes); }

map::LaneMap MapAssembler::map(std::vector<std::string>* failures) const {
  map::LaneMap all;
  const auto& o = skeleton_.frame().origin();
  all.origin_lat = o.lat;
  all.origin_lon = o.lon;
  all.origin_alt = o.alt;
  std::set<int64_t> line_ids;  // a line shared by two roads' maps is written once
  for (const auto& [id, m] : roads_) {
    for (const auto& l : m.lines) {
      if (line_ids.insert(l.id).second) all.lines.push_back(l);
    }
    all.lanelets.insert(all.lanelets.end(), m.lanelets.begin(), m.lanelets.end());
  }
  for (const auto& r : intersections::buildIntersections(skeleton_, roads_, options_, restrictions_, failures)) {
    intersections::appendIntersection(all, r);
  }
  return all;
}

}  // namespace lanemap::mapping
