// lanemap-check's rules (see map_check.h).
#include "core/io/map_check.h"

#include "core/geo/local_frame.h"
#include "core/geo/polyline.h"
#include "core/io/atomic_file.h"
#include "core/io/lanelet2.h"
#include "core/io/read_file.h"
#include "core/osm/coordinate_guard.h"

#include <nlohmann/json.hpp>
#include <osmium/handler.hpp>
#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/relation.hpp>
#include <osmium/osm/way.hpp>
#include <osmium/visitor.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>

namespace lanemap::io {
namespace {

using Tags = std::map<std::string, std::string>;

struct Node {
  double lat = 0, lon = 0;
  bool has_ele = false;
};
struct Way {
  std::vector<int64_t> refs;
  Tags tags;
};
struct Member {
  char kind = 'w';
  int64_t ref = 0;
  std::string role;
};
struct Relation {
  std::vector<Member> members;
  Tags tags;
};

struct Osm : osmium::handler::Handler {
  std::map<int64_t, Node> nodes;
  std::map<int64_t, Way> ways;
  std::map<int64_t, Relation> relations;
  void node(const osmium::Node& n) {
    Node& o = nodes[n.id()];
    if (n.location().valid()) {
      o.lat = n.location().lat_without_check();
      o.lon = n.location().lon_without_check();
    }
    o.has_ele = n.tags().has_key("ele");
  }
  void way(const osmium::Way& w) {
    Way& o = ways[w.id()];
    for (const auto& r : w.nodes()) o.refs.push_back(r.ref());
    for (const auto& t : w.tags()) o.tags[t.key()] = t.value();
  }
  void relation(const osmium::Relation& r) {
    Relation& o = relations[r.id()];
    for (const auto& m : r.members()) {
      o.members.push_back({m.type() == osmium::item_type::node ? 'n' : m.type() == osmium::item_type::way ? 'w' : 'r',
                           m.ref(), m.role()});
    }
    for (const auto& t : r.tags()) o.tags[t.key()] = t.value();
  }
};

std::string tag(const Tags& t, const std::string& k) {
  const auto it = t.find(k);
  return it == t.end() ? std::string() : it->second;
}

using Polyline = std::vector<Eigen::Vector2d>;

bool insidePolygon(const Polyline& ring, const Eigen::Vector2d& p) {
  bool in = false;
  for (size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const auto& a = ring[i];
    const auto& b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      in = !in;
    }
  }
  return in;
}

}  // namespace

std::vector<CheckResult> checkLanelet2Map(const std::string& path, const MapCheckOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError("cannot read map '" + path + "': no such file");
  osm::refuseExponentCoordinate<IoError>(path, "cannot read map '" + path + "'");  // libosmium overflows on it
  Osm osm;
  try {
    osmium::io::Reader reader{osmium::io::File{path, "osm"}};
    osmium::apply(reader, osm);
    reader.close();
  } catch (const std::exception& e) {
    throw IoError("cannot read map '" + path + "': " + e.what());
  }
  std::optional<geo::LocalFrame> frame;
  for (const auto& [id, n] : osm.nodes) {
    frame.emplace(geo::LatLonAlt{n.lat, n.lon, 0.0});
    break;
  }
  std::unordered_map<int64_t, Eigen::Vector2d> xy;
  for (const auto& [id, n] : osm.nodes) xy[id] = frame->toEnu(n.lat, n.lon, 0.0).head<2>();
  const auto polyline = [&](int64_t way) {
    Polyline pl;
    const auto it = osm.ways.find(way);
    if (it == osm.ways.end()) return pl;
    for (int64_t r : it->second.refs) {
      if (const auto p = xy.find(r); p != xy.end()) pl.push_back(p->second);
    }
    return pl;
  };

  // lanemap's sidecar: which lanelets are intersection lanelets, of which intersection.
  std::map<int64_t, int64_t> intersection_of;  // lanelet -> intersection id
  bool have_sidecar = false;
  if (lanelet2WriterOrigin(path)) {
    // lanelet2WriterOrigin found a sidecar matching the file: read its lanelets.
    const Lanelet2File f = readLanelet2File(path, 0.0, 0.0);
    have_sidecar = !f.sidecar.empty();
    for (const auto& ll : f.map.lanelets) {
      if (ll.kind == map::LaneletKind::kIntersection) intersection_of[ll.id] = ll.intersection_id;
    }
  }

  struct L {
    int64_t id, left = 0, right = 0;
    std::optional<int64_t> centre;
    const Relation* rel;
  };
  std::vector<L> lanelets;
  for (const auto& [id, r] : osm.relations) {
    if (tag(r.tags, "type") != "lanelet") continue;
    L l{id, 0, 0, std::nullopt, &r};
    for (const auto& m : r.members) {
      if (m.kind != 'w') continue;
      if (m.role == "left") l.left = m.ref;
      if (m.role == "right") l.right = m.ref;
      if (m.role == "centerline") l.centre = m.ref;
    }
    lanelets.push_back(l);
  }

  std::vector<CheckResult> out;
  const auto add = [&](const std::string& name, const std::string& what) -> CheckResult& {
    out.push_back({name, true, true, what, {}});
    return out.back();
  };

  {
    auto& c = add("ele", "every node has ele (node ids)");
    for (const auto& [id, n] : osm.nodes) {
      if (!n.has_ele) c.offenders.push_back(id);
    }
  }
  {
    auto& c = add("lanelet_tags", "every lanelet has subtype, location, one_way and (but a crosswalk or walkway) a numeric speed_limit (lanelet ids)");
    for (const auto& l : lanelets) {
      const auto& t = l.rel->tags;
      const std::string v = tag(t, "speed_limit");
      char* end = nullptr;
      const double speed = v.empty() ? 0.0 : std::strtod(v.c_str(), &end);
      const bool pedestrian = tag(t, "subtype") == "crosswalk" || tag(t, "subtype") == "walkway";
      const bool numeric = pedestrian || (!v.empty() && end && *end == '\0' && speed > 0.0);
      if (tag(t, "subtype").empty() || tag(t, "location").empty() || tag(t, "one_way").empty() || !numeric) {
        c.offenders.push_back(l.id);
      }
    }
  }
  {
    auto& c = add("lane_change", "lane_change=yes on dashed, =no on other lines between two same-direction lanes (way ids)");
    std::set<int64_t> lefts, rights;
    for (const auto& l : lanelets) {
      lefts.insert(l.left);
      rights.insert(l.right);
    }
    size_t shared = 0;
    for (int64_t w : lefts) {
      if (!rights.count(w) || !osm.ways.count(w)) continue;
      ++shared;
      const auto& t = osm.ways.at(w).tags;
      const std::string type = tag(t, "type");
      const bool dashed = (type == "line_thin" || type == "line_thick") && tag(t, "subtype") == "dashed";
      const std::string lc = tag(t, "lane_change");
      if (lc != (dashed ? "yes" : "no")) c.offenders.push_back(w);
    }
    c.applicable = shared > 0;
  }
  {
    auto& c = add("shared_borders", "neighbouring lanelets share one border line string, not two on top of each other (way ids)");
    std::set<int64_t> bounds;
    for (const auto& l : lanelets) {
      // Lanes only: a crosswalk lies across the lanes by design, an edge of it along a lane's
      // bound for a few metres is no neighbour of that lane.
      const std::string subtype = tag(l.rel->tags, "subtype");
      if (subtype == "crosswalk" || subtype == "walkway") continue;
      bounds.insert(l.left);
      bounds.insert(l.right);
    }
    // Grid of bound segments, 2 m cells.
    const double cell = 2.0;
    const auto key = [&](const Eigen::Vector2d& p) {
      return (static_cast<int64_t>(std::floor(p.x() / cell)) << 32) ^ (static_cast<int64_t>(std::floor(p.y() / cell)) & 0xffffffff);
    };
    std::unordered_map<int64_t, std::vector<int64_t>> grid;
    std::unordered_map<int64_t, Polyline> shapes;
    for (int64_t w : bounds) {
      shapes[w] = polyline(w);
      std::set<int64_t> cells;
      for (const auto& p : geo::pointsEvery(shapes[w], 0.5 * cell)) cells.insert(key(p));
      for (int64_t k : cells) grid[k].push_back(w);
    }
    // Two lanelets that merge (both bounds end at the same two nodes: two lanes into one) or split
    // (both start at the same two nodes) are not neighbours: their bounds converge there by design,
    // and a lanelet short enough to lie wholly on the other's converging end is no defect.
    std::set<std::pair<int64_t, int64_t>> converging;
    {
      const auto ends = [&](int64_t way, bool last) -> int64_t {
        const auto it = osm.ways.find(way);
        if (it == osm.ways.end() || it->second.refs.empty()) return 0;
        return last ? it->second.refs.back() : it->second.refs.front();
      };
      std::map<std::tuple<int64_t, int64_t, bool>, std::vector<const L*>> by_ends;
      for (const auto& l : lanelets) {
        if (!bounds.count(l.left)) continue;
        for (bool last : {false, true}) {
          const int64_t a = ends(l.left, last), b = ends(l.right, last);
          if (a != 0 && b != 0) by_ends[{a, b, last}].push_back(&l);
        }
      }
      for (const auto& [key, group] : by_ends) {
        for (size_t i = 0; i < group.size(); ++i) {
          for (size_t j = i + 1; j < group.size(); ++j) {
            for (int64_t a : {group[i]->left, group[i]->right}) {
              for (int64_t b : {group[j]->left, group[j]->right}) converging.insert({std::min(a, b), std::max(a, b)});
            }
          }
        }
      }
    }
    std::set<int64_t> bad;
    for (int64_t w : bounds) {
      const auto s = geo::pointsEvery(shapes[w], 1.0);
      if (s.size() < 3) continue;
      std::map<int64_t, size_t> close;  // other way -> samples within 0.1 m
      for (const auto& p : s) {
        std::set<int64_t> near;
        for (int dx = -1; dx <= 1; ++dx) {
          for (int dy = -1; dy <= 1; ++dy) {
            const auto it = grid.find(key(p + Eigen::Vector2d(dx * cell, dy * cell)));
            if (it != grid.end()) near.insert(it->second.begin(), it->second.end());
          }
        }
        for (int64_t o : near) {
          if (o != w && geo::distanceToPolyline(shapes[o], p) < 0.1) ++close[o];
        }
      }
      for (const auto& [o, n] : close) {
        if (n >= 0.9 * s.size() && !converging.count({std::min(w, o), std::max(w, o)})) {
          bad.insert(std::min(w, o));
          bad.insert(std::max(w, o));
        }
      }
    }
    c.offenders.assign(bad.begin(), bad.end());
  }
  {
    auto& c = add("bounds_apart", "a lanelet's left and right bound share no node (lanelet ids)");
    for (const auto& l : lanelets) {
      if (!osm.ways.count(l.left) || !osm.ways.count(l.right)) continue;
      const auto& a = osm.ways.at(l.left).refs;
      const std::set<int64_t> b(osm.ways.at(l.right).refs.begin(), osm.ways.at(l.right).refs.end());
      if (std::any_of(a.begin(), a.end(), [&](int64_t n) { return b.count(n) > 0; })) c.offenders.push_back(l.id);
    }
  }
  {
    auto& c = add("centerline_inside", "every centerline point lies inside its lanelet, 0.1 m slack (lanelet ids)");
    size_t with = 0;
    for (const auto& l : lanelets) {
      if (!l.centre) continue;
      ++with;
      Polyline left = polyline(l.left), right = polyline(l.right);
      if (left.size() < 2 || right.size() < 2) continue;
      const bool against = (left.front() - right.back()).norm() + (left.back() - right.front()).norm() <
                           (left.front() - right.front()).norm() + (left.back() - right.back()).norm();
      Polyline ring = left;
      if (against) {
        ring.insert(ring.end(), right.begin(), right.end());
      } else {
        ring.insert(ring.end(), right.rbegin(), right.rend());
      }
      Polyline closed = ring;
      closed.push_back(ring.front());
      for (const auto& p : polyline(*l.centre)) {
        if (!insidePolygon(ring, p) && geo::distanceToPolyline(closed, p) > 0.1) {
          c.offenders.push_back(l.id);
          break;
        }
      }
    }
    c.applicable = with > 0;
  }
  if (options.autoware) {
    auto& c = add("stop_line_refs", "every stop_line is referenced by a regulatory element (ref_line, or refers of a road_marking; way ids)");
    std::set<int64_t> referenced;
    for (const auto& [id, r] : osm.relations) {
      if (tag(r.tags, "type") != "regulatory_element") continue;
      const bool marking = tag(r.tags, "subtype") == "road_marking";  // Autoware: refers = the marking
      for (const auto& m : r.members) {
        if (m.kind == 'w' && (m.role == "ref_line" || (marking && m.role == "refers"))) referenced.insert(m.ref);
      }
    }
    size_t stops = 0;
    for (const auto& [id, w] : osm.ways) {
      if (tag(w.tags, "type") != "stop_line") continue;
      ++stops;
      if (!referenced.count(id)) c.offenders.push_back(id);
    }
    c.applicable = stops > 0;
  }
  {
    // The regulatory elements lanemap writes, as Lanelet2 and Autoware need them.
    auto& c = add("regulatory_elements",
                  "every traffic_sign, traffic_light and right_of_way element is referenced by a lanelet, its ref_line "
                  "(at most one) is a stop_line; a traffic light refers a type=traffic_light way, a traffic sign has "
                  "sign_type or a sign, a right of way has yield and right_of_way lanelets (relation ids)");
    std::set<int64_t> used;
    for (const auto& l : lanelets) {
      for (const auto& m : l.rel->members) {
        if (m.kind == 'r' && m.role == "regulatory_element") used.insert(m.ref);
      }
    }
    size_t n = 0;
    for (const auto& [id, r] : osm.relations) {
      const std::string sub = tag(r.tags, "subtype");
      if (tag(r.tags, "type") != "regulatory_element" ||
          (sub != "traffic_sign" && sub != "traffic_light" && sub != "right_of_way")) {
        continue;
      }
      ++n;
      size_t ref_lines = 0, lights = 0, signs = 0, yields = 0, priorities = 0;
      bool ok = used.count(id) > 0;
      for (const auto& m : r.members) {
        const auto w = m.kind == 'w' ? osm.ways.find(m.ref) : osm.ways.end();
        const std::string wtype = w != osm.ways.end() ? tag(w->second.tags, "type") : "";
        if (m.role == "ref_line") {
          ++ref_lines;
          ok = ok && wtype == "stop_line";
        }
        if (m.role == "refers") {
          lights += wtype == "traffic_light";
          signs += wtype == "traffic_sign";
        }
        if (m.kind == 'r' && m.role == "yield") ++yields;
        if (m.kind == 'r' && m.role == "right_of_way") ++priorities;
      }
      ok = ok && ref_lines <= 1;
      if (sub == "traffic_light") ok = ok && lights > 0;
      if (sub == "traffic_sign") ok = ok && (signs > 0 || !tag(r.tags, "sign_type").empty());
      if (sub == "right_of_way") ok = ok && yields > 0 && priorities > 0;
      if (!ok) c.offenders.push_back(id);
    }
    c.applicable = n > 0;
  }
  if (options.autoware) {
    auto& c = add("crosswalk_refs",
                  "every crosswalk lanelet is the refers of a crosswalk regulatory element that a road lanelet "
                  "references (Autoware vm-05-01; lanelet ids)");
    std::set<int64_t> used;
    for (const auto& l : lanelets) {
      for (const auto& m : l.rel->members) {
        if (m.kind == 'r' && m.role == "regulatory_element") used.insert(m.ref);
      }
    }
    std::set<int64_t> referred;
    for (const auto& [id, r] : osm.relations) {
      if (tag(r.tags, "type") != "regulatory_element" || tag(r.tags, "subtype") != "crosswalk" || !used.count(id)) continue;
      for (const auto& m : r.members) {
        if (m.kind == 'r' && m.role == "refers") referred.insert(m.ref);
      }
    }
    size_t n = 0;
    for (const auto& l : lanelets) {
      if (tag(l.rel->tags, "subtype") != "crosswalk") continue;
      ++n;
      if (!referred.count(l.id)) c.offenders.push_back(l.id);
    }
    c.applicable = n > 0;
  }
  {
    auto& c = add("one_lanelet_per_intersection_path",
                  "no intersection lanelet is followed by another of the same intersection (lanelet ids; lanemap sidecar)");
    c.applicable = have_sidecar && !intersection_of.empty();
    if (c.applicable) {
      // Successors: lanelets whose bounds start on the nodes where this one's end.
      std::map<std::pair<int64_t, int64_t>, std::vector<int64_t>> by_start;
      const auto ends = [&](const L& l, bool start) -> std::pair<int64_t, int64_t> {
        const auto& a = osm.ways.at(l.left).refs;
        const auto& b = osm.ways.at(l.right).refs;
        return start ? std::make_pair(a.front(), b.front()) : std::make_pair(a.back(), b.back());
      };
      for (const auto& l : lanelets) {
        if (osm.ways.count(l.left) && osm.ways.count(l.right)) by_start[ends(l, true)].push_back(l.id);
      }
      for (const auto& l : lanelets) {
        const auto it = intersection_of.find(l.id);
        if (it == intersection_of.end() || !osm.ways.count(l.left) || !osm.ways.count(l.right)) continue;
        const auto next = by_start.find(ends(l, false));
        if (next == by_start.end()) continue;
        for (int64_t n : next->second) {
          const auto jt = intersection_of.find(n);
          if (jt != intersection_of.end() && jt->second == it->second) {
            c.offenders.push_back(l.id);
            break;
          }
        }
      }
    }
  }
  if (options.autoware) {
    auto& c = add("turn_direction", "every intersection lanelet has turn_direction straight|left|right (lanelet ids)");
    size_t n = 0;
    for (const auto& l : lanelets) {
      const std::string t = tag(l.rel->tags, "turn_direction");
      const bool intersection = have_sidecar ? intersection_of.count(l.id) > 0 : !t.empty();
      if (!intersection) continue;
      ++n;
      if (t != "straight" && t != "left" && t != "right") c.offenders.push_back(l.id);
    }
    c.applicable = n > 0;
    auto& p = add("projector_info", "map_projector_info.yaml beside the map");
    const auto info = std::filesystem::path(path).parent_path() / "map_projector_info.yaml";
    const std::string text = readFile(info.string()).value_or(std::string());
    if (text.find("projector_type:") == std::string::npos) p.passed = false;
  }
  for (auto& c : out) {
    if (!c.offenders.empty()) c.passed = false;
  }
  return out;
}

}  // namespace lanemap::io
