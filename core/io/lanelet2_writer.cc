// Lanelet2 OSM writer for map::LaneMap (see lanelet2.h for the conventions).

#include "core/geo/polyline.h"
#include "core/io/lanelet2.h"
#include "core/io/lanelet2_internal.h"
#include "core/io/xml_escape.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <regex>
#include <set>
#include <unordered_map>
#include <unordered_set>

namespace lanemap::io {

using map::LaneletKind;
using map::LaneMap;
using map::LineType;
using map::TurnDirection;
using lanelet2_internal::fnv1a64;
using lanelet2_internal::hex64;
using lanelet2_internal::kSidecarVersion;
using geo::polylineLength;
using lanelet2_internal::readAll;
using lanelet2_internal::sidecarHashOf;

namespace {

// Writer: points closer than this share a node. Lanelet2's points_too_close limit is 5 cm,
// measured by lanelet2_validate in UTM, whose scale factor is 0.9996 near a zone's central
// meridian: two nodes 5.00-5.02 cm apart here are under 5 cm there (a fused West Oakland map had
// 134 such warnings). 5.01 cm keeps every pair written at 5.008 cm or more in UTM.
constexpr double kNodeMergeDistanceM = 0.0501;
// Points closer than this are the same point (a border two lines share drawn twice).
constexpr double kNodeSameM = 0.001;
// Lanelet2's validator warns where a bound turns tighter (mapping.curvature_too_big).
constexpr double kMaxCurvature = 0.5;
constexpr double kStraightTurnRad = 0.5236;    // turn_direction: heading change under 30 deg

// v with `decimals` digits after the point, as printf's "%.Nf" writes it (std::to_chars with a
// precision is specified so, in the C locale; it is several times faster than snprintf).
void appendFixed(std::string& out, double v, int decimals) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed, decimals);
  if (r.ec != std::errc()) throw std::runtime_error("Lanelet2 writer: cannot format a number");
  out.append(buf, r.ptr);
}
std::string formatFixed(double v, int decimals) {
  std::string s;
  appendFixed(s, v, decimals);
  return s;
}

struct OsmLineTags {
  const char* type;
  const char* subtype;  // nullptr: none
};

OsmLineTags osmTagsOf(LineType t) {
  switch (t) {
    case LineType::kDashed: return {"line_thin", "dashed"};
    case LineType::kSolid: return {"line_thin", "solid"};
    case LineType::kSolidSolid: return {"line_thin", "solid_solid"};
    case LineType::kCurb: return {"curbstone", "high"};
    case LineType::kVirtual: return {"virtual", nullptr};
    case LineType::kStopLine: return {"stop_line", nullptr};
  }
  return {"virtual", nullptr};
}

const char* turnTag(TurnDirection t) {
  switch (t) {
    case TurnDirection::kStraight: return "straight";
    case TurnDirection::kLeft: return "left";
    case TurnDirection::kRight: return "right";
    case TurnDirection::kNone: break;
  }
  return nullptr;
}

// Nodes of the file: one per distinct point (points closer than the merge distance share a node),
// ids given in order of first use from `next_id` on.
class NodeTable {
 public:
  explicit NodeTable(int64_t first_id) : first_id_(first_id), next_id_(first_id), slots_(1024) {}

  // The first node, in the order of the 3x3 cells around p and then of insertion, closer than the
  // merge distance; else a new one.
  int64_t idFor(const Eigen::Vector3d& p) {
    const int64_t index = nearIndex(p);
    return index >= 0 ? ids_[index] : add(p);
  }

  // The node idFor would merge p into, and how far it lies from p; nullopt when p gets a new one.
  std::optional<std::pair<int64_t, double>> merged(const Eigen::Vector3d& p) const {
    const int64_t index = nearIndex(p);
    if (index < 0) return std::nullopt;
    return std::make_pair(ids_[index], (points_[index] - p).norm());
  }

  // A node of its own for p, merged with none (a line shorter than the merge distance keeps 2).
  int64_t add(const Eigen::Vector3d& p) {
    const int64_t index = static_cast<int64_t>(points_.size());
    Slot& cell = insert(cellOf(p.x()), cellOf(p.y()));
    if (cell.head < 0) {
      cell.head = index;
    } else {
      next_[cell.tail] = index;
    }
    cell.tail = index;
    next_.push_back(-1);
    points_.push_back(p);
    ids_.push_back(next_id_);
    return next_id_++;
  }

  size_t size() const { return points_.size(); }

  int64_t nearIndex(const Eigen::Vector3d& p) const {
    const int64_t cx = cellOf(p.x()), cy = cellOf(p.y());
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const Slot* cell = find(cx + dx, cy + dy);
        if (!cell) continue;
        for (int64_t index = cell->head; index >= 0; index = next_[index]) {
          if ((points_[index] - p).norm() < kNodeMergeDistanceM) return index;
        }
      }
    }
    return -1;
  }
  int64_t id(size_t i) const { return ids_[i]; }
  const Eigen::Vector3d& point(size_t i) const { return points_[i]; }
  const Eigen::Vector3d& pointOf(int64_t id) const { return points_[static_cast<size_t>(id - first_id_)]; }

 private:
  // A cell of the grid (cell size = merge distance) and its points as a list through next_, in
  // insertion order. The cells live in an open-addressing table (linear probing, at most half
  // full): a lookup is one or two cache lines, where a node-based map took several.
  struct Slot {
    int64_t cx = 0, cy = 0;
    int64_t head = -1, tail = -1;  // head < 0: an empty slot
  };
  static int64_t cellOf(double v) { return static_cast<int64_t>(std::floor(v / kNodeMergeDistanceM)); }
  static uint64_t hashOf(int64_t cx, int64_t cy) {
    uint64_t h = static_cast<uint64_t>(cx) * 0x9E3779B97F4A7C15ull ^ (static_cast<uint64_t>(cy) + 0x632BE59BD9B4E019ull);
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 32);
  }
  const Slot* find(int64_t cx, int64_t cy) const {
    const size_t mask = slots_.size() - 1;
    for (size_t i = hashOf(cx, cy) & mask;; i = (i + 1) & mask) {
      const Slot& s = slots_[i];
      if (s.head < 0) return nullptr;
      if (s.cx == cx && s.cy == cy) return &s;
    }
  }
  Slot& insert(int64_t cx, int64_t cy) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    const size_t mask = slots_.size() - 1;
    for (size_t i = hashOf(cx, cy) & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (s.head < 0) {
        ++used_;
        s.cx = cx;
        s.cy = cy;
        return s;  // the caller links its first point
      }
      if (s.cx == cx && s.cy == cy) return s;
    }
  }
  void grow() {
    std::vector<Slot> old(slots_.size() * 2);
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& s : old) {
      if (s.head < 0) continue;
      size_t i = hashOf(s.cx, s.cy) & mask;
      while (slots_[i].head >= 0) i = (i + 1) & mask;
      slots_[i] = s;
    }
  }
  int64_t first_id_;
  int64_t next_id_;
  std::vector<Slot> slots_;  // size a power of 2
  size_t used_ = 0;
  std::vector<int64_t> next_;  // the next point of the same cell, -1 at its end
  std::vector<Eigen::Vector3d> points_;
  std::vector<int64_t> ids_;
};

// Which OSM id every line and lanelet gets.
struct IdPlan {
  std::unordered_map<int64_t, int64_t> way_of_line;
  std::unordered_map<int64_t, int64_t> relation_of_lanelet;
  std::unordered_map<int64_t, int64_t> relation_of_regulatory;  // RegulatoryElement id -> relation
  std::unordered_map<int64_t, int64_t> relation_of_crosswalk;   // Crosswalk id -> lanelet relation
  int64_t next_free = 1;
};

IdPlan planIds(const LaneMap& map) {
  IdPlan plan;
  std::set<int64_t> used;
  bool keep = true;
  int64_t max_id = 0;
  auto take = [&](int64_t id) {
    keep = keep && id > 0 && used.insert(id).second;
    max_id = std::max(max_id, id);
  };
  for (const auto& l : map.lines) take(l.id);
  for (const auto& ll : map.lanelets) take(ll.id);
  for (const auto& r : map.regulatory_elements) take(r.id);
  for (const auto& c : map.crosswalks) take(c.id);
  int64_t next = 1;
  for (const auto& l : map.lines) plan.way_of_line[l.id] = keep ? l.id : next++;
  for (const auto& ll : map.lanelets) plan.relation_of_lanelet[ll.id] = keep ? ll.id : next++;
  for (const auto& r : map.regulatory_elements) plan.relation_of_regulatory[r.id] = keep ? r.id : next++;
  for (const auto& c : map.crosswalks) plan.relation_of_crosswalk[c.id] = keep ? c.id : next++;
  plan.next_free = keep ? max_id + 1 : next;
  return plan;
}

void validateForWriting(const LaneMap& map, const Lanelet2WriteOptions& options,
                        const std::string& name) {
  const auto fail = [&](const std::string& what) {
    throw Lanelet2Error("cannot write Lanelet2 map '" + name + "': " + what);
  };
  std::unordered_map<int64_t, const map::LineString*> lines;
  for (const auto& l : map.lines) {
    if (!lines.emplace(l.id, &l).second) fail("duplicate line string id " + std::to_string(l.id));
    if (l.points.empty()) fail("line string " + std::to_string(l.id) + " has no point");
    for (const auto& p : l.points) {
      if (!p.allFinite()) fail("line string " + std::to_string(l.id) + " has a non-finite point");
    }
  }
  std::unordered_set<int64_t> lanelet_ids;
  for (const auto& ll : map.lanelets) {
    const std::string what = "lanelet " + std::to_string(ll.id);
    if (!lanelet_ids.insert(ll.id).second) fail("duplicate lanelet id " + std::to_string(ll.id));
    const auto left = lines.find(ll.left_id);
    const auto right = lines.find(ll.right_id);
    if (left == lines.end()) fail(what + " refers to missing left bound " + std::to_string(ll.left_id));
    if (right == lines.end()) fail(what + " refers to missing right bound " + std::to_string(ll.right_id));
    if (ll.left_id == ll.right_id) fail(what + " has the same line string on both sides");
    if (left->second->points.size() < 2 || right->second->points.size() < 2) {
      fail(what + " has a bound with fewer than 2 points");
    }
    if (ll.stop_line_id && !lines.count(*ll.stop_line_id)) {
      fail(what + " refers to missing stop line " + std::to_string(*ll.stop_line_id));
    }
    for (const auto& p : ll.centre) {
      if (!p.allFinite()) fail(what + " has a non-finite centre point");
    }
    if (options.check_orientation) {
      const std::string problem = orientationProblem(ll, *left->second, *right->second);
      if (!problem.empty()) fail(problem);
    }
  }
  std::unordered_set<int64_t> element_ids;
  for (const auto& r : map.regulatory_elements) {
    const std::string what = "regulatory element " + std::to_string(r.id);
    if (!element_ids.insert(r.id).second) fail("duplicate regulatory element id " + std::to_string(r.id));
    const auto stop = lines.find(r.stop_line_id);
    if (stop == lines.end()) fail(what + " refers to missing stop line " + std::to_string(r.stop_line_id));
    if (stop->second->points.size() < 2) fail(what + ": its stop line has fewer than 2 points");
    if (r.lanelets.empty()) fail(what + " applies to no lanelet");
    for (const auto* ids : {&r.lanelets, &r.priority}) {
      for (int64_t id : *ids) {
        if (!lanelet_ids.count(id)) fail(what + " refers to missing lanelet " + std::to_string(id));
      }
    }
    if (r.kind == map::RegulatoryKind::kTrafficLight) {
      if (r.light.size() < 2) fail(what + " (traffic light) has no light line of 2 points");
      for (const auto& p : r.light) {
        if (!p.allFinite()) fail(what + " has a non-finite light point");
      }
    }
  }
  for (const auto& c : map.crosswalks) {
    const std::string what = "crosswalk " + std::to_string(c.id);
    if (!element_ids.insert(c.id).second) fail("duplicate crosswalk id " + std::to_string(c.id));
    if (c.left.size() < 2 || c.right.size() < 2) fail(what + " has an edge with fewer than 2 points");
    for (const auto* edge : {&c.left, &c.right}) {
      for (const auto& p : *edge) {
        if (!p.allFinite()) fail(what + " has a non-finite point");
      }
    }
    for (int64_t id : c.crossing) {
      if (!lanelet_ids.count(id)) fail(what + " refers to missing lanelet " + std::to_string(id));
    }
  }
}

void appendTag(std::string& out, const std::string& k, const std::string& v) {
  out += "    <tag k=\"" + escapeXml(k) + "\" v=\"" + escapeXml(v) + "\"/>\n";
}

// appendTag of a number with `decimals` digits after the point (a key that needs no escaping),
// without a temporary string: a city's truth has millions of them.
void appendFixedTag(std::string& out, const char* k, double v, int decimals) {
  out += "    <tag k=\"";
  out += k;
  out += "\" v=\"";
  appendFixed(out, v, decimals);
  out += "\"/>\n";
}

// Menger curvature of the plane triangle a, b, c (1 / the radius of the circle through them).
double curvatureXy(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector2d u = (b - a).head<2>(), v = (c - b).head<2>(), w = (c - a).head<2>();
  const double denom = u.norm() * v.norm() * w.norm();
  return denom > 1e-12 ? 2.0 * std::abs(u.x() * v.y() - u.y() * v.x()) / denom : 0.0;
}

// A way's node ids, without consecutive repeats (points < 5 cm apart collapse into one node). A
// line of 2 or more points keeps 2 nodes at least: its last point gets a node of its own.
std::vector<int64_t> wayNodes(NodeTable& nodes, const std::vector<Eigen::Vector3d>& pts) {
  std::vector<int64_t> refs;
  for (size_t k = 0; k < pts.size(); ++k) {
    const Eigen::Vector3d& p = pts[k];
    // An inner point merged into another line's node moves by up to the merge distance. Between
    // points 0.5 m apart that can bend the line past Lanelet2's curvature limit (two connections'
    // borders shaped by the car's paths, running within 5 cm of each other for a stretch): such a
    // point is left out instead (the line runs straight past it). A line's ends always merge.
    if (k > 0 && k + 1 < pts.size() && !refs.empty()) {
      if (const auto m = nodes.merged(p); m && m->second > kNodeSameM && m->first != refs.back()) {
        const Eigen::Vector3d& q = nodes.pointOf(m->first);
        const auto mn = nodes.merged(pts[k + 1]);
        const Eigen::Vector3d next = mn ? nodes.pointOf(mn->first) : pts[k + 1];
        const Eigen::Vector3d& last = nodes.pointOf(refs.back());
        const auto bends = [&](const Eigen::Vector3d& x) {
          return std::max(curvatureXy(last, x, next),
                          refs.size() >= 2 ? curvatureXy(nodes.pointOf(refs[refs.size() - 2]), last, x) : 0.0);
        };
        const double merged_bend = bends(q);
        if (merged_bend > kMaxCurvature && merged_bend > bends(p)) continue;
      }
    }
    const int64_t id = nodes.idFor(p);
    if (refs.empty() || refs.back() != id) refs.push_back(id);
  }
  if (refs.size() == 1 && pts.size() >= 2) refs.push_back(nodes.add(pts.back()));
  return refs;
}

void appendWay(std::string& out, int64_t id, const std::vector<int64_t>& refs,
               const std::vector<std::pair<std::string, std::string>>& tags) {
  out += "  <way id=\"" + std::to_string(id) + "\" version=\"1\" visible=\"true\">\n";
  for (int64_t r : refs) {
    out += "    <nd ref=\"";
    out += std::to_string(r);
    out += "\"/>\n";
  }
  for (const auto& [k, v] : tags) appendTag(out, k, v);
  out += "  </way>\n";
}

double roundTo(double v, double step) { return std::round(v / step) * step; }

// The turn of an intersection lanelet from its centre line: the heading change between its first
// and last 2 m (straight below 30 degrees); kNone when the centre is too short to tell.
TurnDirection turnFromCentre(const std::vector<Eigen::Vector3d>& c) {
  if (c.size() < 2 || polylineLength(c) < 0.5) return TurnDirection::kNone;
  const auto direction = [&](bool at_start) {
    Eigen::Vector2d d = Eigen::Vector2d::Zero();
    double len = 0.0;
    for (size_t k = 1; k < c.size() && len < 2.0; ++k) {
      const size_t i = at_start ? k - 1 : c.size() - 1 - k;
      const Eigen::Vector2d seg = (c[i + 1] - c[i]).head<2>();
      d += seg;
      len += seg.norm();
    }
    return d;
  };
  const Eigen::Vector2d a = direction(true), b = direction(false);
  if (a.norm() <= 0.0 || b.norm() <= 0.0) return TurnDirection::kNone;
  const double turn = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
  if (std::abs(turn) < kStraightTurnRad) return TurnDirection::kStraight;
  return turn > 0.0 ? TurnDirection::kLeft : TurnDirection::kRight;
}

std::string formatSpeed(double kmh) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.0f", std::max(1.0, kmh));
  return buf;
}

// `lane_change` of the lines shared by two lanes of one direction (the right bound of one is the
// left bound of the other): yes on a dashed line, no on any other; nothing on other lines.
std::unordered_map<int64_t, bool> laneChangeOfSharedLines(const LaneMap& map) {
  std::unordered_map<int64_t, int> as_left, as_right;
  for (const auto& ll : map.lanelets) {
    ++as_left[ll.left_id];
    ++as_right[ll.right_id];
  }
  std::unordered_map<int64_t, bool> out;
  for (const auto& l : map.lines) {
    if (l.type == LineType::kStopLine) continue;
    if (as_left.count(l.id) && as_right.count(l.id)) out[l.id] = l.type == LineType::kDashed;
  }
  return out;
}

// The lanelets by id and each lanelet's predecessors (the lanelets listing it as successor), for
// lookups in one pass over the map.
struct LaneletIndex {
  explicit LaneletIndex(const LaneMap& map) {
    for (const auto& ll : map.lanelets) {
      by_id.emplace(ll.id, &ll);
      for (int64_t s : ll.successors) predecessors[s].push_back(&ll);
    }
  }
  std::unordered_map<int64_t, const map::Lanelet*> by_id;  // the first lanelet of each id
  std::unordered_map<int64_t, std::vector<const map::Lanelet*>> predecessors;
};

double speedLimitOf(const map::Lanelet& ll, const LaneletIndex& index, const Lanelet2WriteOptions& o) {
  const auto& by_road = o.speed_limit_kmh_by_road;
  if (const auto it = by_road.find(ll.road_id); ll.road_id >= 0 && it != by_road.end()) return it->second;
  if (ll.kind != LaneletKind::kIntersection || by_road.empty()) return o.default_speed_limit_kmh;
  // An intersection lanelet: the slower of the roads it joins (predecessor and successors).
  double v = std::numeric_limits<double>::infinity();
  const auto consider = [&](const map::Lanelet& other) {
    const auto it = by_road.find(other.road_id);
    if (other.road_id >= 0 && it != by_road.end()) v = std::min(v, it->second);
  };
  if (const auto it = index.predecessors.find(ll.id); it != index.predecessors.end()) {
    for (const auto* other : it->second) consider(*other);
  }
  for (int64_t s : ll.successors) {
    if (const auto it = index.by_id.find(s); it != index.by_id.end()) consider(*it->second);
  }
  return std::isfinite(v) ? v : o.default_speed_limit_kmh;
}

}  // namespace

std::optional<double> parseMaxspeedKmh(const std::string& value) {
  static const std::regex re(R"(^\s*([0-9]+(?:\.[0-9]+)?)\s*(km/h|kmh|kph|mph|knots)?\s*$)");
  std::smatch m;
  if (!std::regex_match(value, m, re)) return std::nullopt;
  const double v = std::stod(m[1].str());
  if (!(v > 0.0)) return std::nullopt;
  const std::string unit = m[2].str();
  if (unit == "mph") return v * 1.609344;
  if (unit == "knots") return v * 1.852;
  return v;
}

Lanelet2Document toLanelet2Document(const LaneMap& map, const Lanelet2WriteOptions& options,
                                    const std::string& name) {
  validateForWriting(map, options, name);
  const geo::LocalFrame frame({map.origin_lat, map.origin_lon, map.origin_alt});
  IdPlan ids = planIds(map);

  // Centre line ways get the ids right after the lines' and lanelets' ids; nodes come after.
  std::unordered_map<int64_t, int64_t> centre_way_of_lanelet;
  if (options.write_centre_lines) {
    for (const auto& ll : map.lanelets) {
      if (ll.centre.size() >= 2) centre_way_of_lanelet[ll.id] = ids.next_free++;
    }
  }
  // A stop line becomes Autoware's `road_marking` regulatory element (a stop line with no sign
  // or light of its own: the camera sees the paint only), referenced by the lanelet it ends.
  // Only for a stop line that no regulatory element of the map (sign, light) has as its ref_line.
  std::set<int64_t> ruled_stop_lines;
  for (const auto& r : map.regulatory_elements) ruled_stop_lines.insert(r.stop_line_id);
  std::map<int64_t, int64_t> marking_of_stop_line;  // line id -> regulatory element id
  for (const auto& ll : map.lanelets) {
    if (!options.stop_line_road_markings) break;
    if (ll.stop_line_id && !ruled_stop_lines.count(*ll.stop_line_id) && !marking_of_stop_line.count(*ll.stop_line_id)) {
      marking_of_stop_line[*ll.stop_line_id] = ids.next_free++;
    }
  }
  // Ways of the regulatory elements and crosswalks: a traffic light's line, a crosswalk's two
  // edges (and in Autoware's layout its polygon and regulatory element).
  std::unordered_map<int64_t, int64_t> light_way;  // RegulatoryElement id -> way
  for (const auto& r : map.regulatory_elements) {
    if (r.kind == map::RegulatoryKind::kTrafficLight) light_way[r.id] = ids.next_free++;
  }
  struct CrosswalkIds {
    int64_t left = 0, right = 0, polygon = 0, element = 0;
  };
  std::unordered_map<int64_t, CrosswalkIds> crosswalk_ids;
  for (const auto& c : map.crosswalks) {
    CrosswalkIds& w = crosswalk_ids[c.id];
    w.left = ids.next_free++;
    w.right = ids.next_free++;
    if (options.crosswalk_regulatory_elements) {
      w.polygon = ids.next_free++;
      w.element = ids.next_free++;
    }
  }
  // The regulatory elements each lanelet references (Lanelet2: role regulatory_element).
  std::unordered_map<int64_t, std::vector<int64_t>> elements_of_lanelet;  // lanelet id -> relations
  for (const auto& r : map.regulatory_elements) {
    const int64_t rel = ids.relation_of_regulatory.at(r.id);
    std::set<int64_t> seen;
    for (const auto* v : {&r.lanelets, &r.priority}) {
      for (int64_t id : *v) {
        if (seen.insert(id).second) elements_of_lanelet[id].push_back(rel);
      }
    }
  }
  for (const auto& c : map.crosswalks) {
    if (!options.crosswalk_regulatory_elements) break;
    for (int64_t id : c.crossing) elements_of_lanelet[id].push_back(crosswalk_ids.at(c.id).element);
  }
  const int64_t first_node_id = ids.next_free;
  NodeTable nodes(first_node_id);
  const auto lane_change = laneChangeOfSharedLines(map);

  std::string ways_xml;
  for (const auto& line : map.lines) {
    const OsmLineTags t = osmTagsOf(line.type);
    std::vector<std::pair<std::string, std::string>> tags{{"type", t.type}};
    if (t.subtype) tags.emplace_back("subtype", t.subtype);
    if (const auto it = lane_change.find(line.id); it != lane_change.end()) {
      tags.emplace_back("lane_change", it->second ? "yes" : "no");
    }
    appendWay(ways_xml, ids.way_of_line.at(line.id), wayNodes(nodes, line.points), tags);
  }
  for (const auto& ll : map.lanelets) {
    const auto it = centre_way_of_lanelet.find(ll.id);
    if (it == centre_way_of_lanelet.end()) continue;
    // type=virtual: Lanelet2 knows no `centerline` type; the member role makes it the centre line.
    appendWay(ways_xml, it->second, wayNodes(nodes, ll.centre), {{"type", "virtual"}});
  }
  for (const auto& r : map.regulatory_elements) {
    const auto it = light_way.find(r.id);
    if (it == light_way.end()) continue;
    // Lanelet2/Autoware: the light's bottom edge, `height` the light's own height.
    appendWay(ways_xml, it->second, wayNodes(nodes, r.light),
              {{"type", "traffic_light"}, {"subtype", "red_yellow_green"}, {"height", formatFixed(r.light_height_m, 2)}});
  }
  for (const auto& c : map.crosswalks) {
    const CrosswalkIds& w = crosswalk_ids.at(c.id);
    // The edges of the crossing: no paint of their own (the stripes lie between them).
    appendWay(ways_xml, w.left, wayNodes(nodes, c.left), {{"type", "virtual"}});
    appendWay(ways_xml, w.right, wayNodes(nodes, c.right), {{"type", "virtual"}});
    if (w.polygon) {
      std::vector<Eigen::Vector3d> ring = c.left;
      ring.insert(ring.end(), c.right.rbegin(), c.right.rend());
      std::vector<int64_t> refs = wayNodes(nodes, ring);
      if (refs.size() > 2 && refs.front() != refs.back()) refs.push_back(refs.front());
      appendWay(ways_xml, w.polygon, refs, {{"type", "crosswalk_polygon"}, {"area", "yes"}});
    }
  }

  nlohmann::ordered_json lanelets_json = nlohmann::ordered_json::object();
  std::string rel_xml;
  const LaneletIndex lanelet_index(map);
  for (const auto& ll : map.lanelets) {
    const int64_t rel_id = ids.relation_of_lanelet.at(ll.id);
    rel_xml += "  <relation id=\"" + std::to_string(rel_id) + "\" version=\"1\" visible=\"true\">\n";
    const auto member = [&](int64_t way, const char* role) {
      rel_xml += "    <member type=\"way\" ref=\"" + std::to_string(way) + "\" role=\"" + role + "\"/>\n";
    };
    member(ids.way_of_line.at(ll.left_id), "left");
    member(ids.way_of_line.at(ll.right_id), "right");
    const auto centre = centre_way_of_lanelet.find(ll.id);
    if (centre != centre_way_of_lanelet.end()) member(centre->second, "centerline");
    const auto relation_member = [&](int64_t rel, const char* role) {
      rel_xml += "    <member type=\"relation\" ref=\"" + std::to_string(rel) + "\" role=\"" + role + "\"/>\n";
    };
    if (ll.stop_line_id && marking_of_stop_line.count(*ll.stop_line_id)) {
      relation_member(marking_of_stop_line.at(*ll.stop_line_id), "regulatory_element");
    }
    if (const auto els = elements_of_lanelet.find(ll.id); els != elements_of_lanelet.end()) {
      for (int64_t rel : els->second) relation_member(rel, "regulatory_element");
    }
    appendTag(rel_xml, "type", "lanelet");
    appendTag(rel_xml, "subtype", "road");
    appendTag(rel_xml, "location", options.location);
    appendTag(rel_xml, "one_way", "yes");
    appendTag(rel_xml, "speed_limit", formatSpeed(speedLimitOf(ll, lanelet_index, options)));
    TurnDirection turn = ll.turn;
    if (turn == TurnDirection::kNone && ll.kind == LaneletKind::kIntersection) turn = turnFromCentre(ll.centre);
    if (const char* t = turnTag(turn); t && options.turn_direction_tags) appendTag(rel_xml, "turn_direction", t);
    rel_xml += "  </relation>\n";

    nlohmann::ordered_json j;
    j["kind"] = ll.kind == LaneletKind::kIntersection ? "intersection" : "road";
    j["road_id"] = ll.road_id;
    j["from_node"] = ll.from_node;
    j["to_node"] = ll.to_node;
    j["intersection_id"] = ll.intersection_id;
    j["index_from_left"] = ll.index_from_left;
    if (ll.turn != TurnDirection::kNone) j["turn"] = turnTag(ll.turn);
    if (ll.stop_line_id) j["stop_line"] = ids.way_of_line.at(*ll.stop_line_id);
    // A road mapped as far as a drive went (issue 14) and the lane's confidence: lanemap's own,
    // here rather than as tags Lanelet2's validator would call unknown.
    if (ll.partial) j["partial"] = {{"station_m", ll.partial->station_m}, {"road_length_m", ll.partial->road_length_m}};
    if (ll.confidence) j["confidence"] = *ll.confidence;
    lanelets_json[std::to_string(rel_id)] = std::move(j);
  }

  nlohmann::ordered_json elements_json = nlohmann::ordered_json::object();
  for (const auto& r : map.regulatory_elements) {
    const int64_t rel = ids.relation_of_regulatory.at(r.id);
    rel_xml += "  <relation id=\"" + std::to_string(rel) + "\" version=\"1\" visible=\"true\">\n";
    const auto way_member = [&](int64_t way, const char* role) {
      rel_xml += "    <member type=\"way\" ref=\"" + std::to_string(way) + "\" role=\"" + role + "\"/>\n";
    };
    const auto lanelet_members = [&](const std::vector<int64_t>& v, const char* role) {
      for (int64_t id : v) {
        rel_xml += "    <member type=\"relation\" ref=\"" + std::to_string(ids.relation_of_lanelet.at(id)) +
                   "\" role=\"" + role + "\"/>\n";
      }
    };
    const bool right_of_way = r.kind == map::RegulatoryKind::kGiveWay && !r.priority.empty();
    if (r.kind == map::RegulatoryKind::kTrafficLight) way_member(light_way.at(r.id), "refers");
    if (right_of_way) {
      lanelet_members(r.priority, "right_of_way");
      lanelet_members(r.lanelets, "yield");
    }
    way_member(ids.way_of_line.at(r.stop_line_id), "ref_line");
    appendTag(rel_xml, "type", "regulatory_element");
    if (r.kind == map::RegulatoryKind::kTrafficLight) {
      appendTag(rel_xml, "subtype", "traffic_light");
    } else if (right_of_way) {
      appendTag(rel_xml, "subtype", "right_of_way");
    } else {
      // Lanelet2's TrafficSign takes its type from `sign_type` when it has no sign of its own
      // (the camera maps no sign); stop_sign is the value Autoware's stop line module looks for.
      appendTag(rel_xml, "subtype", "traffic_sign");
      appendTag(rel_xml, "sign_type", r.kind == map::RegulatoryKind::kStopSign ? "stop_sign" : "give_way");
    }
    rel_xml += "  </relation>\n";
    nlohmann::ordered_json j;
    j["kind"] = map::toString(r.kind);
    j["osm_node"] = r.osm_node;
    if (r.kind == map::RegulatoryKind::kTrafficLight) j["light_position"] = r.light_estimated ? "estimated" : "measured";
    elements_json[std::to_string(rel)] = std::move(j);
  }
  nlohmann::ordered_json crosswalks_json = nlohmann::ordered_json::object();
  for (const auto& c : map.crosswalks) {
    const CrosswalkIds& w = crosswalk_ids.at(c.id);
    const int64_t rel = ids.relation_of_crosswalk.at(c.id);
    rel_xml += "  <relation id=\"" + std::to_string(rel) + "\" version=\"1\" visible=\"true\">\n";
    rel_xml += "    <member type=\"way\" ref=\"" + std::to_string(w.left) + "\" role=\"left\"/>\n";
    rel_xml += "    <member type=\"way\" ref=\"" + std::to_string(w.right) + "\" role=\"right\"/>\n";
    appendTag(rel_xml, "type", "lanelet");
    appendTag(rel_xml, "subtype", "crosswalk");
    appendTag(rel_xml, "location", options.location);
    appendTag(rel_xml, "one_way", "no");
    rel_xml += "  </relation>\n";
    if (w.element) {
      // Autoware's crosswalk regulatory element (vector map requirement vm-05-01): refers = the
      // crosswalk lanelet, crosswalk_polygon = its area; the road lanelets under it reference it.
      rel_xml += "  <relation id=\"" + std::to_string(w.element) + "\" version=\"1\" visible=\"true\">\n";
      rel_xml += "    <member type=\"relation\" ref=\"" + std::to_string(rel) + "\" role=\"refers\"/>\n";
      rel_xml += "    <member type=\"way\" ref=\"" + std::to_string(w.polygon) + "\" role=\"crosswalk_polygon\"/>\n";
      appendTag(rel_xml, "type", "regulatory_element");
      appendTag(rel_xml, "subtype", "crosswalk");
      rel_xml += "  </relation>\n";
    }
    nlohmann::ordered_json j;
    j["road_id"] = c.road_id;
    std::vector<int64_t> crossing;
    for (int64_t id : c.crossing) crossing.push_back(ids.relation_of_lanelet.at(id));
    j["crossing"] = crossing;
    crosswalks_json[std::to_string(rel)] = std::move(j);
  }

  for (const auto& [line_id, reg_id] : marking_of_stop_line) {
    rel_xml += "  <relation id=\"" + std::to_string(reg_id) + "\" version=\"1\" visible=\"true\">\n";
    rel_xml += "    <member type=\"way\" ref=\"" + std::to_string(ids.way_of_line.at(line_id)) + "\" role=\"refers\"/>\n";
    appendTag(rel_xml, "type", "regulatory_element");
    appendTag(rel_xml, "subtype", "road_marking");
    rel_xml += "  </relation>\n";
  }

  Lanelet2Document doc;
  std::string& out = doc.osm;
  out.reserve(ways_xml.size() + rel_xml.size() + nodes.size() * 200 + 256);
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<osm version=\"0.6\" generator=\"lanemap\">\n";
  std::vector<double> local_xy;
  local_xy.reserve(2 * nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::Vector3d& p = nodes.point(i);
    const geo::LatLonAlt ll = enuToLatLonEle(frame, p);
    // Appended piece by piece: a million nodes in a city's truth.
    out += "  <node id=\"";
    out += std::to_string(nodes.id(i));
    out += "\" version=\"1\" visible=\"true\" lat=\"";
    appendFixed(out, ll.lat, 10);
    out += "\" lon=\"";
    appendFixed(out, ll.lon, 10);
    out += "\">\n";
    appendFixedTag(out, "ele", ll.alt, 4);
    if (options.local_xy_tags) {
      appendFixedTag(out, "local_x", p.x(), 4);
      appendFixedTag(out, "local_y", p.y(), 4);
    }
    out += "  </node>\n";
    local_xy.push_back(roundTo(p.x(), 1e-4));
    local_xy.push_back(roundTo(p.y(), 1e-4));
  }
  out += ways_xml;
  out += rel_xml;
  out += "</osm>\n";

  // The hash comes first: a reader looking for the sidecar of a renamed copy reads only the start.
  nlohmann::ordered_json side;
  side["osm_fnv1a64"] = hex64(fnv1a64(out));
  side["osm_bytes"] = out.size();
  side["lanemap_sidecar"] = kSidecarVersion;
  side["about"] = "lanemap metadata of a Lanelet2 map: lanelets by relation id; the nodes' ENU x/y (m) "
                  "in the frame of `origin`, node ids first_node_id, first_node_id + 1, ...";
  side["origin"] = {{"lat", map.origin_lat}, {"lon", map.origin_lon}, {"alt", map.origin_alt}};
  side["lanelets"] = std::move(lanelets_json);
  if (!map.regulatory_elements.empty()) side["regulatory_elements"] = std::move(elements_json);
  if (!map.crosswalks.empty()) side["crosswalks"] = std::move(crosswalks_json);
  side["first_node_id"] = first_node_id;
  side["local_xy"] = std::move(local_xy);
  doc.sidecar = side.dump() + "\n";
  return doc;
}

std::string toLanelet2Xml(const LaneMap& map, const Lanelet2WriteOptions& options,
                          const std::string& name) {
  return toLanelet2Document(map, options, name).osm;
}

std::string autowareProjectorInfo(const LaneMap& map) {
  return "# Autoware map projector: lanemap's ENU frame is GeographicLib's LocalCartesian at map_origin.\n"
         "projector_type: LocalCartesian\n"
         "vertical_datum: WGS84\n"
         "map_origin:\n"
         "  latitude: " + formatFixed(map.origin_lat, 10) + "\n"
         "  longitude: " + formatFixed(map.origin_lon, 10) + "\n"
         "  altitude: " + formatFixed(map.origin_alt, 4) + "\n";
}

void writeLanelet2(const LaneMap& map, const std::string& path, const Lanelet2WriteOptions& options) {
  const Lanelet2Document doc = toLanelet2Document(map, options, path);
  // The map and its sidecar are two files; each is written atomically, and the pair moves from the
  // old state to the new one without a moment where the map on disk has no sidecar of its own: the
  // new sidecar goes to MAP.next.lanemap.json first (the reader finds a sidecar by the map's hash
  // among the folder's *.lanemap.json), then the map, then the sidecar is renamed into place. A
  // crash before the map's rename leaves the old map with its old sidecar; after it, the new map
  // finds the new sidecar (under either name).
  const std::string sidecar = lanelet2SidecarPath(path);
  const std::string next = sidecar.substr(0, sidecar.size() - std::string(".lanemap.json").size()) + ".next.lanemap.json";
  if (options.write_sidecar) {
    // A write killed after the map's rename left the map's sidecar as MAP.next: put it in place
    // before MAP.next is reused, or the map on disk would lose its sidecar if this write is killed.
    std::error_code ec;
    if (std::filesystem::is_regular_file(next, ec) && std::filesystem::is_regular_file(path, ec) &&
        sidecarHashOf(next) == hex64(fnv1a64(readAll(path)))) {
      renameFileDurably(next, sidecar);
    }
    writeFileAtomically(next, doc.sidecar);
    try {
      writeFileAtomically(path, doc.osm);
    } catch (const IoError&) {  // e.g. a full disk: the old map and its sidecar stay, nothing else
      std::error_code ec;
      std::filesystem::remove(next, ec);
      throw;
    }
    renameFileDurably(next, sidecar);
  } else {
    removeFileDurably(next);  // no stale sidecar of an earlier version of the map
    removeFileDurably(sidecar);
    writeFileAtomically(path, doc.osm);
  }
  if (options.write_projector_info) {
    const auto dir = std::filesystem::path(path).parent_path();
    writeFileAtomically((dir / "map_projector_info.yaml").string(), autowareProjectorInfo(map));
  }
}

void writeLanelet2(const LaneMap& map, const std::string& path) {
  writeLanelet2(map, path, Lanelet2WriteOptions{});
}

void writeAutowareMapFolder(const LaneMap& map, const std::string& dir, const Lanelet2WriteOptions& options) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Lanelet2Error("cannot create map folder '" + dir + "': " + ec.message());
  Lanelet2WriteOptions o = options;
  o.write_projector_info = true;
  o.turn_direction_tags = true;
  o.stop_line_road_markings = true;
  o.crosswalk_regulatory_elements = true;
  writeLanelet2(map, (std::filesystem::path(dir) / "lanelet2_map.osm").string(), o);
}

}  // namespace lanemap::io
