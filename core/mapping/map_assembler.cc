#include "core/mapping/map_assembler.h"

#include "core/mapping/shared_dividers.h"
#include "core/mapping/two_way_links.h"

#include <algorithm>
#include <set>
#include <tuple>
#include <utility>

namespace lanemap::mapping {

MapAssembler::MapAssembler(const skeleton::Skeleton& skeleton, intersections::IntersectionOptions options,
                           std::vector<osm::Restriction> restrictions)
    : skeleton_(skeleton), options_(std::move(options)), restrictions_(std::move(restrictions)) {
  options_.validate();
  const auto& all = skeleton_.intersections();
  for (size_t i = 0; i < all.size(); ++i) index_of_intersection_.emplace(all[i].id, i);
}

void MapAssembler::setRoad(int64_t road_id, map::LaneMap lanes) {
  // A two-way link's two directions cut to the stretch both cover (two_way_links.h), from the two
  // as set (kept for the roads that may be cut only), the lower road id first: the same whatever
  // order the two came in.
  const bool link = mayMatchTwoWayLink(lanes, skeleton_, road_id);
  if (link) {
    as_set_[road_id] = lanes;
  } else {
    as_set_.erase(road_id);
  }
  roads_[road_id] = std::move(lanes);
  markEnds(road_id);
  const auto* road = skeleton_.road(road_id);
  if (!road || road->reverse_id < 0) return;
  const auto other = as_set_.find(road->reverse_id);
  if (other == as_set_.end()) return;
  markEnds(road->reverse_id);
  if (!link) {  // no link now: the reverse as it was set
    roads_[road->reverse_id] = other->second;
    return;
  }
  const int64_t a = std::min(road_id, road->reverse_id), b = std::max(road_id, road->reverse_id);
  map::LaneMap la = as_set_.at(a), lb = as_set_.at(b);
  if (matchTwoWayLink(la, a, lb, b, skeleton_)) ++two_way_links_cut_;
  roads_[a] = std::move(la);
  roads_[b] = std::move(lb);
}

void MapAssembler::markEnds(int64_t road_id) {
  if (const auto* road = skeleton_.road(road_id)) {
    for (const int64_t node : {road->from, road->to}) {
      if (const auto it = index_of_intersection_.find(node); it != index_of_intersection_.end()) marked_.insert(it->second);
    }
  }
}

bool MapAssembler::addPassage(intersections::DrivenPassage passage) {
  const auto* from = skeleton_.road(passage.from_road);
  const auto* to = skeleton_.road(passage.to_road);
  if (!from || !to || from->to != to->from || passage.path.size() < 2) return false;
  const auto it = index_of_intersection_.find(from->to);
  if (it == index_of_intersection_.end()) return false;
  passage.intersection_id = from->to;
  auto& list = passages_[it->second];
  const auto order = [](const intersections::DrivenPassage& a, const intersections::DrivenPassage& b) {
    const auto key = [](const intersections::DrivenPassage& p) {
      return std::make_tuple(p.from_road, p.to_road, p.path.front().x(), p.path.front().y(), p.path.back().x(),
                             p.path.back().y(), p.path.size());
    };
    return key(a) < key(b);
  };
  list.insert(std::upper_bound(list.begin(), list.end(), passage, order), std::move(passage));
  marked_.insert(it->second);
  return true;
}

std::vector<intersections::DrivenPassage> MapAssembler::passages() const {
  std::vector<intersections::DrivenPassage> out;
  for (const auto& [i, list] : passages_) out.insert(out.end(), list.begin(), list.end());
  return out;
}

size_t MapAssembler::passageCount() const {
  size_t n = 0;
  for (const auto& [i, list] : passages_) n += list.size();
  return n;
}

size_t MapAssembler::update() {
  const size_t n = marked_.size();
  for (const size_t i : marked_) {
    Built b;
    try {
      static const std::vector<intersections::DrivenPassage> none;
      const auto p = passages_.find(i);
      b.result = intersections::buildJoinedIntersection(skeleton_, i, roads_, options_, restrictions_,
                                                        p == passages_.end() ? none : p->second);
    } catch (const std::exception& e) {
      b.failure = "intersection " + std::to_string(skeleton_.intersections()[i].id) + ": " + e.what();
    }
    if (b.result || !b.failure.empty()) {
      built_[i] = std::move(b);
    } else {
      built_.erase(i);
    }
  }
  marked_.clear();
  return n;
}

std::vector<const intersections::IntersectionResult*> MapAssembler::intersections() {
  update();
  std::vector<const intersections::IntersectionResult*> out;
  for (const auto& [i, b] : built_) {
    if (b.result) out.push_back(&*b.result);
  }
  return out;
}

std::vector<std::string> MapAssembler::failures() {
  update();
  std::vector<std::string> out;
  for (const auto& [i, b] : built_) {
    if (!b.failure.empty()) out.push_back(b.failure);
  }
  return out;
}

map::LaneMap MapAssembler::map(std::vector<std::string>* failures) {
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
  intersections::appendIntersections(all, intersections());
  shareDividers(all, skeleton_);  // two bounds of opposite lanes on top of each other: one line
  if (failures) {
    for (auto& f : this->failures()) failures->push_back(std::move(f));
  }
  return all;
}

}  // namespace lanemap::mapping
