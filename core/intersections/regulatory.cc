#include "core/intersections/regulatory.h"
#include "core/osm/coordinate_guard.h"

#include <osmium/handler.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/visitor.hpp>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

namespace lanemap::intersections {

const char* toString(Control c) {
  switch (c) {
    case Control::kNone: return "none";
    case Control::kStop: return "stop";
    case Control::kGiveWay: return "give_way";
    case Control::kTrafficSignals: return "traffic_signals";
  }
  return "?";
}

namespace {

class ControlHandler : public osmium::handler::Handler {
 public:
  std::unordered_map<int64_t, ControlNode> nodes;

  void node(const osmium::Node& n) {
    const char* hw = n.tags().get_value_by_key("highway");
    if (!hw || !n.location().valid()) return;
    const std::string h = hw;
    ControlNode c;
    if (h == "stop") c.control = Control::kStop;
    else if (h == "give_way") c.control = Control::kGiveWay;
    else if (h == "traffic_signals") c.control = Control::kTrafficSignals;
    else return;
    c.id = n.id();
    c.lat = n.location().lat();
    c.lon = n.location().lon();
    for (const char* key : {"direction", "traffic_signals:direction"}) {
      if (const char* v = n.tags().get_value_by_key(key)) {
        c.direction = v;
        break;
      }
    }
    if (const char* all = n.tags().get_value_by_key("stop"); all && std::string(all) == "all") c.direction.clear();
    nodes[c.id] = c;
  }
};

// Whether a node's direction tag lets it apply to travel along (or against) its way.
bool appliesTo(const std::string& direction, bool along_way) {
  if (direction.empty() || direction == "both") return true;
  if (direction == "forward") return along_way;
  if (direction == "backward") return !along_way;
  return true;  // a bearing or an unknown value: the side of the junction decides
}

}  // namespace

std::unordered_map<int64_t, ControlNode> readControlNodes(const std::string& osm_path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(osm_path, ec)) {
    throw osm::OsmError("cannot read OSM file '" + osm_path + "': no such file");
  }
  osm::refuseExponentCoordinate<osm::OsmError>(osm_path, "cannot read OSM file '" + osm_path + "'");  // libosmium overflows on it
  ControlHandler h;
  try {
    osmium::io::Reader reader{osmium::io::File{osm_path}, osmium::osm_entity_bits::node};
    osmium::apply(reader, h);
    reader.close();
  } catch (const std::exception& e) {
    throw osm::OsmError("cannot read the nodes of OSM file '" + osm_path + "': " + e.what());
  }
  return std::move(h.nodes);
}

ApproachControl approachControl(const skeleton::Skeleton& sk, int64_t road_id,
                                const std::unordered_map<int64_t, ControlNode>& controls) {
  ApproachControl out;
  const skeleton::AtomicRoad* road = sk.road(road_id);
  if (!road) return out;
  // The strongest control wins: signals over stop over give way.
  const auto rank = [](Control c) { return c == Control::kTrafficSignals ? 3 : c == Control::kStop ? 2 : c == Control::kGiveWay ? 1 : 0; };
  const auto consider = [&](const ControlNode& c) {
    if (rank(c.control) > rank(out.control)) out = {c.control, c.id};
  };
  if (const skeleton::Intersection* in = sk.intersection(road->to)) {
    for (int64_t n : in->osm_nodes) {
      if (const auto it = controls.find(n); it != controls.end()) consider(it->second);
    }
    if (const auto it = controls.find(in->id); it != controls.end()) consider(it->second);
  }
  for (int64_t n : road->osm_nodes) {
    const auto it = controls.find(n);
    if (it == controls.end()) continue;
    const ControlNode& c = it->second;
    if (!appliesTo(c.direction, road->along_way)) continue;
    const Eigen::Vector3d p = sk.frame().toEnu(c.lat, c.lon);
    const skeleton::RoadMatch m = sk.project(road->id, p.head<2>());
    const double to_end = road->length - m.s;
    if (m.road_id < 0 || to_end > kApproachSearchM || m.s < 0.5 * road->length) continue;
    consider(c);
  }
  return out;
}

size_t addRegulatoryElements(map::LaneMap& map, const skeleton::Skeleton& sk,
                             const std::unordered_map<int64_t, ControlNode>& controls) {
  map.regulatory_elements.clear();
  int64_t next_id = 1;
  for (const auto& l : map.lines) next_id = std::max(next_id, l.id + 1);
  for (const auto& l : map.lanelets) next_id = std::max(next_id, l.id + 1);
  for (const auto& c : map.crosswalks) next_id = std::max(next_id, c.id + 1);

  // Stop lines and the road lanelets that end at each; the control of every approach.
  std::map<int64_t, std::vector<const map::Lanelet*>> at_stop_line;
  std::map<int64_t, ApproachControl> control_of_road;
  for (const auto& ll : map.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad || ll.road_id < 0) continue;
    if (!control_of_road.count(ll.road_id)) control_of_road[ll.road_id] = approachControl(sk, ll.road_id, controls);
    if (ll.stop_line_id && map.line(*ll.stop_line_id)) at_stop_line[*ll.stop_line_id].push_back(&ll);
  }
  // Lanelets entering an intersection from an approach with no control: priority for give way.
  const auto entering = [&](const map::Lanelet& ll) {
    return std::any_of(ll.successors.begin(), ll.successors.end(), [&](int64_t s) {
      const map::Lanelet* n = map.lanelet(s);
      return n && n->kind == map::LaneletKind::kIntersection;
    });
  };
  for (const auto& [stop_id, lanelets] : at_stop_line) {
    const map::Lanelet& first = *lanelets.front();
    const ApproachControl ac = control_of_road.at(first.road_id);
    if (ac.control == Control::kNone) continue;
    map::RegulatoryElement r;
    r.id = next_id++;
    r.stop_line_id = stop_id;
    r.osm_node = ac.node;
    for (const auto* ll : lanelets) r.lanelets.push_back(ll->id);
    const skeleton::AtomicRoad* road = sk.road(first.road_id);
    switch (ac.control) {
      case Control::kStop: r.kind = map::RegulatoryKind::kStopSign; break;
      case Control::kGiveWay: {
        r.kind = map::RegulatoryKind::kGiveWay;
        const skeleton::Intersection* in = road ? sk.intersection(road->to) : nullptr;
        if (!in) break;
        const std::set<int64_t> incoming(in->incoming.begin(), in->incoming.end());
        for (const auto& ll : map.lanelets) {
          if (ll.kind != map::LaneletKind::kRoad || ll.road_id == first.road_id || !incoming.count(ll.road_id)) continue;
          const auto c = control_of_road.find(ll.road_id);
          if (c != control_of_road.end() && c->second.control == Control::kNone && entering(ll)) r.priority.push_back(ll.id);
        }
        break;
      }
      case Control::kTrafficSignals: {
        r.kind = map::RegulatoryKind::kTrafficLight;
        const map::LineString& stop = *map.line(stop_id);
        const Eigen::Vector3d a = stop.points.front(), b = stop.points.back();
        const Eigen::Vector3d mid = 0.5 * (a + b);
        Eigen::Vector3d along = b - a;
        along.z() = 0.0;
        along = along.norm() > 0.0 ? along.normalized() : Eigen::Vector3d::UnitX();
        const Eigen::Vector3d up(0.0, 0.0, kLightClearanceM);
        r.light = {mid + up - 0.5 * kLightWidthM * along, mid + up + 0.5 * kLightWidthM * along};
        r.light_height_m = kLightHeightM;
        r.light_estimated = true;
        break;
      }
      case Control::kNone: break;
    }
    map.regulatory_elements.push_back(std::move(r));
  }
  return map.regulatory_elements.size();
}

}  // namespace lanemap::intersections
