// Lanelet2 OSM reader for map::LaneMap (see lanelet2.h for the conventions).

#include "core/geo/polyline.h"
#include "core/io/lanelet2.h"
#include "core/io/lanelet2_internal.h"
#include "core/osm/coordinate_guard.h"

#include <nlohmann/json.hpp>
#include <osmium/handler.hpp>
#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/relation.hpp>
#include <osmium/osm/way.hpp>
#include <osmium/visitor.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <set>
#include <unordered_map>
#include <unordered_set>

namespace lanemap::io {

using map::LaneletKind;
using map::LaneMap;
using map::LineType;
using map::TurnDirection;
using lanelet2_internal::Alignment;
using lanelet2_internal::fnv1a64;
using lanelet2_internal::hex64;
using lanelet2_internal::kSidecarVersion;
using lanelet2_internal::lanelet2Alignment;
using geo::polylineLength;
using lanelet2_internal::readAll;
using lanelet2_internal::sidecarHashOf;

namespace {

constexpr double kSuccessorDistanceM = 1e-2;   // reader: end/start points closer than 1 cm meet
constexpr double kLocalXyAgreementM = 0.05;    // local_x/y vs lat/lon: osmium keeps 1e-7 deg
                                               // (<= 1.1 cm); 5 cm leaves margin, an origin
                                               // shift of another map is far larger

// n points spread evenly by arc length from the first to the last point of `pts`.
std::vector<Eigen::Vector3d> resampleEvenly(const std::vector<Eigen::Vector3d>& pts, size_t n) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(n);
  const double total = polylineLength(pts);
  if (pts.size() < 2 || total <= 0.0) {
    out.assign(n, pts.empty() ? Eigen::Vector3d::Zero() : pts.front());
    return out;
  }
  size_t seg = 0;
  double seg_start = 0.0;  // arc length at pts[seg]
  for (size_t i = 0; i < n; ++i) {
    const double s = (n == 1) ? 0.0 : total * static_cast<double>(i) / static_cast<double>(n - 1);
    while (seg + 2 < pts.size() && seg_start + (pts[seg + 1] - pts[seg]).norm() < s) {
      seg_start += (pts[seg + 1] - pts[seg]).norm();
      ++seg;
    }
    const double seg_len = (pts[seg + 1] - pts[seg]).norm();
    const double t = seg_len > 0.0 ? std::clamp((s - seg_start) / seg_len, 0.0, 1.0) : 0.0;
    out.push_back(pts[seg] + t * (pts[seg + 1] - pts[seg]));
  }
  out.back() = pts.back();
  return out;
}

struct RawNode {
  double lat = 0.0, lon = 0.0;
  bool located = false;
  std::string ele, local_x, local_y;  // tag values, parsed when the node is used
};

struct RawWay {
  std::vector<int64_t> refs;
  std::string type, subtype, height;
};

struct RawMember {
  char kind = 'w';  // 'n', 'w', 'r'
  int64_t ref = 0;
  std::string role;
};

struct RawRelation {
  std::vector<RawMember> members;
  std::map<std::string, std::string> tags;
  std::string tag(const std::string& k) const {
    const auto it = tags.find(k);
    return it == tags.end() ? std::string() : it->second;
  }
};

struct RawOsm {
  std::unordered_map<int64_t, RawNode> nodes;
  std::unordered_map<int64_t, RawWay> ways;
  std::map<int64_t, RawRelation> relations;  // sorted: deterministic lanelet order
};

class Collector : public osmium::handler::Handler {
 public:
  explicit Collector(RawOsm& raw) : raw_(raw) {}

  void node(const osmium::Node& n) {
    RawNode& out = raw_.nodes[n.id()];
    if (n.location().valid()) {
      out.located = true;
      out.lat = n.location().lat_without_check();
      out.lon = n.location().lon_without_check();
    }
    if (const char* v = n.tags().get_value_by_key("ele")) out.ele = v;
    if (const char* v = n.tags().get_value_by_key("local_x")) out.local_x = v;
    if (const char* v = n.tags().get_value_by_key("local_y")) out.local_y = v;
  }

  void way(const osmium::Way& w) {
    RawWay& out = raw_.ways[w.id()];
    for (const auto& nr : w.nodes()) out.refs.push_back(nr.ref());
    if (const char* v = w.tags().get_value_by_key("type")) out.type = v;
    if (const char* v = w.tags().get_value_by_key("subtype")) out.subtype = v;
    if (const char* v = w.tags().get_value_by_key("height")) out.height = v;
  }

  void relation(const osmium::Relation& r) {
    RawRelation& out = raw_.relations[r.id()];
    for (const auto& m : r.members()) {
      RawMember rm;
      rm.kind = m.type() == osmium::item_type::node ? 'n' : m.type() == osmium::item_type::way ? 'w' : 'r';
      rm.ref = m.ref();
      rm.role = m.role();
      out.members.push_back(std::move(rm));
    }
    for (const auto& t : r.tags()) out.tags[t.key()] = t.value();
  }

 private:
  RawOsm& raw_;
};

RawOsm parseOsmFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw Lanelet2Error("cannot read Lanelet2 map '" + path + "': no such file");
  }
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Lanelet2Error("cannot read Lanelet2 map '" + path + "': not a regular file");
  }
  if (std::filesystem::file_size(path, ec) == 0) {
    throw Lanelet2Error("cannot read Lanelet2 map '" + path + "': empty file");
  }
  osm::refuseExponentCoordinate<Lanelet2Error>(path, "cannot read Lanelet2 map '" + path + "'");  // libosmium overflows on it
  RawOsm raw;
  try {
    osmium::io::Reader reader{osmium::io::File{path, "osm"}};
    Collector collector(raw);
    osmium::apply(reader, collector);
    reader.close();
  } catch (const std::exception& e) {
    throw Lanelet2Error("cannot read Lanelet2 map '" + path + "': " + e.what());
  }
  return raw;
}

double parseNumber(const std::string& text, const std::string& path, const std::string& what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(v)) {
    throw Lanelet2Error("malformed Lanelet2 map '" + path + "': " + what + " '" + text +
                        "' is not a number");
  }
  return v;
}

int64_t parseInteger(const std::string& text, const std::string& path, const std::string& what) {
  try {
    size_t used = 0;
    const long long v = std::stoll(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  throw Lanelet2Error("malformed Lanelet2 map '" + path + "': " + what + " '" + text +
                      "' is not an integer");
}

LineType lineTypeOf(const RawWay& w) {
  const std::string& t = w.type;
  const std::string& s = w.subtype;
  if (t == "line_thin" || t == "line_thick") {
    if (s == "dashed") return LineType::kDashed;
    if (s == "solid_solid") return LineType::kSolidSolid;
    return LineType::kSolid;  // solid, dashed_solid, solid_dashed (one side may not cross), none
  }
  if (t == "curbstone" || t == "road_border" || t == "fence" || t == "wall" ||
      t == "guard_rail" || t == "keepout" || t == "rail") {
    return LineType::kCurb;  // physical borders
  }
  if (t == "stop_line") return LineType::kStopLine;
  if (t == "bike_marking") return LineType::kDashed;
  if (t == "zig-zag") return LineType::kSolid;
  return LineType::kVirtual;  // virtual, pedestrian_marking, zebra_marking, untyped, unknown
}

TurnDirection turnOf(const std::string& v) {
  if (v == "straight") return TurnDirection::kStraight;
  if (v == "left") return TurnDirection::kLeft;
  if (v == "right") return TurnDirection::kRight;
  return TurnDirection::kNone;
}

// One bound of a lanelet as used by it, in its driving direction.
struct Bound {
  int64_t way_id = 0;
  bool reversed = false;  // relative to the way's node order
  std::vector<int64_t> node_ids;
  std::vector<Eigen::Vector3d> points;
  void reverse() {
    reversed = !reversed;
    std::reverse(node_ids.begin(), node_ids.end());
    std::reverse(points.begin(), points.end());
  }
};

struct ReadLanelet {
  map::Lanelet lanelet;
  Bound left, right;
  std::optional<int64_t> centre_way;
  std::optional<int64_t> stop_way;
};

// The kind of a regulatory element relation as lanemap models it; nullopt for any other element.
// Traffic signs: Autoware's stop_sign, Lanelet2's German (de206 stop, de205 give way) and US
// (usR1-1, usR1-2) sign types, from `sign_type` or the subtype of the first `refers` sign.
std::optional<map::RegulatoryKind> regulatoryKindOf(const std::string& subtype, const std::string& sign) {
  if (subtype == "traffic_light") return map::RegulatoryKind::kTrafficLight;
  if (subtype == "right_of_way") return map::RegulatoryKind::kGiveWay;
  if (subtype == "traffic_sign") {
    if (sign == "stop_sign" || sign == "stop" || sign == "de206" || sign == "usR1-1") return map::RegulatoryKind::kStopSign;
    if (sign == "give_way" || sign == "yield" || sign == "de205" || sign == "usR1-2") return map::RegulatoryKind::kGiveWay;
  }
  return std::nullopt;
}

// The sidecar of an OSM file whose bytes hash to `hash`: MAP.lanemap.json when it matches, else
// any *.lanemap.json in the same folder that names the hash (a renamed copy of the map). Only the
// first bytes of each candidate are read until one matches.
struct SidecarMatch {
  std::string path;
  bool stale = false;  // MAP.lanemap.json exists but names another hash
};

SidecarMatch findSidecar(const std::string& osm_path, const std::string& hash) {
  SidecarMatch match;
  std::error_code ec;
  const std::string own = lanelet2SidecarPath(osm_path);
  if (std::filesystem::is_regular_file(own, ec)) {
    if (sidecarHashOf(own) == hash) {
      match.path = own;
      return match;
    }
    match.stale = true;
  }
  const auto dir = std::filesystem::path(osm_path).parent_path();
  const std::string suffix = ".lanemap.json";
  size_t looked = 0;
  for (std::filesystem::directory_iterator it(dir.empty() ? "." : dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
    if (it->path().string() == own || ++looked > 1000) continue;
    if (sidecarHashOf(it->path().string()) == hash) {
      match.path = it->path().string();
      break;
    }
  }
  return match;
}

// What a sidecar holds, parsed and checked.
struct Sidecar {
  std::string path;
  geo::LatLonAlt origin;
  std::unordered_map<int64_t, nlohmann::json> lanelets;
  int64_t first_node_id = 0;
  std::vector<double> local_xy;
  nlohmann::json extra = nlohmann::json::object();  // regulatory_elements, crosswalks (if any)
};

Sidecar parseSidecar(const std::string& path, const std::string& osm_path) {
  Sidecar side;
  side.path = path;
  const auto bad = [&](const std::string& what) -> Lanelet2Error {
    return Lanelet2Error("malformed lanemap sidecar '" + path + "' of '" + osm_path + "': " + what);
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(readAll(path));
  } catch (const std::exception& e) {
    throw bad(e.what());
  }
  try {
    if (j.value("lanemap_sidecar", 0) != kSidecarVersion) throw bad("unknown version");
    const auto& o = j.at("origin");
    side.origin = {o.at("lat").get<double>(), o.at("lon").get<double>(), o.at("alt").get<double>()};
    for (const auto& [id, v] : j.at("lanelets").items()) {
      side.lanelets[std::stoll(id)] = v;
    }
    side.first_node_id = j.at("first_node_id").get<int64_t>();
    side.local_xy = j.at("local_xy").get<std::vector<double>>();
    for (const char* section : {"regulatory_elements", "crosswalks"}) {
      if (j.contains(section)) {
        if (!j.at(section).is_object()) throw bad(std::string(section) + " is not an object");
        side.extra[section] = j.at(section);
      }
    }
  } catch (const Lanelet2Error&) {
    throw;
  } catch (const std::exception& e) {
    throw bad(e.what());
  }
  if (side.local_xy.size() % 2 != 0) throw bad("local_xy has an odd number of values");
  return side;
}

class Lanelet2Reader {
 public:
  Lanelet2Reader(const std::string& path, double lat, double lon, const Lanelet2ReadOptions& options)
      : path_(path), options_(options), frame_({lat, lon, options.origin_alt}), raw_(parseOsmFile(path)) {
    out_.map.origin_lat = lat;
    out_.map.origin_lon = lon;
    out_.map.origin_alt = options.origin_alt;
    const SidecarMatch match = findSidecar(path, hex64(fnv1a64(readAll(path))));
    out_.stale_sidecar = match.stale && match.path.empty();
    if (!match.path.empty()) {
      sidecar_ = parseSidecar(match.path, path);
      out_.sidecar = match.path;
    }
  }

  Lanelet2File read() {
    collectLanelets();
    collectRegulatoryWays();
    decideCoordinates();
    for (auto& rl : lanelets_) buildBounds(rl);
    buildLines();
    for (auto& rl : lanelets_) buildCentre(rl);
    findSuccessors();
    buildRegulatoryElements();
    buildCrosswalks();
    for (auto& rl : lanelets_) out_.map.lanelets.push_back(std::move(rl.lanelet));
    return std::move(out_);
  }

 private:
  [[noreturn]] void malformed(const std::string& what) const {
    throw Lanelet2Error("malformed Lanelet2 map '" + path_ + "': " + what);
  }

  const RawWay& way(int64_t id, int64_t relation) const {
    const auto it = raw_.ways.find(id);
    if (it == raw_.ways.end()) {
      malformed("relation " + std::to_string(relation) + " refers to missing way " + std::to_string(id));
    }
    return it->second;
  }

  bool keepSubtype(const std::string& subtype) const {
    if (options_.subtypes.empty()) return true;
    return std::find(options_.subtypes.begin(), options_.subtypes.end(), subtype) !=
           options_.subtypes.end();
  }

  // The stop line of a foreign lanelet: a stop_line way that one of its regulatory elements
  // (traffic light, right of way, ...) names as `ref_line`.
  std::optional<int64_t> stopLineFromRegulatoryElements(int64_t lanelet_id, const RawRelation& rel) const {
    for (const auto& m : rel.members) {
      if (m.kind != 'r' || m.role != "regulatory_element") continue;
      const auto reg = raw_.relations.find(m.ref);
      if (reg == raw_.relations.end()) continue;
      // A right of way's ref_line is the stop line of its yield lanelets only.
      if (reg->second.tag("subtype") == "right_of_way" &&
          std::none_of(reg->second.members.begin(), reg->second.members.end(), [&](const RawMember& rm) {
            return rm.kind == 'r' && rm.role == "yield" && rm.ref == lanelet_id;
          })) {
        continue;
      }
      const bool marking = reg->second.tag("subtype") == "road_marking";  // Autoware: refers = the marking
      for (const auto& rm : reg->second.members) {
        if (rm.kind != 'w' || (rm.role != "ref_line" && !(marking && rm.role == "refers"))) continue;
        const auto w = raw_.ways.find(rm.ref);
        if (w != raw_.ways.end() && w->second.type == "stop_line") return rm.ref;
      }
    }
    return std::nullopt;
  }

  void collectLanelets() {
    for (const auto& [id, rel] : raw_.relations) {
      if (rel.tag("type") != "lanelet") continue;
      const std::string subtype = rel.tag("subtype");
      if (subtype == "crosswalk") {
        collectCrosswalk(id, rel);
        out_.lanelet_subtype[id] = subtype;
        continue;
      }
      if (!keepSubtype(subtype)) continue;
      ReadLanelet rl;
      rl.lanelet.id = id;
      int lefts = 0, rights = 0, centres = 0;
      for (const auto& m : rel.members) {
        const bool inverted = m.role.find("inverted") != std::string::npos;
        // "left"/"right", or a variant naming an inverted member ("left_inverted", ...).
        const bool is_left = m.role == "left" || (inverted && m.role.find("left") != std::string::npos);
        const bool is_right = m.role == "right" || (inverted && m.role.find("right") != std::string::npos);
        if (m.role == "centerline") {
          if (m.kind == 'w') {
            rl.centre_way = m.ref;
            centre_ways_.insert(m.ref);
          }
          ++centres;
          continue;
        }
        if (!is_left && !is_right) continue;
        if (m.kind != 'w') {
          malformed("lanelet " + std::to_string(id) + ": member '" + m.role + "' is not a way");
        }
        Bound& b = is_left ? rl.left : rl.right;
        (is_left ? lefts : rights)++;
        b.way_id = m.ref;
        b.reversed = inverted;
        way(m.ref, id);  // must exist
      }
      if (lefts != 1 || rights != 1) {
        malformed("lanelet " + std::to_string(id) + " has " + std::to_string(lefts) +
                  " left and " + std::to_string(rights) + " right bounds (expected one each)");
      }
      if (centres > 1) malformed("lanelet " + std::to_string(id) + " has several centerlines");
      fillAttributes(rl, rel);
      out_.lanelet_subtype[id] = subtype;
      lanelets_.push_back(std::move(rl));
    }
  }

  void fillAttributes(ReadLanelet& rl, const RawRelation& rel) {
    map::Lanelet& ll = rl.lanelet;
    const std::string where = "lanelet " + std::to_string(ll.id) + " tag ";
    const auto integer = [&](const char* key, int64_t fallback) {
      const std::string v = rel.tag(key);
      return v.empty() ? fallback : parseInteger(v, path_, where + key);
    };
    const std::string turn = rel.tag("turn_direction");
    ll.turn = turnOf(turn);
    if (sidecar_) {
      const auto it = sidecar_->lanelets.find(ll.id);
      if (it != sidecar_->lanelets.end()) {
        fillFromSidecar(rl, it->second);
        return;
      }
    }
    ll.road_id = integer("lanemap:road_id", -1);
    ll.from_node = integer("lanemap:from_node", -1);
    ll.to_node = integer("lanemap:to_node", -1);
    ll.intersection_id = integer("lanemap:intersection_id", -1);
    ll.index_from_left = static_cast<int>(integer("lanemap:index_from_left", -1));
    const std::string kind = rel.tag("lanemap:kind");
    if (kind.empty()) {
      ll.kind = (!turn.empty() || ll.intersection_id != -1) ? LaneletKind::kIntersection
                                                            : LaneletKind::kRoad;
    } else {
      ll.kind = kind == "intersection" ? LaneletKind::kIntersection : LaneletKind::kRoad;
    }
    const std::string stop = rel.tag("lanemap:stop_line");
    if (!stop.empty()) {
      rl.stop_way = parseInteger(stop, path_, where + "lanemap:stop_line");
      way(*rl.stop_way, ll.id);
    } else {
      rl.stop_way = stopLineFromRegulatoryElements(ll.id, rel);
    }
  }

  // lanemap's attributes of a lanelet from its sidecar entry. The sidecar's `turn` is the model's
  // (kNone where the writer derived turn_direction from the geometry).
  void fillFromSidecar(ReadLanelet& rl, const nlohmann::json& j) {
    map::Lanelet& ll = rl.lanelet;
    const std::string where = "lanelet " + std::to_string(ll.id) + " ";
    try {
      ll.kind = j.at("kind").get<std::string>() == "intersection" ? LaneletKind::kIntersection : LaneletKind::kRoad;
      ll.road_id = j.at("road_id").get<int64_t>();
      ll.from_node = j.at("from_node").get<int64_t>();
      ll.to_node = j.at("to_node").get<int64_t>();
      ll.intersection_id = j.at("intersection_id").get<int64_t>();
      ll.index_from_left = j.at("index_from_left").get<int>();
      ll.turn = j.contains("turn") ? turnOf(j.at("turn").get<std::string>()) : TurnDirection::kNone;
      if (j.contains("stop_line")) rl.stop_way = j.at("stop_line").get<int64_t>();
      if (j.contains("partial")) {
        ll.partial = map::PartialRoad{j.at("partial").at("station_m").get<double>(), j.at("partial").at("road_length_m").get<double>()};
      }
      if (j.contains("confidence")) ll.confidence = j.at("confidence").get<double>();
    } catch (const std::exception& e) {
      throw Lanelet2Error("malformed lanemap sidecar '" + sidecar_->path + "' of '" + path_ + "': " + where + e.what());
    }
    if (rl.stop_way) way(*rl.stop_way, ll.id);
  }

  // Every node the kept lanelets use (and one way using it), for the coordinate decision.
  std::map<int64_t, int64_t> usedNodes() const {
    std::map<int64_t, int64_t> used;
    const auto add = [&](int64_t way_id) {
      const auto it = raw_.ways.find(way_id);
      if (it == raw_.ways.end()) return;
      for (int64_t n : it->second.refs) used.emplace(n, way_id);
    };
    for (const auto& rl : lanelets_) {
      add(rl.left.way_id);
      add(rl.right.way_id);
      if (rl.centre_way) add(*rl.centre_way);
      if (rl.stop_way) add(*rl.stop_way);
    }
    for (const auto& [way_id, w] : raw_.ways) {
      if (isStandaloneLine(way_id, w)) add(way_id);
    }
    for (int64_t way_id : aux_ways_) add(way_id);
    return used;
  }

  // A typed marking or border way whose nodes are all there: kept as a LineString even when no
  // lanelet uses it (a curb behind a parking lane, a lone stop line), so nothing typed is lost.
  bool isStandaloneLine(int64_t way_id, const RawWay& w) const {
    if (w.refs.size() < 2 || (w.type != "virtual" && lineTypeOf(w) == LineType::kVirtual)) return false;
    if (centre_ways_.count(way_id)) return false;  // a lanelet's centre line, not a marking
    if (aux_ways_.count(way_id)) return false;     // a crosswalk's edge or a traffic light
    return std::all_of(w.refs.begin(), w.refs.end(), [&](int64_t n) {
      const auto it = raw_.nodes.find(n);
      return it != raw_.nodes.end() && it->second.located;
    });
  }

  // The node's mm-precise position from the sidecar, in the reader's frame; nullopt when the
  // sidecar has none for it. `ele` is the node's; `p` its position from lat/lon.
  std::optional<Eigen::Vector3d> sidecarPosition(int64_t id, double ele) const {
    if (!sidecar_ || id < sidecar_->first_node_id) return std::nullopt;
    const uint64_t i = static_cast<uint64_t>(id - sidecar_->first_node_id);
    if (2 * i + 1 >= sidecar_->local_xy.size()) return std::nullopt;
    const double x = sidecar_->local_xy[2 * i], y = sidecar_->local_xy[2 * i + 1];
    if (!writer_frame_) writer_frame_.emplace(sidecar_->origin);
    const geo::LatLonAlt g = writer_frame_->toWgs84(Eigen::Vector3d(x, y, ele - sidecar_->origin.alt));
    return latLonEleToEnu(frame_, g.lat, g.lon, ele);
  }

  // Positions from lat/lon(/ele); from the sidecar's ENU coordinates (converted to our frame), or
  // else from local_x/local_y, when every used node has them and they agree with lat/lon (for the
  // tags: in our frame, i.e. the file was written with our origin).
  void decideCoordinates() {
    if (sidecar_) {
      bool all = true;
      std::unordered_map<int64_t, Eigen::Vector3d> precise;
      for (const auto& [id, way_id] : usedNodes()) {
        const auto it = raw_.nodes.find(id);
        if (it == raw_.nodes.end() || !it->second.located) { all = false; break; }
        const RawNode& n = it->second;
        const double ele = n.ele.empty() ? options_.origin_alt
                                         : parseNumber(n.ele, path_, "ele of node " + std::to_string(id));
        const Eigen::Vector3d p = latLonEleToEnu(frame_, n.lat, n.lon, ele);
        const auto q = sidecarPosition(id, ele);
        if (!q || (q->head<2>() - p.head<2>()).norm() >= kLocalXyAgreementM) { all = false; break; }
        precise[id] = *q;
      }
      if (all && !precise.empty()) {
        position_ = std::move(precise);
        out_.used_local_xy = true;
        return;
      }
    }
    bool all_local = true;
    for (const auto& [id, way_id] : usedNodes()) {
      const auto it = raw_.nodes.find(id);
      if (it == raw_.nodes.end()) {
        malformed("way " + std::to_string(way_id) + " refers to missing node " + std::to_string(id));
      }
      const RawNode& n = it->second;
      if (!n.located) malformed("node " + std::to_string(id) + " has no valid lat/lon");
      const double ele = n.ele.empty() ? options_.origin_alt
                                       : parseNumber(n.ele, path_, "ele of node " + std::to_string(id));
      Eigen::Vector3d p = latLonEleToEnu(frame_, n.lat, n.lon, ele);
      if (all_local && !n.local_x.empty() && !n.local_y.empty()) {
        char* end_x = nullptr;
        char* end_y = nullptr;
        const double x = std::strtod(n.local_x.c_str(), &end_x);
        const double y = std::strtod(n.local_y.c_str(), &end_y);
        const bool ok = *end_x == '\0' && *end_y == '\0' && std::isfinite(x) && std::isfinite(y);
        if (ok && std::hypot(x - p.x(), y - p.y()) < kLocalXyAgreementM) {
          local_[id] = Eigen::Vector2d(x, y);
        } else {
          all_local = false;
        }
      } else {
        all_local = false;
      }
      position_[id] = p;
    }
    out_.used_local_xy = all_local && !position_.empty();
    if (out_.used_local_xy) {
      for (const auto& [id, xy] : local_) position_[id].head<2>() = xy;
    }
  }

  void wayGeometry(int64_t way_id, int64_t relation, std::vector<int64_t>& ids,
                   std::vector<Eigen::Vector3d>& pts) const {
    const RawWay& w = way(way_id, relation);
    if (w.refs.empty()) malformed("way " + std::to_string(way_id) + " has no node");
    ids = w.refs;
    pts.clear();
    for (int64_t n : w.refs) pts.push_back(position_.at(n));
  }

  // Bounds in the driving direction, aligned as Lanelet2 aligns them.
  void buildBounds(ReadLanelet& rl) {
    for (Bound* b : {&rl.left, &rl.right}) {
      const bool inverted = b->reversed;
      wayGeometry(b->way_id, rl.lanelet.id, b->node_ids, b->points);
      b->reversed = false;
      if (inverted) b->reverse();
    }
    if (rl.left.points.size() < 2 || rl.right.points.size() < 2) {
      malformed("lanelet " + std::to_string(rl.lanelet.id) + " has a bound with fewer than 2 nodes");
    }
    const Alignment a = lanelet2Alignment(rl.left.points, rl.right.points);
    if (a.invert_left) rl.left.reverse();
    if (a.invert_right) rl.right.reverse();
  }

  // One LineString per way in its own direction; a reversed copy (fresh id) for lanelets that use
  // it the other way round, unless no lanelet uses it forwards (then the way itself is reversed).
  void buildLines() {
    std::map<int64_t, std::pair<int, int>> uses;  // way -> (forward, reversed)
    for (const auto& rl : lanelets_) {
      for (const Bound* b : {&rl.left, &rl.right}) {
        auto& u = uses[b->way_id];
        (b->reversed ? u.second : u.first)++;
      }
    }
    int64_t next_id = 1;
    for (const auto& [id, n] : raw_.nodes) next_id = std::max(next_id, std::abs(id) + 1);
    for (const auto& [id, w] : raw_.ways) next_id = std::max(next_id, std::abs(id) + 1);
    for (const auto& [id, r] : raw_.relations) next_id = std::max(next_id, std::abs(id) + 1);

    std::map<std::pair<int64_t, bool>, int64_t> line_id;  // (way, reversed) -> line id
    for (const auto& [way_id, u] : uses) {
      if (u.first > 0) {
        addLine(way_id, way_id, false);
        line_id[{way_id, false}] = way_id;
        if (u.second > 0) {
          addLine(next_id, way_id, true);
          out_.reversed_copy_of[next_id] = way_id;
          line_id[{way_id, true}] = next_id++;
        }
      } else {
        addLine(way_id, way_id, true);
        line_id[{way_id, true}] = way_id;
      }
    }
    std::set<int64_t> stop_ways;
    for (auto& rl : lanelets_) {
      rl.lanelet.left_id = line_id.at({rl.left.way_id, rl.left.reversed});
      rl.lanelet.right_id = line_id.at({rl.right.way_id, rl.right.reversed});
      if (rl.stop_way) {
        rl.lanelet.stop_line_id = *rl.stop_way;
        if (!uses.count(*rl.stop_way)) stop_ways.insert(*rl.stop_way);
      }
    }
    for (int64_t w : stop_ways) addLine(w, w, false);
    // OSM ids are per element type: a way may share its number with a lanelet relation. A
    // standalone line that would collide gets a fresh id (ids of the map stay distinct).
    std::vector<int64_t> standalone;
    for (const auto& [way_id, w] : raw_.ways) {
      if (!uses.count(way_id) && !stop_ways.count(way_id) && isStandaloneLine(way_id, w)) standalone.push_back(way_id);
    }
    std::sort(standalone.begin(), standalone.end());  // deterministic fresh ids
    for (int64_t way_id : standalone) addLine(raw_.relations.count(way_id) ? next_id++ : way_id, way_id, false);
    std::sort(out_.map.lines.begin(), out_.map.lines.end(),
              [](const auto& a, const auto& b) { return a.id < b.id; });
  }

  void addLine(int64_t id, int64_t way_id, bool reversed) {
    const RawWay& w = raw_.ways.at(way_id);
    map::LineString line;
    line.id = id;
    line.type = lineTypeOf(w);
    std::vector<int64_t> ids;
    wayGeometry(way_id, way_id, ids, line.points);
    if (reversed) std::reverse(line.points.begin(), line.points.end());
    out_.line_tag[id] = w.subtype.empty() ? w.type : w.type + ":" + w.subtype;
    out_.map.lines.push_back(std::move(line));
    if (!reversed || !line_of_way_.count(way_id)) line_of_way_[way_id] = id;
  }

  void buildCentre(ReadLanelet& rl) {
    const auto& left = rl.left.points;
    const auto& right = rl.right.points;
    if (rl.centre_way) {
      std::vector<int64_t> ids;
      std::vector<Eigen::Vector3d> centre;
      wayGeometry(*rl.centre_way, rl.lanelet.id, ids, centre);
      const Eigen::Vector3d start = 0.5 * (left.front() + right.front());
      if ((centre.back() - start).norm() < (centre.front() - start).norm()) {
        std::reverse(centre.begin(), centre.end());
      }
      if (centre.size() >= 2) {
        rl.lanelet.centre = std::move(centre);
        return;
      }
    }
    const double len = std::max(polylineLength(left), polylineLength(right));
    const double spacing = options_.centre_spacing_m > 0.0 ? options_.centre_spacing_m : 1.0;
    // At most kMaxComputedCentrePoints from the spacing: a bound with a node hundreds of km away
    // (fuzz/regressions/lanelet2) must not become a million-point centre line.
    constexpr size_t kMaxComputedCentrePoints = 10000;
    const double wanted = std::ceil(len / spacing) + 1.0;
    const size_t by_spacing = std::isfinite(wanted) && wanted < kMaxComputedCentrePoints
                                  ? static_cast<size_t>(wanted) : kMaxComputedCentrePoints;
    const size_t n = std::max({size_t{2}, left.size(), right.size(), by_spacing});
    const auto l = resampleEvenly(left, n);
    const auto r = resampleEvenly(right, n);
    rl.lanelet.centre.resize(n);
    for (size_t i = 0; i < n; ++i) rl.lanelet.centre[i] = 0.5 * (l[i] + r[i]);
    ++out_.computed_centres;
  }

  static bool samePoint(int64_t id_a, const Eigen::Vector3d& a, int64_t id_b, const Eigen::Vector3d& b) {
    return id_a == id_b || (a - b).norm() < kSuccessorDistanceM;
  }

  // B succeeds A when A's bounds end where B's bounds start (both sides).
  void findSuccessors() {
    for (auto& a : lanelets_) {
      for (const auto& b : lanelets_) {
        if (&a == &b) continue;
        if (samePoint(a.left.node_ids.back(), a.left.points.back(), b.left.node_ids.front(),
                      b.left.points.front()) &&
            samePoint(a.right.node_ids.back(), a.right.points.back(), b.right.node_ids.front(),
                      b.right.points.front())) {
          a.lanelet.successors.push_back(b.lanelet.id);
        }
      }
    }
  }

  // A crosswalk lanelet (subtype=crosswalk): kept apart from the lanes, in map.crosswalks.
  struct ReadCrosswalk {
    int64_t id = 0;
    int64_t left = 0, right = 0;
    bool left_inverted = false, right_inverted = false;
  };

  void collectCrosswalk(int64_t id, const RawRelation& rel) {
    ReadCrosswalk c;
    c.id = id;
    int lefts = 0, rights = 0;
    for (const auto& m : rel.members) {
      if (m.kind != 'w') continue;
      const bool inverted = m.role.find("inverted") != std::string::npos;
      const bool is_left = m.role == "left" || (inverted && m.role.find("left") != std::string::npos);
      const bool is_right = m.role == "right" || (inverted && m.role.find("right") != std::string::npos);
      if (!is_left && !is_right) continue;
      way(m.ref, id);  // must exist
      (is_left ? c.left : c.right) = m.ref;
      (is_left ? c.left_inverted : c.right_inverted) = inverted;
      (is_left ? lefts : rights)++;
    }
    if (lefts != 1 || rights != 1) {
      malformed("crosswalk lanelet " + std::to_string(id) + " has " + std::to_string(lefts) + " left and " +
                std::to_string(rights) + " right bounds (expected one each)");
    }
    aux_ways_.insert(c.left);
    aux_ways_.insert(c.right);
    crosswalks_.push_back(c);
  }

  const nlohmann::json* sidecarEntry(const char* section, int64_t id) const {
    if (!sidecar_ || !sidecar_->extra.contains(section)) return nullptr;
    const auto& sec = sidecar_->extra.at(section);
    const auto it = sec.find(std::to_string(id));
    return it == sec.end() ? nullptr : &*it;
  }

  // The regulatory elements lanemap models (stop and give-way signs, right of way, traffic
  // lights) whose ref_line is a stop line of the map and which apply to a lanelet that was read.
  // Collected before the coordinates are decided (the lights' nodes must get positions).
  void collectRegulatoryWays() {
    for (const auto& [id, rel] : raw_.relations) {
      if (rel.tag("type") != "regulatory_element" || rel.tag("subtype") != "traffic_light") continue;
      for (const auto& m : rel.members) {
        const auto w = raw_.ways.find(m.ref);
        if (m.kind == 'w' && m.role == "refers" && w != raw_.ways.end() && w->second.refs.size() >= 2 &&
            std::all_of(w->second.refs.begin(), w->second.refs.end(), [&](int64_t n) {
              const auto it = raw_.nodes.find(n);
              return it != raw_.nodes.end() && it->second.located;
            })) {
          aux_ways_.insert(m.ref);
          break;
        }
      }
    }
  }

  void buildRegulatoryElements() {
    std::set<int64_t> kept;
    std::map<int64_t, std::vector<int64_t>> users;  // regulatory element -> lanelets referencing it
    for (const auto& rl : lanelets_) kept.insert(rl.lanelet.id);
    for (const auto& [id, rel] : raw_.relations) {
      if (rel.tag("type") != "lanelet" || !kept.count(id)) continue;
      for (const auto& m : rel.members) {
        if (m.kind == 'r' && m.role == "regulatory_element") users[m.ref].push_back(id);
      }
    }
    for (const auto& [id, rel] : raw_.relations) {
      if (rel.tag("type") != "regulatory_element") continue;
      std::string sign = rel.tag("sign_type");
      std::optional<int64_t> stop_way, light_way;
      std::vector<int64_t> yield, priority;
      for (const auto& m : rel.members) {
        if (m.kind == 'w' && m.role == "ref_line" && !stop_way) stop_way = m.ref;
        if (m.kind == 'w' && m.role == "refers" && !light_way) {
          light_way = m.ref;
          if (sign.empty()) {
            if (const auto w = raw_.ways.find(m.ref); w != raw_.ways.end()) sign = w->second.subtype;
          }
        }
        if (m.kind == 'r' && m.role == "yield" && kept.count(m.ref)) yield.push_back(m.ref);
        if (m.kind == 'r' && m.role == "right_of_way" && kept.count(m.ref)) priority.push_back(m.ref);
      }
      const auto kind = regulatoryKindOf(rel.tag("subtype"), sign);
      if (!kind || !stop_way || !line_of_way_.count(*stop_way)) continue;
      map::RegulatoryElement r;
      r.id = id;
      r.kind = *kind;
      r.light_estimated = false;  // unless the sidecar says so
      r.stop_line_id = line_of_way_.at(*stop_way);
      if (rel.tag("subtype") == "right_of_way") {
        r.lanelets = yield;
        r.priority = priority;
      } else if (const auto u = users.find(id); u != users.end()) {
        r.lanelets = u->second;
      }
      if (r.lanelets.empty()) continue;
      if (r.kind == map::RegulatoryKind::kTrafficLight) {
        if (!light_way || !aux_ways_.count(*light_way)) continue;
        std::vector<int64_t> ids;
        wayGeometry(*light_way, id, ids, r.light);
        const std::string& h = raw_.ways.at(*light_way).height;
        if (!h.empty()) r.light_height_m = parseNumber(h, path_, "height of way " + std::to_string(*light_way));
        r.light_estimated = false;
      }
      if (const nlohmann::json* j = sidecarEntry("regulatory_elements", id)) {
        try {
          r.osm_node = j->value("osm_node", int64_t{-1});
          r.light_estimated = j->value("light_position", std::string()) == "estimated";
        } catch (const std::exception& e) {
          throw Lanelet2Error("malformed lanemap sidecar '" + sidecar_->path + "' of '" + path_ +
                              "': regulatory element " + std::to_string(id) + " " + e.what());
        }
      }
      out_.map.regulatory_elements.push_back(std::move(r));
    }
  }

  void buildCrosswalks() {
    std::set<int64_t> kept;
    for (const auto& rl : lanelets_) kept.insert(rl.lanelet.id);
    // Autoware's crosswalk elements: crosswalk lanelet (refers) -> road lanelets referencing them.
    std::map<int64_t, std::vector<int64_t>> crossing_of;
    for (const auto& [id, rel] : raw_.relations) {
      if (rel.tag("type") != "lanelet" || !kept.count(id)) continue;
      for (const auto& m : rel.members) {
        if (m.kind != 'r' || m.role != "regulatory_element") continue;
        const auto reg = raw_.relations.find(m.ref);
        if (reg == raw_.relations.end() || reg->second.tag("subtype") != "crosswalk") continue;
        for (const auto& rm : reg->second.members) {
          if (rm.kind == 'r' && rm.role == "refers") crossing_of[rm.ref].push_back(id);
        }
      }
    }
    for (const auto& c : crosswalks_) {
      map::Crosswalk cw;
      cw.id = c.id;
      std::vector<int64_t> ids;
      wayGeometry(c.left, c.id, ids, cw.left);
      wayGeometry(c.right, c.id, ids, cw.right);
      if (c.left_inverted) std::reverse(cw.left.begin(), cw.left.end());
      if (c.right_inverted) std::reverse(cw.right.begin(), cw.right.end());
      if (cw.left.size() < 2 || cw.right.size() < 2) {
        malformed("crosswalk lanelet " + std::to_string(c.id) + " has a bound with fewer than 2 nodes");
      }
      const Alignment a = lanelet2Alignment(cw.left, cw.right);
      if (a.invert_left) std::reverse(cw.left.begin(), cw.left.end());
      if (a.invert_right) std::reverse(cw.right.begin(), cw.right.end());
      if (const nlohmann::json* j = sidecarEntry("crosswalks", c.id)) {
        try {
          cw.road_id = j->value("road_id", int64_t{-1});
          for (int64_t id : j->value("crossing", std::vector<int64_t>{})) {
            if (kept.count(id)) cw.crossing.push_back(id);
          }
        } catch (const std::exception& e) {
          throw Lanelet2Error("malformed lanemap sidecar '" + sidecar_->path + "' of '" + path_ + "': crosswalk " +
                              std::to_string(c.id) + " " + e.what());
        }
      } else if (const auto it = crossing_of.find(c.id); it != crossing_of.end()) {
        cw.crossing = it->second;
      }
      out_.map.crosswalks.push_back(std::move(cw));
    }
  }

  std::string path_;
  Lanelet2ReadOptions options_;
  geo::LocalFrame frame_;
  RawOsm raw_;
  Lanelet2File out_;
  std::vector<ReadLanelet> lanelets_;
  std::unordered_map<int64_t, Eigen::Vector3d> position_;
  std::unordered_map<int64_t, Eigen::Vector2d> local_;
  std::optional<Sidecar> sidecar_;
  mutable std::optional<geo::LocalFrame> writer_frame_;
  std::set<int64_t> centre_ways_;
  std::set<int64_t> aux_ways_;  // crosswalk edges and traffic lights: not lines of the map
  std::vector<ReadCrosswalk> crosswalks_;
  std::map<int64_t, int64_t> line_of_way_;  // way id -> LineString id (its forward line)
};

}  // namespace

std::optional<geo::LatLonAlt> lanelet2WriterOrigin(const std::string& osm_path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(osm_path, ec)) return std::nullopt;
  const SidecarMatch match = findSidecar(osm_path, hex64(fnv1a64(readAll(osm_path))));
  if (match.path.empty()) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(readAll(match.path));
    const auto& o = j.at("origin");
    return geo::LatLonAlt{o.at("lat").get<double>(), o.at("lon").get<double>(), o.at("alt").get<double>()};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

Lanelet2File readLanelet2File(const std::string& path, double origin_lat, double origin_lon,
                              const Lanelet2ReadOptions& options) {
  return Lanelet2Reader(path, origin_lat, origin_lon, options).read();
}

LaneMap readLanelet2(const std::string& path, double origin_lat, double origin_lon,
                     const Lanelet2ReadOptions& options) {
  return readLanelet2File(path, origin_lat, origin_lon, options).map;
}

LaneMap readLanelet2(const std::string& path, double origin_lat, double origin_lon) {
  return readLanelet2(path, origin_lat, origin_lon, Lanelet2ReadOptions{});
}

}  // namespace lanemap::io
