// buildWorld: lays out the lane-level world on an OSM skeleton.
//
// Vocabulary. A *cross-section* is one way segment between two intersections with both of its
// directions (the atomic road E_ij and its reverse E_ji, or a single one-way road). Its reference
// line is the smoothed polyline in the direction of its reference road (the one along the way).
// Lateral offsets d are along the reference line's left normal; the layout is first made for
// right-hand traffic ("canonical" d: forward lanes at d < 0, backward lanes at d > 0) and mirrored
// (d -> -d) for left-hand traffic. Across a cross-section, from the centre line (the *anchor*,
// d = 0 for a two-way road, the left lane edge for a one-way road) outwards on each side: a turn
// pocket (only in its section), the lanes, a parking/bike strip or a bus bay, the curb, a
// sidewalk. A cross-section is cut lengthwise into *sections* where the layout changes (turn
// pocket start, bus bay); every lane boundary of a section is one LineString shared by the two
// lanelets beside it, and lanelets of consecutive sections are successors.
// Intersections join the incoming to the outgoing lanes with Bezier lanelets (METHOD.md 5).
#include "core/sim/world_builder.h"

#include "core/intersections/curve.h"
#include "core/io/lanelet2_orientation.h"
#include "core/map/simplify.h"
#include "core/osm/turn_lanes.h"
#include "core/sim/world_geometry.h"
#include "core/sim/world_scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <unordered_map>

namespace lanemap::sim {

namespace {

using detail::FillPrimitive;
using Eigen::Vector2d;
using Eigen::Vector3d;
using geom::RefLine;
using map::Lanelet;
using map::LaneletKind;
using map::LineString;
using map::LineType;
using map::TurnDirection;

constexpr double kPi = 3.14159265358979323846;
constexpr double kCrownFadeM = 8.0;
constexpr double kCurbPaintWidth = 0.15;
constexpr double kStopLineWidth = 0.4;
constexpr double kCrosswalkDepth = 3.0;     // along the road
constexpr double kCrosswalkSetback = 0.5;   // from the road end
constexpr double kBayLength = 30.0, kBayTaper = 8.0;

uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Independent, order-free random streams: one per (seed, object, purpose).
std::mt19937_64 rngFor(uint64_t seed, int64_t object, uint64_t purpose) {
  return std::mt19937_64(mix64(mix64(seed) ^ mix64(static_cast<uint64_t>(object) * 31 + purpose)));
}
double uni(std::mt19937_64& r, double a, double b) { return std::uniform_real_distribution<double>(a, b)(r); }
bool chance(std::mt19937_64& r, double p) { return uni(r, 0.0, 1.0) < p; }

std::string baseClass(const std::string& highway) {
  if (highway.size() > 5 && highway.substr(highway.size() - 5) == "_link") return highway.substr(0, highway.size() - 5);
  return highway;
}
bool isMajor(const std::string& c) { return c == "primary" || c == "secondary" || c == "tertiary" || c == "trunk"; }
bool isMinorStreet(const std::string& c) {
  return c == "residential" || c == "tertiary" || c == "unclassified" || c == "living_street";
}

enum class Edge { kNone, kParking, kBike };

// One side of a cross-section (canonical coordinates).
struct Side {
  int sigma = -1;                 // outward direction of canonical d
  int dir = 0;                    // driving direction of its lanes: +1 along the reference, -1, 0 none
  int64_t road_id = -1;           // the atomic road its lanes belong to
  int64_t from_node = -1, to_node = -1;  // in its driving direction
  std::vector<double> lane_w;     // inner -> outer
  std::vector<std::string> turn;  // turn:lanes entries, inner -> outer ("" none)
  Edge edge = Edge::kNone;
  double edge_w = 0.0;
  double sidewalk_w = 0.0;
  bool pocket = false;
  double pocket_start = 0.0, pocket_w = 0.0, pocket_taper = 15.0;
  bool bay = false;
  double bay_s0 = 0.0, bay_s1 = 0.0, bay_w = 0.0;
  double pocketWidth(double s) const {
    if (!pocket) return 0.0;
    const double x = dir > 0 ? (s - pocket_start) : (pocket_start - s);
    return pocket_w * geom::smoothstep(x / pocket_taper);
  }
  double bayWidth(double s) const {
    if (!bay) return 0.0;
    return bay_w * (geom::smoothstep((s - bay_s0) / kBayTaper) - geom::smoothstep((s - (bay_s1 - kBayTaper)) / kBayTaper));
  }
  double lanesWidth() const {
    double w = 0.0;
    for (double x : lane_w) w += x;
    return w;
  }
};

// A column: one lateral boundary of a section.
enum class ColKind { kAnchor, kPocketDiv, kLaneOuter, kEdgeOuter, kSidewalkOuter };
struct Column {
  int side = -1;  // 0 forward side, 1 backward side, -1 the anchor
  ColKind kind = ColKind::kAnchor;
  int lane = -1;  // kLaneOuter: lane index (inner -> outer, without the pocket)
};

struct Section {
  double s0 = 0.0, s1 = 0.0;
  bool pocket_in[2] = {false, false};
  bool bay_in[2] = {false, false};
  std::vector<Column> cols;     // canonical left -> right (descending canonical d)
  std::vector<double> ss;       // reference arc lengths of the samples
  std::vector<std::vector<double>> d;  // [col][sample] canonical offsets
  std::vector<int64_t> line_ids;       // [col] LineString id (0: none)
  // Lanelets per side, inner -> outer (pocket first when present).
  std::vector<int64_t> lanes[2];
};

struct CrossSection {
  int64_t key = -1;
  const skeleton::AtomicRoad* ref = nullptr;
  const skeleton::AtomicRoad* rev = nullptr;
  std::string highway;
  bool two_way = false;
  RefLine line;
  double sb = 0.0, se = 0.0;
  double anchor = 0.0;
  Side side[2];
  std::vector<Section> sections;
  double left_extent = 0.0, right_extent = 0.0;  // actual d of the outermost edges (sidewalks)
  double halfWidth() const {  // of the carriageway, canonical, the larger side
    double w0 = side[0].lanesWidth() + side[0].edge_w + (side[0].pocket ? side[0].pocket_w : 0.0);
    double w1 = side[1].lanesWidth() + side[1].edge_w + (side[1].pocket ? side[1].pocket_w : 0.0);
    if (!two_way) return std::max(anchor + w1, w0 - anchor);
    return std::max(w0, w1);
  }
};

// End of a lane at an intersection.
struct LaneEnd {
  int64_t lanelet = -1;
  Vector2d centre, left, right, tangent;  // tangent in the driving direction
  double width = 3.0;
  bool pocket = false;
  osm::LaneMovements moves;
};
struct Approach {
  int64_t road_id = -1;
  int64_t xs = -1;
  std::vector<LaneEnd> lanes;  // left -> right
};

struct ZoneSeg {
  Vector2d a, b;
  double left = 0.0, right = 0.0;  // extents (>= 0) on each side
  int64_t xs = -1;
};

class Builder {
 public:
  Builder(const skeleton::Skeleton& sk, const WorldOptions& o) : sk_(sk), o_(o), m_(o.right_hand_traffic ? 1.0 : -1.0) {
    impl_ = std::make_unique<SimWorld::Impl>();
    impl_->options = o;
    impl_->right_hand = o.right_hand_traffic;
  }

  std::unique_ptr<SimWorld::Impl> run() {
    if (sk_.roads().empty()) throw std::runtime_error("buildWorld: the skeleton has no road");
    const auto& origin = sk_.frame().origin();
    truth().origin_lat = origin.lat;
    truth().origin_lon = origin.lon;
    truth().origin_alt = origin.alt;
    makeTerrain();
    groupCrossSections();
    // Smoothing over about the road's half width: the lanes of a hairpin tighter than the road's
    // width still fold on its inner side (a known limit, see the Monaco test).
    for (auto& xs : xss_) xs.line = RefLine(xs.ref->polyline, 1.0, std::clamp(xs.halfWidth(), 3.0, 8.0));
    computeNodeInfo();
    for (auto& xs : xss_) buildCrossSection(xs);
    for (const auto& in : sk_.intersections()) buildIntersection(in);
    shareOpposedIntersectionBounds();
    placeObstacles();
    for (auto& cw : truth().crosswalks) cw.id = nextId();
    fillStats();
    impl_->finalize();
    return std::move(impl_);
  }

 private:
  map::LaneMap& truth() { return impl_->truth; }
  int64_t nextId() { return next_id_++; }

  // ---------- surface ----------
  void makeTerrain() {
    if (o_.flat) return;
    auto r = rngFor(o_.seed, -1, 1);
    // Long waves: slope bound sum(A k) = max_grade; the bumps add little over a few metres.
    const int n = 4;
    std::vector<double> share(n);
    double tot = 0.0;
    for (auto& s : share) tot += (s = uni(r, 0.5, 1.0));
    for (int i = 0; i < n; ++i) {
      const double lambda = uni(r, 180.0, 700.0);
      const double k = 2.0 * kPi / lambda;
      const double th = uni(r, 0.0, 2.0 * kPi);
      detail::Terrain::Wave w;
      w.k = Vector2d(std::cos(th), std::sin(th)) * k;
      w.amplitude = o_.max_grade * share[i] / tot / k;
      w.phase = uni(r, 0.0, 2.0 * kPi);
      impl_->terrain.waves.push_back(w);
    }
    for (int i = 0; i < 2; ++i) {
      const double lambda = uni(r, 5.0, 11.0);
      const double th = uni(r, 0.0, 2.0 * kPi);
      detail::Terrain::Wave w;
      w.k = Vector2d(std::cos(th), std::sin(th)) * (2.0 * kPi / lambda);
      w.amplitude = o_.bump_amplitude_m / 2.0;
      w.phase = uni(r, 0.0, 2.0 * kPi);
      impl_->terrain.waves.push_back(w);
    }
  }

  double terrainAt(const Vector2d& p) const { return o_.flat ? 0.0 : impl_->terrain.at(p.x(), p.y()); }

  // Road-surface offset of a point at actual offset d of a cross-section (crown, curb step).
  double profileAt(const CrossSection& xs, double s, double d, double left_curb, double right_curb) const {
    if (o_.flat) return 0.0;
    const double fade = geom::smoothstep(std::min(s - xs.sb, xs.se - s) / kCrownFadeM);
    if (d <= left_curb + 1e-9 && d >= right_curb - 1e-9) return -o_.crown_slope * std::abs(d) * fade;
    const double edge = d > left_curb ? left_curb : right_curb;
    return -o_.crown_slope * std::abs(edge) * fade + o_.curb_height_m;
  }

  // ---------- cross-sections ----------
  void groupCrossSections() {
    std::set<int64_t> done;
    for (const auto& r : sk_.roads()) {
      if (done.count(r.id)) continue;
      const skeleton::AtomicRoad* rev = r.reverse_id >= 0 ? sk_.road(r.reverse_id) : nullptr;
      CrossSection xs;
      xs.key = static_cast<int64_t>(xss_.size());
      if (rev && !r.along_way && rev->along_way) {
        xs.ref = rev;
        xs.rev = &r;
      } else {
        xs.ref = &r;
        xs.rev = rev;
      }
      done.insert(r.id);
      if (rev) done.insert(rev->id);
      xs.two_way = xs.rev != nullptr;
      const auto hw = xs.ref->tags.find("highway");
      xs.highway = hw == xs.ref->tags.end() ? std::string("road") : hw->second;
      layoutCrossSection(xs);
      xs_of_road_[xs.ref->id] = xs.key;
      if (xs.rev) xs_of_road_[xs.rev->id] = xs.key;
      xss_.push_back(std::move(xs));
    }
  }

  void layoutCrossSection(CrossSection& xs) {
    const osm::Tags& tags = xs.ref->tags;
    auto r = rngFor(o_.seed, xs.ref->id, 2);
    LaneCounts counts = laneCountsFor(tags, !xs.two_way);
    // A one-way road against its way (oneway=-1): its lanes are "forward" of its reference road.
    const std::string cls = baseClass(xs.highway);
    // Lane widths: width / lanes when tagged, else the class default with a per-lane variation.
    const int total = counts.forward + counts.backward;
    double tagged = -1.0;
    if (auto it = tags.find("width"); it != tags.end()) {
      char* end = nullptr;
      const double w = std::strtod(it->second.c_str(), &end);
      if (end != it->second.c_str() && w > 0.0) tagged = w / total;
    }
    const double base = o_.default_lane_width_m > 0 ? o_.default_lane_width_m : defaultLaneWidth(xs.highway);
    auto laneWidth = [&]() {
      const double w = tagged > 0 ? tagged : base + uni(r, -o_.lane_width_jitter_m, o_.lane_width_jitter_m);
      return std::clamp(w, o_.lane_width_min_m, o_.lane_width_max_m);
    };
    const std::string tl_key_f = xs.two_way ? "turn:lanes:forward" : "turn:lanes";
    const auto tl_f = tags.count(tl_key_f) ? osm::splitTurnLanes(tags.at(tl_key_f)) : std::vector<std::string>();
    const auto tl_b = tags.count("turn:lanes:backward") ? osm::splitTurnLanes(tags.at("turn:lanes:backward")) : std::vector<std::string>();
    for (int k = 0; k < 2; ++k) {
      Side& sd = xs.side[k];
      sd.sigma = k == 0 ? -1 : +1;
      const int n = k == 0 ? counts.forward : counts.backward;
      const skeleton::AtomicRoad* road = k == 0 ? xs.ref : xs.rev;
      if (n > 0 && road) {
        sd.dir = k == 0 ? +1 : -1;
        sd.road_id = road->id;
        sd.from_node = road->from;
        sd.to_node = road->to;
        for (int i = 0; i < n; ++i) sd.lane_w.push_back(laneWidth());
        // turn:lanes lists lanes left to right in the driving direction; inner = left in RHT.
        const auto& tl = k == 0 ? tl_f : tl_b;
        sd.turn.assign(n, "");
        if (static_cast<int>(tl.size()) == n) {
          for (int i = 0; i < n; ++i) sd.turn[i] = tl[o_.right_hand_traffic ? i : n - 1 - i];
        }
      }
      // Curb-side strip.
      if (isMinorStreet(cls) && chance(r, o_.p_parking_lane)) {
        sd.edge = Edge::kParking;
        sd.edge_w = uni(r, 2.2, 2.5);
      } else if (isMajor(cls) && chance(r, o_.p_bike_lane)) {
        sd.edge = Edge::kBike;
        sd.edge_w = uni(r, 1.5, 1.8);
      }
      const double p_sw = cls == "service" ? o_.p_sidewalk / 3.0 : (cls == "motorway" || cls == "trunk" ? 0.0 : o_.p_sidewalk);
      if (chance(r, p_sw)) sd.sidewalk_w = uni(r, 1.5, 3.0);
    }
    xs.anchor = xs.two_way ? 0.0 : xs.side[0].lanesWidth() / 2.0;
  }

  // How far from each junction the lanes of every incident cross-section end (its trim there): the
  // widest carriageway half width at the junction + 1 m. (A rule that also cleared the corners of
  // roads meeting at acute angles, (h_i + h_j) / sin theta, made the truth's lanes end up to 25 m
  // before such junctions, where lanemap's mapper, which ends lanes at the OSM junction's ROI,
  // cannot follow: West Oakland's oracle intersection RMS went from 0.07 to 0.47 m. Not used.)
  void computeNodeInfo() {
    for (const auto& in : sk_.intersections()) {
      std::set<int64_t> xset;
      for (int64_t r : in.incoming) xset.insert(xs_of_road_.at(r));
      for (int64_t r : in.outgoing) xset.insert(xs_of_road_.at(r));
      degree_[in.id] = static_cast<int>(xset.size());
      double rmax = 0.0;
      for (int64_t x : xset) rmax = std::max(rmax, xss_[x].halfWidth());
      min_trim_[in.id] = in.dead_end ? 0.0 : rmax + 1.0;
    }
  }
  int degree(int64_t node) const {
    auto it = degree_.find(node);
    return it == degree_.end() ? 0 : it->second;
  }

  // Canonical offsets of a section's columns at s.
  std::vector<double> columnValues(const CrossSection& xs, const Section& sec, double s) const {
    std::vector<double> vals(sec.cols.size());
    // Columns are stored left -> right; compute side offsets first, then map.
    std::vector<double> side_vals[2];
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      double pos = xs.anchor;
      auto push = [&](double w) {
        pos += sd.sigma * w;
        side_vals[k].push_back(pos);
      };
      if (sec.pocket_in[k]) push(sd.pocketWidth(s));
      for (double w : sd.lane_w) push(w);
      if (sd.edge != Edge::kNone) push(sd.edge_w);
      else if (sec.bay_in[k]) push(sd.bayWidth(s));
      if (sd.sidewalk_w > 0) push(sd.sidewalk_w);
    }
    // Left -> right: backward side outer -> inner, anchor, forward side inner -> outer.
    size_t i = 0;
    for (auto it = side_vals[1].rbegin(); it != side_vals[1].rend(); ++it) vals[i++] = *it;
    vals[i++] = xs.anchor;
    for (double v : side_vals[0]) vals[i++] = v;
    return vals;
  }

  std::vector<Column> columnTemplate(const CrossSection& xs, const Section& sec) const {
    std::vector<Column> side_cols[2];
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      if (sec.pocket_in[k]) side_cols[k].push_back({k, ColKind::kPocketDiv, -1});
      for (int i = 0; i < static_cast<int>(sd.lane_w.size()); ++i) side_cols[k].push_back({k, ColKind::kLaneOuter, i});
      if (sd.edge != Edge::kNone || sec.bay_in[k]) side_cols[k].push_back({k, ColKind::kEdgeOuter, -1});
      if (sd.sidewalk_w > 0) side_cols[k].push_back({k, ColKind::kSidewalkOuter, -1});
    }
    std::vector<Column> cols(side_cols[1].rbegin(), side_cols[1].rend());
    cols.push_back({-1, ColKind::kAnchor, -1});
    cols.insert(cols.end(), side_cols[0].begin(), side_cols[0].end());
    return cols;
  }

  LineType lineTypeOf(const CrossSection& xs, const Section& sec, const Column& c) const {
    switch (c.kind) {
      case ColKind::kAnchor:
        if (xs.two_way) {
          const std::string cls = baseClass(xs.highway);
          return isMajor(cls) || cls == "motorway" ? LineType::kSolidSolid : LineType::kSolid;
        }
        return xs.side[1].edge != Edge::kNone ? LineType::kSolid : LineType::kCurb;
      case ColKind::kPocketDiv: return LineType::kDashed;
      case ColKind::kLaneOuter: {
        const Side& sd = xs.side[c.side];
        if (c.lane + 1 < static_cast<int>(sd.lane_w.size())) return LineType::kDashed;
        return sd.edge != Edge::kNone || sec.bay_in[c.side] ? LineType::kSolid : LineType::kCurb;
      }
      case ColKind::kEdgeOuter: return LineType::kCurb;
      case ColKind::kSidewalkOuter: return LineType::kVirtual;  // not a LineString
    }
    return LineType::kVirtual;
  }

  void chooseTrim(CrossSection& xs) {
    const double L = xs.line.length();
    const double raw = std::max(xs.ref->length, 1e-6);
    double sb = xs.ref->s_begin, se = xs.ref->s_end;
    if (xs.rev) {
      sb = std::max(sb, xs.rev->length - xs.rev->s_end);
      se = std::min(se, xs.rev->length - xs.rev->s_begin);
    }
    sb *= L / raw;
    se *= L / raw;
    sb = std::max(sb, min_trim_[xs.ref->from]);
    se = std::min(se, L - min_trim_[xs.ref->to]);
    constexpr double kMin = 4.0;
    if (se - sb < kMin) {
      const double mid = std::clamp((sb + se) / 2.0, 0.0, L);
      sb = std::max(0.0, mid - kMin / 2);
      se = std::min(L, sb + kMin);
      sb = std::max(0.0, se - kMin);
    }
    xs.sb = sb;
    xs.se = std::max(se, sb + 0.05);
  }

  void choosePocketsAndBays(CrossSection& xs) {
    auto r = rngFor(o_.seed, xs.ref->id, 3);
    const std::string cls = baseClass(xs.highway);
    const bool pocket_class = cls != "motorway" && cls != "trunk" && cls != "service";
    for (int k = 0; k < 2; ++k) {
      Side& sd = xs.side[k];
      if (sd.dir == 0 || !pocket_class) continue;
      if (degree(sd.to_node) < 3 || !chance(r, o_.p_turn_pocket)) continue;
      const double len = uni(r, 30.0, 50.0);
      const double start = k == 0 ? xs.se - len : xs.sb + len;
      const double room = k == 0 ? start - xs.sb : xs.se - start;
      if (room < 20.0) continue;
      sd.pocket = true;
      sd.pocket_start = start;
      sd.pocket_taper = std::min(15.0, len / 2.0);
      sd.pocket_w = std::clamp(sd.lane_w.front() + uni(r, -0.1, 0.1), o_.lane_width_min_m, o_.lane_width_max_m);
    }
    if (xs.side[0].pocket && xs.side[1].pocket && xs.side[1].pocket_start > xs.side[0].pocket_start - 10.0) {
      xs.side[1].pocket = false;
    }
    double lo = xs.sb + 15.0, hi = xs.se - 15.0;
    if (xs.side[0].pocket) hi = std::min(hi, xs.side[0].pocket_start - 5.0);
    if (xs.side[1].pocket) lo = std::max(lo, xs.side[1].pocket_start + 5.0);
    if (!isMajor(cls)) return;
    for (int k = 0; k < 2; ++k) {
      Side& sd = xs.side[k];
      if (sd.dir == 0 || sd.edge != Edge::kNone || hi - lo < kBayLength) continue;
      if (!chance(r, o_.p_bus_bay)) continue;
      sd.bay = true;
      sd.bay_s0 = uni(r, lo, hi - kBayLength);
      sd.bay_s1 = sd.bay_s0 + kBayLength;
      sd.bay_w = uni(r, 2.8, 3.2);
      // The other side's bay must not share the range (keeps sections simple).
      if (k == 0) {
        if (sd.bay_s0 - lo > hi - sd.bay_s1) hi = sd.bay_s0 - 5.0;
        else lo = sd.bay_s1 + 5.0;
      }
    }
  }

  // The section's columns: template, samples and offsets (what buildSection lays its lines on).
  void fillColumns(const CrossSection& xs, Section& sec) const {
    sec.cols = columnTemplate(xs, sec);
    sec.ss = xs.line.samplesBetween(sec.s0, sec.s1);
    sec.d.assign(sec.cols.size(), std::vector<double>(sec.ss.size()));
    for (size_t i = 0; i < sec.ss.size(); ++i) {
      const auto v = columnValues(xs, sec, sec.ss[i]);
      for (size_t c = 0; c < v.size(); ++c) sec.d[c][i] = v[c];
    }
  }

  // A boundary line of a section as buildSection makes it (before its id, type and direction).
  std::vector<Vector3d> boundaryPoints(const CrossSection& xs, const Section& sec, int col) const {
    // The inner edge of a bend tighter than the offset folds: it is a corner on the ground.
    auto pts = columnPoints3(xs, sec, col);
    std::vector<Vector2d> dirs(sec.ss.size());
    for (size_t i = 0; i < dirs.size(); ++i) dirs[i] = xs.line.tangentAt(sec.ss[i]);
    geom::dropBackwardPoints(pts, dirs);
    geom::removeLoops(pts, 80);
    return pts;
  }

  // The lanes of one side of a section as (inner column, outer column), inner -> outer.
  std::vector<std::pair<int, int>> laneColumns(const Section& sec, int k) const {
    const int nc = static_cast<int>(sec.cols.size());
    int anchor = -1;
    for (int c = 0; c < nc; ++c) {
      if (sec.cols[c].kind == ColKind::kAnchor) anchor = c;
    }
    std::vector<std::pair<int, int>> out;
    int inner = anchor;
    for (int c = k == 0 ? anchor + 1 : anchor - 1; k == 0 ? c < nc : c >= 0; c += k == 0 ? 1 : -1) {
      if (sec.cols[c].kind == ColKind::kPocketDiv || sec.cols[c].kind == ColKind::kLaneOuter) out.emplace_back(inner, c);
      inner = c;
    }
    return out;
  }

  // True when Lanelet2 would read every lanelet of the section as meant.
  bool sectionIsSound(const CrossSection& xs, Section sec) const {
    fillColumns(xs, sec);
    for (int k = 0; k < 2; ++k) {
      if (xs.side[k].dir == 0) continue;
      for (const auto& [inner, outer] : laneColumns(sec, k)) {
        LineString in, out;
        in.points = boundaryPoints(xs, sec, inner);
        out.points = boundaryPoints(xs, sec, outer);
        Lanelet l;
        for (size_t i = 0; i < sec.ss.size(); ++i) {
          const Vector2d p = at(xs, sec.ss[i], (sec.d[inner][i] + sec.d[outer][i]) / 2.0);
          l.centre.emplace_back(p.x(), p.y(), 0.0);
        }
        if (xs.side[k].dir < 0) std::reverse(l.centre.begin(), l.centre.end());
        const bool left_is_inner = o_.right_hand_traffic;
        if (!lanelet2ReadsAsMeant(l, left_is_inner ? in : out, left_is_inner ? out : in)) return false;
      }
    }
    return true;
  }

  // Where half of the reference line's heading change over [s0, s1] is done (a hairpin's tip).
  double halfTurn(const CrossSection& xs, double s0, double s1) const {
    constexpr double kStep = 1.0;
    std::vector<std::pair<double, double>> turned;  // (s, heading change from s0 to s)
    double total = 0.0;
    Vector2d previous = xs.line.tangentAt(s0);
    for (double s = s0 + kStep; s < s1; s += kStep) {
      const Vector2d t = xs.line.tangentAt(s);
      total += std::abs(intersections::headingChange(previous, t));
      previous = t;
      turned.emplace_back(s, total);
    }
    for (const auto& [s, sum] : turned) {
      if (sum >= total / 2.0) return s;
    }
    return (s0 + s1) / 2.0;
  }

  std::vector<Section> makeSections(const CrossSection& xs) const {
    std::vector<double> b = {xs.sb, xs.se};
    const Side& f = xs.side[0];
    const Side& g = xs.side[1];
    if (f.pocket) b.push_back(f.pocket_start);
    if (g.pocket) b.push_back(g.pocket_start);
    for (int k = 0; k < 2; ++k) {
      if (xs.side[k].bay) {
        b.push_back(xs.side[k].bay_s0);
        b.push_back(xs.side[k].bay_s1);
      }
    }
    std::sort(b.begin(), b.end());
    // The lanelet that splits at a pocket must not start at the intersection (it would merge and
    // diverge): give it a section of its own.
    if (f.pocket) {
      auto it = std::lower_bound(b.begin(), b.end(), f.pocket_start - 1e-6);
      if (it != b.begin() && std::abs(*(it - 1) - xs.sb) < 1e-6) b.push_back((xs.sb + f.pocket_start) / 2.0);
    }
    if (g.pocket) {
      auto it = std::upper_bound(b.begin(), b.end(), g.pocket_start + 1e-6);
      if (it != b.end() && std::abs(*it - xs.se) < 1e-6) b.push_back((xs.se + g.pocket_start) / 2.0);
    }
    std::sort(b.begin(), b.end());
    const auto section = [&](double s0, double s1) {
      Section sec;
      sec.s0 = s0;
      sec.s1 = s1;
      const double mid = (sec.s0 + sec.s1) / 2.0;
      sec.pocket_in[0] = f.pocket && mid > f.pocket_start;
      sec.pocket_in[1] = g.pocket && mid < g.pocket_start;
      for (int k = 0; k < 2; ++k) {
        const Side& sd = xs.side[k];
        sec.bay_in[k] = sd.bay && mid > sd.bay_s0 && mid < sd.bay_s1;
      }
      return sec;
    };
    std::vector<Section> out;
    for (size_t i = 0; i + 1 < b.size(); ++i) {
      if (b[i + 1] - b[i] >= 0.01) out.push_back(section(b[i], b[i + 1]));
    }
    // A long lanelet that turns back on itself (a hairpin) is read backwards by Lanelet2's loader
    // (its geometry::align compares the bounds' middle points): a section with such a lanelet is
    // split at the tip of its turn, up to three times over, while the pieces stay kMinPiece long.
    constexpr double kMinPiece = 5.0;
    for (int round = 0; round < 3; ++round) {
      std::vector<Section> next;
      bool split = false;
      for (const Section& sec : out) {
        const double s = halfTurn(xs, sec.s0, sec.s1);
        if (s - sec.s0 < kMinPiece || sec.s1 - s < kMinPiece || sectionIsSound(xs, sec)) {
          next.push_back(sec);
          continue;
        }
        next.push_back(section(sec.s0, s));
        next.push_back(section(s, sec.s1));
        split = true;
      }
      out = std::move(next);
      if (!split) break;
    }
    if (out.empty()) {  // cannot happen (se - sb >= 0.05), but never leave a road without lanes
      Section sec;
      sec.s0 = xs.sb;
      sec.s1 = xs.se;
      out.push_back(sec);
    }
    return out;
  }

  // Index of the curb column of a side (its outermost carriageway edge) in a section; the anchor
  // when the side has none. Columns run left to right: side 1 first (outer to inner), side 0 last.
  int curbColumn(const Section& sec, int k) const { return edgeColumn(sec, k, false); }
  // Index of the outermost column of a side (sidewalk edge when there is a sidewalk).
  int outerColumn(const Section& sec, int k) const { return edgeColumn(sec, k, true); }
  int edgeColumn(const Section& sec, int k, bool with_sidewalk) const {
    const int n = static_cast<int>(sec.cols.size());
    int anchor = -1;
    for (int i = 0; i < n; ++i) {
      if (sec.cols[i].kind == ColKind::kAnchor) anchor = i;
    }
    auto ok = [&](int i) {
      return sec.cols[i].side == k && (with_sidewalk || sec.cols[i].kind != ColKind::kSidewalkOuter);
    };
    if (k == 1) {
      for (int i = 0; i < anchor; ++i) {
        if (ok(i)) return i;
      }
    } else {
      for (int i = n - 1; i > anchor; --i) {
        if (ok(i)) return i;
      }
    }
    return anchor;
  }

  Vector2d at(const CrossSection& xs, double s, double canonical_d) const {
    return xs.line.offsetPoint(s, m_ * canonical_d);
  }

  // Road-surface offset at canonical column value d of a section at sample index i.
  double profileForColumn(const CrossSection& xs, const Section& sec, size_t i, double dcan) const {
    const double l = m_ * sec.d[curbColumn(sec, 1)][i];
    const double r = m_ * sec.d[curbColumn(sec, 0)][i];
    return profileAt(xs, sec.ss[i], m_ * dcan, std::max(l, r), std::min(l, r));
  }

  std::vector<Vector2d> columnPoints(const CrossSection& xs, const Section& sec, int col) const {
    std::vector<Vector2d> pts(sec.ss.size());
    for (size_t i = 0; i < sec.ss.size(); ++i) pts[i] = at(xs, sec.ss[i], sec.d[col][i]);
    return pts;
  }

  std::vector<Vector3d> columnPoints3(const CrossSection& xs, const Section& sec, int col) const {
    std::vector<Vector3d> pts(sec.ss.size());
    for (size_t i = 0; i < sec.ss.size(); ++i) {
      const Vector2d p = at(xs, sec.ss[i], sec.d[col][i]);
      pts[i] = Vector3d(p.x(), p.y(), terrainAt(p) + profileForColumn(xs, sec, i, sec.d[col][i]));
    }
    return pts;
  }

  void addFill(Surface s, detail::Layer layer, std::vector<Vector2d> poly, int64_t lanelet = -1, bool faded = false) {
    if (poly.size() < 3) return;
    FillPrimitive f;
    f.surface = s;
    f.layer = layer;
    f.lanelet = lanelet;
    f.faded = faded;
    f.polygon = std::move(poly);
    impl_->fills.push_back(std::move(f));
  }

  std::vector<Vector2d> stripPolygon(const CrossSection& xs, const Section& sec, int ca, int cb) const {
    std::vector<Vector2d> poly = columnPoints(xs, sec, ca);
    const auto other = columnPoints(xs, sec, cb);
    poly.insert(poly.end(), other.rbegin(), other.rend());
    return poly;
  }

  // Marking paint of one LineString (2-D points), with its worn and missing stretches.
  void emitLinePaint(const std::vector<Vector2d>& pts, LineType type, double outward, const std::vector<MarkingGap>& gaps) {
    if (pts.size() < 2) return;
    std::vector<double> cum(pts.size(), 0.0);
    for (size_t i = 1; i < pts.size(); ++i) cum[i] = cum[i - 1] + (pts[i] - pts[i - 1]).norm();
    const double L = cum.back();
    if (L < 1e-3) return;
    if (type == LineType::kCurb) {
      emitStroke(pts, cum, 0.0, L, outward * kCurbPaintWidth / 2.0, kCurbPaintWidth, Surface::kCurb, detail::kLayerCurb, false);
      return;
    }
    std::vector<std::pair<double, double>> pieces;
    if (type == LineType::kDashed) {
      for (double a = 0.0; a < L; a += kDashPeriod) pieces.emplace_back(a, std::min(L, a + kDashLength));
    } else {
      pieces.emplace_back(0.0, L);
    }
    // Split the pieces at the gaps.
    std::vector<std::tuple<double, double, bool>> parts;
    for (const auto& [a, b] : pieces) {
      double cur = a;
      std::vector<MarkingGap> sorted = gaps;
      std::sort(sorted.begin(), sorted.end(), [](const MarkingGap& x, const MarkingGap& y) { return x.s0 < y.s0; });
      for (const auto& g : sorted) {
        const double g0 = std::max(g.s0, cur), g1 = std::min(g.s1, b);
        if (g1 <= g0) continue;
        if (g0 > cur) parts.emplace_back(cur, g0, false);
        if (!g.missing) parts.emplace_back(g0, g1, true);
        cur = g1;
      }
      if (cur < b) parts.emplace_back(cur, b, false);
    }
    for (const auto& [a, b, faded] : parts) {
      if (b - a < 0.05) continue;
      if (type == LineType::kSolidSolid) {
        emitStroke(pts, cum, a, b, kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint, faded);
        emitStroke(pts, cum, a, b, -kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint, faded);
      } else if (type == LineType::kSolid) {
        emitStroke(pts, cum, a, b, 0.0, kLinePaintWidth, Surface::kSolidPaint, detail::kLayerLinePaint, faded);
      } else if (type == LineType::kDashed) {
        emitStroke(pts, cum, a, b, 0.0, kLinePaintWidth, Surface::kDashedPaint, detail::kLayerLinePaint, faded);
      }
    }
  }

  // A band of `width` centred `offset` to the left of the sub-polyline [a, b] (arc lengths).
  void emitStroke(const std::vector<Vector2d>& pts, const std::vector<double>& cum, double a, double b, double offset,
                  double width, Surface surface, detail::Layer layer, bool faded) {
    std::vector<Vector2d> sub;
    auto interp = [&](double s) {
      size_t i = std::upper_bound(cum.begin(), cum.end(), s) - cum.begin();
      i = std::clamp<size_t>(i, 1, cum.size() - 1);
      const double l = cum[i] - cum[i - 1];
      const double u = l > 0 ? std::clamp((s - cum[i - 1]) / l, 0.0, 1.0) : 0.0;
      return Vector2d(pts[i - 1] + u * (pts[i] - pts[i - 1]));
    };
    sub.push_back(interp(a));
    for (size_t i = 0; i < cum.size(); ++i) {
      if (cum[i] > a + 1e-3 && cum[i] < b - 1e-3) sub.push_back(pts[i]);
    }
    sub.push_back(interp(b));
    if (sub.size() < 2 || (sub.back() - sub.front()).norm() < 1e-4) return;
    std::vector<double> d1(sub.size(), offset + width / 2.0), d2(sub.size(), offset - width / 2.0);
    auto left = geom::offsetPolyline(sub, d1);
    const auto right = geom::offsetPolyline(sub, d2);
    left.insert(left.end(), right.rbegin(), right.rend());
    addFill(surface, layer, std::move(left), -1, faded);
  }

  std::vector<MarkingGap> chooseGaps(int64_t line_id, LineType type, double length) {
    std::vector<MarkingGap> out;
    if (type != LineType::kDashed && type != LineType::kSolid && type != LineType::kSolidSolid) return out;
    if (length < 15.0) return out;
    auto r = rngFor(o_.seed, line_id, 4);
    const double max_len = std::min(30.0, 0.45 * length);
    if (chance(r, o_.p_missing_marking)) {
      const double len = uni(r, std::min(6.0, max_len), max_len);
      const double s0 = uni(r, 0.0, std::max(0.0, length / 2.0 - len));
      out.push_back({line_id, s0, s0 + len, true});
    }
    if (chance(r, o_.p_faded_marking)) {
      const double len = uni(r, std::min(6.0, max_len), max_len);
      const double s0 = uni(r, length / 2.0, std::max(length / 2.0, length - len));
      out.push_back({line_id, s0, s0 + len, false});
    }
    return out;
  }

  void buildCrossSection(CrossSection& xs) {
    chooseTrim(xs);
    choosePocketsAndBays(xs);
    xs.sections = makeSections(xs);
    for (int k = 0; k < 2; ++k) {
      if (xs.side[k].bay) ++impl_->stats.bus_bays;
      if (xs.side[k].edge == Edge::kParking) ++impl_->stats.parking_lanes;
      if (xs.side[k].edge == Edge::kBike) ++impl_->stats.bike_lanes;
    }
    xs.left_extent = 0.0;
    xs.right_extent = 0.0;
    for (auto& sec : xs.sections) buildSection(xs, sec);
    linkSections(xs);
    buildEnds(xs);
    ++impl_->stats.cross_sections;
  }

  void buildSection(CrossSection& xs, Section& sec) {
    fillColumns(xs, sec);
    const int nc = static_cast<int>(sec.cols.size());
    for (int c = 0; c < nc; ++c) {
      for (double v : sec.d[c]) {
        xs.left_extent = std::max(xs.left_extent, m_ * v);
        xs.right_extent = std::min(xs.right_extent, m_ * v);
      }
    }
    // 1. LineStrings.
    sec.line_ids.assign(nc, 0);
    for (int c = 0; c < nc; ++c) {
      const LineType type = lineTypeOf(xs, sec, sec.cols[c]);
      if (sec.cols[c].kind == ColKind::kSidewalkOuter) continue;
      LineString ls;
      ls.id = nextId();
      ls.type = type;
      ls.points = boundaryPoints(xs, sec, c);
      // Lines inside the backward side run in its driving direction; the anchor and the forward
      // side run along the reference (the centre line is the one shared, inverted for one side).
      const bool reversed = sec.cols[c].side == 1 && xs.side[1].dir != 0;
      if (reversed) std::reverse(ls.points.begin(), ls.points.end());
      sec.line_ids[c] = ls.id;
      // Paint.
      std::vector<Vector2d> p2(ls.points.size());
      for (size_t i = 0; i < p2.size(); ++i) p2[i] = ls.points[i].head<2>();
      const double len = geom::polylineLength(p2);
      auto gaps = chooseGaps(ls.id, type, len);
      for (const auto& g : gaps) {
        impl_->gaps.push_back(g);
        ++(g.missing ? impl_->stats.missing : impl_->stats.faded);
      }
      // Outward (for the curb band) relative to the line's own left normal.
      const int col_side = sec.cols[c].side;
      double canon_out = col_side == 1 ? +1.0 : -1.0;
      if (col_side == -1) canon_out = +1.0;  // one-way anchor curb: the left edge
      double outward = canon_out * m_;
      if (reversed) outward = -outward;
      emitLinePaint(p2, type, outward, gaps);
      pushLine(std::move(ls));
    }
    // 2. Strips: lanes (lanelets), shoulders, sidewalks.
    int anchor = -1;
    for (int c = 0; c < nc; ++c) {
      if (sec.cols[c].kind == ColKind::kAnchor) anchor = c;
    }
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      // Columns of this side, inner -> outer, with the inner neighbour of each.
      std::vector<int> chain;
      if (k == 0) {
        for (int c = anchor + 1; c < nc; ++c) chain.push_back(c);
      } else {
        for (int c = anchor - 1; c >= 0; --c) chain.push_back(c);
      }
      int inner = anchor;
      std::vector<int64_t> lane_ids;
      int lane_count = 0;
      for (int c : chain) {
        if (sec.cols[c].kind == ColKind::kPocketDiv || sec.cols[c].kind == ColKind::kLaneOuter) ++lane_count;
      }
      int pos = 0;
      for (int c : chain) {
        const Column& col = sec.cols[c];
        auto poly = stripPolygon(xs, sec, inner, c);
        if (col.kind == ColKind::kPocketDiv || col.kind == ColKind::kLaneOuter) {
          const bool pocket = col.kind == ColKind::kPocketDiv;
          const int64_t id = makeRoadLanelet(xs, sec, k, inner, c, pos, lane_count, pocket);
          lane_ids.push_back(id);
          addFill(Surface::kAsphalt, detail::kLayerLane, std::move(poly), id);
          ++pos;
        } else if (col.kind == ColKind::kEdgeOuter) {
          const Surface s = sd.edge == Edge::kBike ? Surface::kBikeLane : Surface::kParking;
          addFill(s, detail::kLayerShoulder, std::move(poly));
        } else if (col.kind == ColKind::kSidewalkOuter) {
          addFill(Surface::kSidewalk, detail::kLayerSidewalk, std::move(poly));
        }
        inner = c;
      }
      sec.lanes[k] = lane_ids;
    }
    // 3. Road profile quads.
    const int cl = curbColumn(sec, 1), cr = curbColumn(sec, 0);
    const int ol = outerColumn(sec, 1), orr = outerColumn(sec, 0);
    for (size_t i = 0; i + 1 < sec.ss.size(); ++i) {
      detail::CrownQuad q;
      for (int e = 0; e < 2; ++e) {
        const size_t j = i + e;
        const double s = sec.ss[j];
        (e == 0 ? q.a : q.b) = xs.line.pointAt(s);
        (e == 0 ? q.na : q.nb) = xs.line.normalAt(s);
        const double a1 = m_ * sec.d[cl][j], a2 = m_ * sec.d[cr][j];
        q.left_curb[e] = std::max(a1, a2);
        q.right_curb[e] = std::min(a1, a2);
        const double b1 = m_ * sec.d[ol][j], b2 = m_ * sec.d[orr][j];
        q.left_outer[e] = std::max(b1, b2);
        q.right_outer[e] = std::min(b1, b2);
        q.fade[e] = geom::smoothstep(std::min(s - xs.sb, xs.se - s) / kCrownFadeM);
      }
      impl_->quads.push_back(q);
    }
  }

  int64_t makeRoadLanelet(const CrossSection& xs, const Section& sec, int k, int inner, int outer, int pos, int count,
                          bool pocket) {
    const Side& sd = xs.side[k];
    Lanelet l;
    l.id = nextId();
    l.kind = LaneletKind::kRoad;
    const bool left_is_inner = o_.right_hand_traffic;
    const int left_col = left_is_inner ? inner : outer;
    const int right_col = left_is_inner ? outer : inner;
    l.left_id = sec.line_ids[left_col];
    l.right_id = sec.line_ids[right_col];
    for (size_t i = 0; i < sec.ss.size(); ++i) {
      const double dc = (sec.d[inner][i] + sec.d[outer][i]) / 2.0;
      const Vector2d p = at(xs, sec.ss[i], dc);
      l.centre.emplace_back(p.x(), p.y(), terrainAt(p) + profileForColumn(xs, sec, i, dc));
    }
    if (sd.dir < 0) std::reverse(l.centre.begin(), l.centre.end());
    l.road_id = sd.road_id;
    l.from_node = sd.from_node;
    l.to_node = sd.to_node;
    l.index_from_left = o_.right_hand_traffic ? pos : count - 1 - pos;
    detail::LaneSlot slot;
    slot.cross_section = xs.key;
    slot.dir = sd.dir;
    slot.rank_centre = pos;
    slot.rank_curb = count - 1 - pos;
    impl_->slots[l.id] = slot;
    lanelet_meta_[l.id] = {pocket, pos};
    const int64_t id = l.id;
    pushLanelet(std::move(l));
    ++impl_->stats.road_lanelets;
    return id;
  }

  Lanelet& laneletRef(int64_t id) { return truth().lanelets[lanelet_pos_.at(id)]; }
  void pushLanelet(Lanelet&& l) {
    lanelet_pos_[l.id] = truth().lanelets.size();
    truth().lanelets.push_back(std::move(l));
  }
  void pushLine(LineString&& l) {
    line_pos_[l.id] = truth().lines.size();
    truth().lines.push_back(std::move(l));
  }

  void linkSections(CrossSection& xs) {
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      if (sd.dir == 0) continue;
      const int n = static_cast<int>(xs.sections.size());
      for (int q = 0; q + 1 < n; ++q) {
        const Section& a = sd.dir > 0 ? xs.sections[q] : xs.sections[q + 1];  // predecessor
        const Section& b = sd.dir > 0 ? xs.sections[q + 1] : xs.sections[q];  // successor
        const auto& la = a.lanes[k];
        const auto& lb = b.lanes[k];
        // Match by rank from the curb (pockets appear on the inner side).
        for (size_t i = 0; i < la.size(); ++i) {
          const size_t rank = la.size() - 1 - i;
          if (rank < lb.size()) laneletRef(la[i]).successors.push_back(lb[lb.size() - 1 - rank]);
        }
        if (lb.size() > la.size() && !la.empty()) {  // a pocket opens: the inner lane splits
          for (size_t j = 0; j + la.size() < lb.size(); ++j) laneletRef(la.front()).successors.push_back(lb[j]);
        }
      }
    }
  }

  // Lane ends at both ends of the cross-section; crosswalks and stop lines.
  void buildEnds(CrossSection& xs) {
    auto r = rngFor(o_.seed, xs.ref->id, 5);
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      if (sd.dir == 0) continue;
      // Approach: the last section in the driving direction; departure: the first.
      const Section& last = sd.dir > 0 ? xs.sections.back() : xs.sections.front();
      const Section& first = sd.dir > 0 ? xs.sections.front() : xs.sections.back();
      incoming_[sd.to_node].push_back(laneEnds(xs, last, k, true));
      outgoing_[sd.from_node].push_back(laneEnds(xs, first, k, false));
    }
    // Crosswalks at each end; stop lines for the approaches.
    for (int end = 0; end < 2; ++end) {
      const int64_t node = end == 0 ? xs.ref->from : xs.ref->to;
      const double e = end == 0 ? xs.sb : xs.se;
      const double inward = end == 0 ? +1.0 : -1.0;  // towards the road's middle, in s
      const Vector2d ep = xs.line.pointAt(e);
      end_points_[node].push_back(ep);
      const Section& sec = end == 0 ? xs.sections.front() : xs.sections.back();
      for (int k = 0; k < 2; ++k) {
        const int c = curbColumn(sec, k);
        const size_t i = end == 0 ? 0 : sec.ss.size() - 1;
        end_points_[node].push_back(at(xs, sec.ss[i], sec.d[c][i]));
      }
      if (degree(node) < 3) continue;
      bool crosswalk = false;
      if (xs.se - xs.sb >= 20.0 && chance(r, o_.p_crosswalk)) {
        const double a = e + inward * kCrosswalkSetback, b = e + inward * (kCrosswalkSetback + kCrosswalkDepth);
        const Section* s = sectionContaining(xs, std::min(a, b), std::max(a, b));
        if (s) {
          emitCrosswalk(xs, *s, std::min(a, b), std::max(a, b));
          crosswalk = true;
          ++impl_->stats.crosswalks;
        }
      }
      // The side approaching this end: forward side approaches `to` (end 1), backward `from`.
      const int k = end == 1 ? 0 : 1;
      const Side& sd = xs.side[k];
      if (sd.dir == 0 || sd.to_node != node || xs.se - xs.sb < 10.0 || !chance(r, o_.p_stop_line)) continue;
      const double s_stop = e + inward * (crosswalk ? kCrosswalkSetback + kCrosswalkDepth + 1.0 : 1.0);
      const Section* s = sectionContaining(xs, s_stop - kStopLineWidth, s_stop + kStopLineWidth);
      if (!s) continue;
      emitStopLine(xs, *s, k, s_stop);
    }
  }

  const Section* sectionContaining(const CrossSection& xs, double a, double b) const {
    for (const auto& s : xs.sections) {
      if (a >= s.s0 - 1e-9 && b <= s.s1 + 1e-9) return &s;
    }
    return nullptr;
  }

  Approach laneEnds(const CrossSection& xs, const Section& sec, int k, bool at_end) {
    const Side& sd = xs.side[k];
    Approach ap;
    ap.road_id = sd.road_id;
    ap.xs = xs.key;
    // Sample index of this end: the driving direction's end (approach) or start (departure).
    const bool ref_end = (sd.dir > 0) == at_end;
    const size_t i = ref_end ? sec.ss.size() - 1 : 0;
    const double s = sec.ss[i];
    Vector2d t = xs.line.tangentAt(s) * static_cast<double>(sd.dir);
    for (int64_t id : sec.lanes[k]) {
      const Lanelet& l = laneletRef(id);
      const LineString& lb = lineRef(l.left_id);
      const LineString& rb = lineRef(l.right_id);
      LaneEnd le;
      le.lanelet = id;
      le.centre = (at_end ? l.centre.back() : l.centre.front()).head<2>();
      // Bound points at this end: the bound stored along the driving direction or not.
      auto endOf = [&](const LineString& ls) {
        const Vector2d a = ls.points.front().head<2>(), b = ls.points.back().head<2>();
        return (a - le.centre).norm() < (b - le.centre).norm() ? a : b;
      };
      le.left = endOf(lb);
      le.right = endOf(rb);
      le.width = (le.left - le.right).norm();
      le.tangent = t;
      le.pocket = lanelet_meta_[id].first;
      const int idx = l.index_from_left;
      ap.lanes.resize(std::max<size_t>(ap.lanes.size(), idx + 1));
      ap.lanes[idx] = le;
    }
    // turn:lanes movements (for approaches): the non-pocket lanes in order.
    if (at_end) {
      std::vector<int> regular;
      for (size_t j = 0; j < ap.lanes.size(); ++j) {
        if (!ap.lanes[j].pocket) regular.push_back(static_cast<int>(j));
      }
      // sd.turn is inner -> outer; map to left -> right.
      std::vector<std::string> lr = sd.turn;
      if (!o_.right_hand_traffic) std::reverse(lr.begin(), lr.end());
      if (lr.size() == regular.size()) {
        for (size_t j = 0; j < regular.size(); ++j) ap.lanes[regular[j]].moves = osm::parseTurnLane(lr[j]);
      }
      for (auto& le : ap.lanes) {
        if (le.pocket) {
          le.moves.specified = true;
          le.moves.left = o_.right_hand_traffic;
          le.moves.right = !o_.right_hand_traffic;
        }
      }
    }
    return ap;
  }

  const LineString& lineRef(int64_t id) { return truth().lines[line_pos_.at(id)]; }

  void emitCrosswalk(const CrossSection& xs, const Section& sec, double a, double b) {
    const int cl = curbColumn(sec, 1), cr = curbColumn(sec, 0);
    const double mid = (a + b) / 2.0;
    const auto v = columnValues(xs, sec, mid);
    const double d_hi = std::max(v[cl], v[cr]), d_lo = std::min(v[cl], v[cr]);
    constexpr double kStripe = 0.5, kGap = 0.5;
    for (double d = d_lo + 0.25; d + kStripe <= d_hi - 0.1; d += kStripe + kGap) {
      std::vector<Vector2d> poly = {at(xs, a, d), at(xs, b, d), at(xs, b, d + kStripe), at(xs, a, d + kStripe)};
      addFill(Surface::kCrosswalkPaint, detail::kLayerCrosswalk, std::move(poly));
    }
    // The truth's crosswalk lanelet: its two edges (s = a and s = b) from one curb to the other,
    // the left edge on the walker's left; the road lanelets of both directions under it.
    map::Crosswalk cw;
    cw.id = 0;  // given in run(), after every line and lanelet (their ids stay as they were)
    cw.road_id = xs.ref->id;
    const auto edge = [&](double s) {
      std::vector<Vector3d> e;
      for (double d : {d_lo, d_hi}) {
        const Vector2d p = at(xs, s, d);
        const double l = m_ * v[cl], r = m_ * v[cr];
        e.emplace_back(p.x(), p.y(), terrainAt(p) + profileAt(xs, s, m_ * d, std::max(l, r), std::min(l, r)));
      }
      return e;
    };
    std::vector<Vector3d> ea = edge(a), eb = edge(b);
    const Vector2d w = (ea.back() - ea.front()).head<2>(), q = (eb.front() - ea.front()).head<2>();
    const bool b_left = w.x() * q.y() - w.y() * q.x() > 0.0;
    cw.left = b_left ? eb : ea;
    cw.right = b_left ? ea : eb;
    for (int k = 0; k < 2; ++k) cw.crossing.insert(cw.crossing.end(), sec.lanes[k].begin(), sec.lanes[k].end());
    truth().crosswalks.push_back(std::move(cw));
  }

  // Intersection lanelets whose bounds lie on top of each other share one line string: two of
  // opposite directions along the road's centre line carried through a junction (two opposed
  // straight-on paths, or a left turn and the opposing right turn; the second uses it reversed, as
  // the road lanelets of both directions share their centre line), and two side by side in one
  // direction. Two copies of one border are what Autoware's requirements (lanemap-check
  // shared_borders) forbid.
  void shareOpposedIntersectionBounds() {
    auto& t = truth();
    std::map<int64_t, std::vector<size_t>> by_intersection;
    for (size_t i = 0; i < t.lanelets.size(); ++i) {
      if (t.lanelets[i].kind == LaneletKind::kIntersection) by_intersection[t.lanelets[i].intersection_id].push_back(i);
    }
    const auto near = [](const Vector3d& a, const Vector3d& b) { return (a - b).head<2>().norm() < 0.02; };
    const auto onTop = [&](const LineString& a, const LineString& b, bool reversed) {
      if (a.points.size() < 2 || b.points.size() < 2) return false;
      const Vector3d& b0 = reversed ? b.points.back() : b.points.front();
      const Vector3d& b1 = reversed ? b.points.front() : b.points.back();
      if (!near(a.points.front(), b0) || !near(a.points.back(), b1)) return false;
      const auto inside = [](const LineString& p, const LineString& q) {  // every point of p on q
        for (const auto& x : p.points) {
          double best = 1e9;
          for (size_t k = 0; k + 1 < q.points.size(); ++k) {
            const Vector2d u = q.points[k].head<2>(), v = q.points[k + 1].head<2>();
            const double len2 = (v - u).squaredNorm();
            const double f = len2 > 0.0 ? std::clamp((x.head<2>() - u).dot(v - u) / len2, 0.0, 1.0) : 0.0;
            best = std::min(best, (u + f * (v - u) - x.head<2>()).norm());
          }
          if (best > 0.02) return false;
        }
        return true;
      };
      return inside(a, b) && inside(b, a);
    };
    std::unordered_map<int64_t, int> uses;  // a line another lanelet also uses stays
    for (const auto& l : t.lanelets) {
      ++uses[l.left_id];
      ++uses[l.right_id];
      if (l.stop_line_id) ++uses[*l.stop_line_id];
    }
    std::set<int64_t> dropped;
    for (const auto& [id, idx] : by_intersection) {
      for (size_t a = 0; a < idx.size(); ++a) {
        for (size_t b = a + 1; b < idx.size(); ++b) {
          Lanelet& la = t.lanelets[idx[a]];
          Lanelet& lb = t.lanelets[idx[b]];
          // lb's bound `mine` becomes la's bound `theirs` when they lie on top of each other.
          const auto share = [&](int64_t& mine, int64_t theirs, bool reversed) {
            if (mine == theirs || dropped.count(mine) || dropped.count(theirs) || uses[mine] != 1) return;
            if (!onTop(lineRef(theirs), lineRef(mine), reversed)) return;
            dropped.insert(mine);
            mine = theirs;
          };
          share(lb.left_id, la.left_id, true);    // opposite directions, the centre line
          share(lb.left_id, la.right_id, false);  // side by side in one direction: lb right of la
          share(lb.right_id, la.left_id, false);  // lb left of la
        }
      }
    }
    if (dropped.empty()) return;
    t.lines.erase(std::remove_if(t.lines.begin(), t.lines.end(), [&](const LineString& l) { return dropped.count(l.id) > 0; }),
                  t.lines.end());
    line_pos_.clear();
    for (size_t i = 0; i < t.lines.size(); ++i) line_pos_[t.lines[i].id] = i;
  }

  void emitStopLine(const CrossSection& xs, const Section& sec, int k, double s) {
    const auto v = columnValues(xs, sec, s);
    int anchor = 0, edge = 0;
    for (int c = 0; c < static_cast<int>(sec.cols.size()); ++c) {
      if (sec.cols[c].kind == ColKind::kAnchor) anchor = c;
      if (sec.cols[c].side == k && (sec.cols[c].kind == ColKind::kLaneOuter || sec.cols[c].kind == ColKind::kPocketDiv)) edge = c;
    }
    const double din = v[anchor], dout = v[edge];
    LineString ls;
    ls.id = nextId();
    ls.type = LineType::kStopLine;
    Vector2d pin = at(xs, s, din), pout = at(xs, s, dout);
    const bool left_is_inner = o_.right_hand_traffic;
    Vector2d p0 = left_is_inner ? pin : pout, p1 = left_is_inner ? pout : pin;
    auto z = [&](const Vector2d& p, double dcan) {
      const double l = m_ * v[curbColumn(sec, 1)], r = m_ * v[curbColumn(sec, 0)];
      return terrainAt(p) + profileAt(xs, s, m_ * dcan, std::max(l, r), std::min(l, r));
    };
    ls.points = {Vector3d(p0.x(), p0.y(), z(p0, left_is_inner ? din : dout)),
                 Vector3d(p1.x(), p1.y(), z(p1, left_is_inner ? dout : din))};
    const double h = kStopLineWidth / 2.0;
    addFill(Surface::kStopLinePaint, detail::kLayerStopLine,
            {at(xs, s - h, din), at(xs, s + h, din), at(xs, s + h, dout), at(xs, s - h, dout)});
    for (int64_t id : sec.lanes[k]) laneletRef(id).stop_line_id = ls.id;
    pushLine(std::move(ls));
    ++impl_->stats.stop_lines;
  }

  // ---------- intersections ----------
  static TurnDirection classify(const Vector2d& tin, const Vector2d& tout) {
    return intersections::turnDirection(tin, tout, 40.0);
  }
  // A U-turn: back onto the same road, or a heading change beyond kUturnMinDeg (onto the other
  // carriageway of a dual carriageway, through the median). Not built (no U-turns, METHOD.md 5).
  static bool isUturn(const Approach& a, const Approach& d) {
    constexpr double kUturnMinDeg = 150.0;
    return d.xs == a.xs ||
           std::abs(intersections::headingChange(a.lanes.front().tangent, d.lanes.front().tangent)) >
               kUturnMinDeg * kPi / 180.0;
  }

  void buildIntersection(const skeleton::Intersection& in) {
    auto& ins = incoming_[in.id];
    auto& outs = outgoing_[in.id];
    std::vector<Vector2d> patch_pts = end_points_[in.id];
    double radius = 0.0;
    for (const auto& p : patch_pts) radius = std::max(radius, (p - in.centre).norm());
    for (const Approach& a : ins) {
      std::vector<int> connections(a.lanes.size(), 0);
      const Approach* straightest = nullptr;
      double best_dot = -2.0;
      for (const Approach& d : outs) {
        if (a.lanes.empty() || d.lanes.empty() || isUturn(a, d)) continue;
        const Vector2d tin = a.lanes.front().tangent, tout = d.lanes.front().tangent;
        if (tin.dot(tout) > best_dot) {
          best_dot = tin.dot(tout);
          straightest = &d;
        }
        const TurnDirection turn = classify(tin, tout);
        for (const auto& [i, o] : pairLanes(a, d, turn)) {
          if (connect(in, a.lanes[i], d.lanes[o], turn, &radius)) ++connections[i];
        }
      }
      // No lane may end at an intersection that has a way out: link it straight on.
      if (straightest) {
        for (size_t i = 0; i < a.lanes.size(); ++i) {
          if (connections[i]) continue;
          const size_t o = std::min(i, straightest->lanes.size() - 1);
          connect(in, a.lanes[i], straightest->lanes[o], classify(a.lanes[i].tangent, straightest->lanes[o].tangent), &radius);
        }
      }
    }
    if (!in.dead_end && patch_pts.size() >= 3) {
      auto hull = convexHull(patch_pts);
      if (hull.size() >= 3) {
        impl_->flat_polygons.push_back(hull);
        addFill(Surface::kIntersection, detail::kLayerIntersection, hull);
      }
    }
    zones_circles_.push_back({in.centre, radius});
  }

  // (incoming lane, outgoing lane) pairs for one movement (METHOD.md 5 + our rules): straight k->k
  // from the left over lanes that may go straight; left turns from the left-most lane(s), right
  // turns from the right-most, honouring turn:lanes where tagged.
  std::vector<std::pair<int, int>> pairLanes(const Approach& a, const Approach& d, TurnDirection turn) const {
    std::vector<std::pair<int, int>> out;
    const int nin = static_cast<int>(a.lanes.size()), nout = static_cast<int>(d.lanes.size());
    bool any_specified = false;
    for (const auto& l : a.lanes) any_specified |= l.moves.specified;
    std::vector<int> cand;
    if (turn == TurnDirection::kStraight) {
      for (int i = 0; i < nin; ++i) {
        const auto& m = a.lanes[i].moves;
        if (!m.specified || m.straight) cand.push_back(i);
      }
      for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) out.emplace_back(cand[j], j);
      return out;
    }
    const bool left = turn == TurnDirection::kLeft;
    for (int i = 0; i < nin; ++i) {
      const auto& m = a.lanes[i].moves;
      if (m.specified && (left ? m.left : m.right)) cand.push_back(i);
    }
    if (cand.empty()) {
      if (any_specified) {
        // Tagged lanes with no such movement: only an untagged edge lane may turn.
        const int edge = left ? 0 : nin - 1;
        if (a.lanes[edge].moves.specified) return out;
      }
      cand.push_back(left ? 0 : nin - 1);
    }
    if (left) {
      for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) out.emplace_back(cand[j], j);
    } else {
      for (int j = 0; j < static_cast<int>(cand.size()) && j < nout; ++j) {
        out.emplace_back(cand[cand.size() - 1 - j], nout - 1 - j);
      }
    }
    return out;
  }

  // Lanelet2's loader reads the lanelet as meant (io::orientationProblem), also once simplified as
  // groundtruth.osm is written.
  static bool lanelet2ReadsAsMeant(const Lanelet& l, const LineString& left, const LineString& right) {
    if (!io::orientationProblem(l, left, right).empty()) return false;
    Lanelet ls = l;
    LineString lefts = left, rights = right;
    ls.centre = map::simplifyPolyline(l.centre, kTruthSimplifyTolerance);
    lefts.points = map::simplifyPolyline(left.points, kTruthSimplifyTolerance);
    rights.points = map::simplifyPolyline(right.points, kTruthSimplifyTolerance);
    return io::orientationProblem(ls, lefts, rights).empty();
  }

  // An intersection lanelet is sound when its outline is a simple polygon (its bounds do not cross)
  // and Lanelet2 reads it as meant.
  static bool connectionIsSound(const Lanelet& l, const LineString& left, const LineString& right) {
    const auto xy = [](const std::vector<Vector3d>& p) {
      std::vector<Vector2d> out;
      for (const auto& q : p) out.push_back(q.head<2>());
      return out;
    };
    return intersections::outlineIsSimple(xy(left.points), xy(right.points)) && lanelet2ReadsAsMeant(l, left, right);
  }

  // Builds the intersection lanelet a -> b. Not built (false, counted) when it is not sound (see
  // connectionIsSound): a sharp connection between lane ends that overlap, at the junctions of
  // roads too short for their trims (a few dozen of Monaco's ~6,000 connections).
  bool connect(const skeleton::Intersection& in, const LaneEnd& a, const LaneEnd& b, TurnDirection turn, double* radius) {
    intersections::CurveOptions curve_options;
    curve_options.step_m = 0.5;
    const auto curve = intersections::bezierConnection(a.centre, a.tangent, b.centre, b.tangent, curve_options)
                           .sample(curve_options.step_m);
    const auto bounds = intersections::connectorBounds(a.left, a.right, a.tangent, b.left, b.right, b.tangent,
                                                       curve_options, &curve);
    const auto& left = bounds.left;
    const auto& right = bounds.right;
    auto lift = [&](const std::vector<Vector2d>& pts) {
      std::vector<Vector3d> out;
      for (const auto& p : pts) out.emplace_back(p.x(), p.y(), terrainAt(p));
      return out;
    };
    LineString lb, rb;
    lb.type = LineType::kVirtual;
    lb.points = lift(left);
    rb.type = LineType::kVirtual;
    rb.points = lift(right);
    // Keep the joints' heights equal to the road lanes' (crown faded to 0 there anyway).
    Lanelet l;
    l.kind = LaneletKind::kIntersection;
    l.centre = lift(curve);
    l.centre.front() = laneletRef(a.lanelet).centre.back();
    l.centre.back() = laneletRef(b.lanelet).centre.front();
    if (!connectionIsSound(l, lb, rb)) {
      ++impl_->stats.connections_not_built;
      return false;
    }
    lb.id = nextId();
    rb.id = nextId();
    l.id = nextId();
    l.left_id = lb.id;
    l.right_id = rb.id;
    l.successors = {b.lanelet};
    l.turn = turn;
    l.intersection_id = in.id;
    for (const auto& p : curve) *radius = std::max(*radius, (p - in.centre).norm() + std::max(a.width, b.width) / 2);
    std::vector<Vector2d> poly = left;
    poly.insert(poly.end(), right.rbegin(), right.rend());
    addFill(Surface::kIntersection, detail::kLayerIntersection, std::move(poly));
    pushLine(std::move(lb));
    pushLine(std::move(rb));
    laneletRef(a.lanelet).successors.push_back(l.id);
    pushLanelet(std::move(l));
    ++impl_->stats.intersection_lanelets;
    return true;
  }

  static std::vector<Vector2d> convexHull(std::vector<Vector2d> p) {
    std::sort(p.begin(), p.end(), [](const Vector2d& a, const Vector2d& b) {
      return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    if (p.size() < 3) return p;
    std::vector<Vector2d> h(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {
      while (k >= 2 && geom::cross(h[k - 1] - h[k - 2], p[i] - h[k - 2]) <= 0) --k;
      h[k++] = p[i];
    }
    for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
      while (k >= t && geom::cross(h[k - 1] - h[k - 2], p[i - 1] - h[k - 2]) <= 0) --k;
      h[k++] = p[i - 1];
    }
    h.resize(k - 1);
    return h;
  }

  // ---------- obstacles ----------
  struct Circle {
    Vector2d c;
    double r;
  };

  void indexZones() {
    for (const auto& xs : xss_) {
      const auto samples = xs.line.samplesBetween(xs.sb, xs.se);
      for (size_t i = 0; i + 1 < samples.size(); ++i) {
        ZoneSeg z;
        z.a = xs.line.pointAt(samples[i]);
        z.b = xs.line.pointAt(samples[i + 1]);
        z.left = std::max(0.0, xs.left_extent);
        z.right = std::max(0.0, -xs.right_extent);
        z.xs = xs.key;
        const double ext = std::max(z.left, z.right) + 1.0;
        Eigen::AlignedBox2d box;
        box.extend(z.a);
        box.extend(z.b);
        const uint32_t idx = static_cast<uint32_t>(zones_.size());
        zones_.push_back(z);
        forCells(box.min() - Vector2d(ext, ext), box.max() + Vector2d(ext, ext), [&](int64_t key) { zone_grid_[key].push_back(idx); });
      }
    }
  }

  template <typename F>
  void forCells(const Vector2d& lo, const Vector2d& hi, F f) const {
    const int64_t x0 = static_cast<int64_t>(std::floor(lo.x() / kZoneCell)), x1 = static_cast<int64_t>(std::floor(hi.x() / kZoneCell));
    const int64_t y0 = static_cast<int64_t>(std::floor(lo.y() / kZoneCell)), y1 = static_cast<int64_t>(std::floor(hi.y() / kZoneCell));
    for (int64_t x = x0; x <= x1; ++x) {
      for (int64_t y = y0; y <= y1; ++y) f((x << 32) ^ (y & 0xffffffffLL));
    }
  }

  // True when the rectangle keeps clear of every road (but `skip_xs`) and intersection.
  bool clearOfRoads(const geom::Rect& r, int64_t skip_xs, double margin) const {
    Eigen::AlignedBox2d box;
    for (const auto& c : r.corners()) box.extend(c);
    bool clear = true;
    forCells(box.min(), box.max(), [&](int64_t key) {
      if (!clear) return;
      auto it = zone_grid_.find(key);
      if (it == zone_grid_.end()) return;
      for (uint32_t idx : it->second) {
        const ZoneSeg& z = zones_[idx];
        if (z.xs == skip_xs) continue;
        const double side = geom::cross(z.b - z.a, r.c - z.a);
        const double need = (side > 0 ? z.left : z.right) + margin;
        if (geom::rectSegmentDistance(r, z.a, z.b) < need) {
          clear = false;
          return;
        }
      }
    });
    if (!clear) return false;
    const auto k = r.corners();
    forCells(box.min(), box.max(), [&](int64_t key) {
      if (!clear) return;
      auto it = circle_grid_.find(key);
      if (it == circle_grid_.end()) return;
      for (uint32_t idx : it->second) {
        const Circle& c = zones_circles_[idx];
        double d = r.contains(c.c) ? 0.0 : 1e300;
        for (int i = 0; i < 4; ++i) d = std::min(d, geom::pointSegmentDistance(c.c, k[i], k[(i + 1) % 4]));
        if (d < c.r + margin) {
          clear = false;
          return;
        }
      }
    });
    return clear;
  }

  bool clearOfBuildings(const geom::Rect& r) const {
    Eigen::AlignedBox2d box;
    for (const auto& c : r.corners()) box.extend(c);
    bool clear = true;
    forCells(box.min(), box.max(), [&](int64_t key) {
      if (!clear) return;
      auto it = building_grid_.find(key);
      if (it == building_grid_.end()) return;
      for (uint32_t idx : it->second) {
        if (geom::rectsOverlap(building_rects_[idx], r)) {
          clear = false;
          return;
        }
      }
    });
    return clear;
  }

  void addBuildingRect(const geom::Rect& r) {
    Eigen::AlignedBox2d box;
    for (const auto& c : r.corners()) box.extend(c);
    const uint32_t idx = static_cast<uint32_t>(building_rects_.size());
    building_rects_.push_back(r);
    forCells(box.min(), box.max(), [&](int64_t key) { building_grid_[key].push_back(idx); });
  }

  Eigen::Vector3f randomColour(std::mt19937_64& r, bool car) {
    if (car) {
      static const float palette[][3] = {{0.8f, 0.1f, 0.1f}, {0.1f, 0.2f, 0.7f}, {0.9f, 0.9f, 0.9f},
                                         {0.1f, 0.1f, 0.1f}, {0.5f, 0.5f, 0.55f}, {0.2f, 0.5f, 0.2f}};
      const auto& c = palette[std::uniform_int_distribution<int>(0, 5)(r)];
      return Eigen::Vector3f(c[0], c[1], c[2]);
    }
    const float g = static_cast<float>(uni(r, 0.45, 0.85));
    return Eigen::Vector3f(g, static_cast<float>(g * uni(r, 0.85, 1.0)), static_cast<float>(g * uni(r, 0.75, 1.0)));
  }

  void placeObstacles() {
    indexZones();
    for (uint32_t i = 0; i < zones_circles_.size(); ++i) {
      const Circle& c = zones_circles_[i];
      const Vector2d e(c.r + 1.0, c.r + 1.0);
      forCells(c.c - e, c.c + e, [&](int64_t key) { circle_grid_[key].push_back(i); });
    }
    for (const auto& xs : xss_) {
      auto r = rngFor(o_.seed, xs.ref->id, 6);
      placeParkedCars(xs, r);
      placeBuildings(xs, r);
    }
  }

  void addCar(const CrossSection& xs, std::mt19937_64& r, const geom::Rect& rect, double s, double dcan) {
    Obstacle o;
    o.kind = Obstacle::Kind::kParkedCar;
    const double ground = terrainAt(rect.c) + profileAt(xs, s, m_ * dcan, 1e9, -1e9);
    o.centre = Vector3d(rect.c.x(), rect.c.y(), ground + 0.75);
    o.yaw = std::atan2(rect.axis.y(), rect.axis.x());
    o.half_extent = Vector3d(rect.hl, rect.hw, 0.75);
    o.colour = randomColour(r, true);
    impl_->obstacles.push_back(o);
    ++impl_->stats.parked_cars;
  }

  // A car stopped at the curb of a bus bay (asphalt beside the lanes, not a driving lane).
  void placeBayCar(const CrossSection& xs, int k, std::mt19937_64& r) {
    const Side& sd = xs.side[k];
    if (!sd.bay || !chance(r, 0.5)) return;
    const double mid = (sd.bay_s0 + sd.bay_s1) / 2.0;
    const Section* sec = sectionContaining(xs, sd.bay_s0, sd.bay_s1);
    if (!sec) return;
    const auto v = columnValues(xs, *sec, mid);
    int edge_col = -1, lane_col = -1;
    for (int c = 0; c < static_cast<int>(sec->cols.size()); ++c) {
      if (sec->cols[c].side != k) continue;
      if (sec->cols[c].kind == ColKind::kEdgeOuter) edge_col = c;
      if (sec->cols[c].kind == ColKind::kLaneOuter && sec->cols[c].lane + 1 == static_cast<int>(sd.lane_w.size())) lane_col = c;
    }
    if (edge_col < 0 || lane_col < 0) return;
    const double len = 4.6;
    if (xs.line.tangentAt(mid - len).dot(xs.line.tangentAt(mid + len)) < std::cos(5.0 * kPi / 180.0)) return;
    const double dmid = (v[edge_col] + v[lane_col]) / 2.0;
    geom::Rect rect;
    rect.c = at(xs, mid, dmid);
    rect.axis = xs.line.tangentAt(mid) * static_cast<double>(sd.dir);
    rect.hl = len / 2.0;
    rect.hw = 0.9;
    if (clearOfRoads(rect, xs.key, 0.2)) addCar(xs, r, rect, mid, dmid);
  }

  void placeParkedCars(const CrossSection& xs, std::mt19937_64& r) {
    for (int k = 0; k < 2; ++k) placeBayCar(xs, k, r);
    for (int k = 0; k < 2; ++k) {
      const Side& sd = xs.side[k];
      if (sd.edge != Edge::kParking) continue;
      const double lo = xs.sb + 6.0, hi = xs.se - 6.0;
      double s = lo + uni(r, 0.0, 3.0);
      while (true) {
        const double len = uni(r, 4.2, 4.9);
        if (s + len > hi) break;
        const double mid = s + len / 2.0;
        const Section* sec = sectionContaining(xs, s, s + len);
        // A straight car fits a curved strip only where the road bends little (< 5 deg over it).
        const bool straight = xs.line.tangentAt(s).dot(xs.line.tangentAt(s + len)) > std::cos(5.0 * kPi / 180.0);
        if (sec && straight && chance(r, o_.parked_car_occupancy)) {
          const auto v = columnValues(xs, *sec, mid);
          int edge_col = -1, lane_col = -1;
          for (int c = 0; c < static_cast<int>(sec->cols.size()); ++c) {
            if (sec->cols[c].side != k) continue;
            if (sec->cols[c].kind == ColKind::kEdgeOuter) edge_col = c;
            if (sec->cols[c].kind == ColKind::kLaneOuter && sec->cols[c].lane + 1 == static_cast<int>(sd.lane_w.size())) lane_col = c;
          }
          // Nor where the strip shifts sideways (a turn pocket's taper).
          const auto va = columnValues(xs, *sec, s), vb = columnValues(xs, *sec, s + len);
          const bool steady = edge_col >= 0 && lane_col >= 0 &&
                              std::abs(va[edge_col] + va[lane_col] - v[edge_col] - v[lane_col]) < 0.1 &&
                              std::abs(vb[edge_col] + vb[lane_col] - v[edge_col] - v[lane_col]) < 0.1;
          if (steady) {
            const double dmid = (v[edge_col] + v[lane_col]) / 2.0;
            geom::Rect rect;
            rect.c = at(xs, mid, dmid);
            rect.axis = xs.line.tangentAt(mid) * static_cast<double>(sd.dir == 0 ? 1 : sd.dir);
            rect.hl = len / 2.0;
            rect.hw = 0.9;
            if (clearOfRoads(rect, xs.key, 0.2)) addCar(xs, r, rect, mid, dmid);
          }
        }
        s += len + uni(r, 0.8, 3.0);
      }
    }
  }

  void placeBuildings(const CrossSection& xs, std::mt19937_64& r) {
    const double L = xs.se - xs.sb;
    if (L < 12.0) return;
    for (int k = 0; k < 2; ++k) {
      // Actual side: +1 left of the reference line, -1 right.
      const double side = (k == 1 ? 1.0 : -1.0) * m_;
      const double extent = side > 0 ? xs.left_extent : -xs.right_extent;
      double s = xs.sb + 3.0 + uni(r, 0.0, 4.0);
      while (true) {
        const double len = uni(r, 8.0, 20.0);
        if (s + len > xs.se - 3.0) break;
        const double depth = uni(r, 8.0, 14.0);
        const double setback = uni(r, 1.5, 5.0);
        const double height = uni(r, 4.0, 18.0);
        if (chance(r, o_.p_building)) {
          const double mid = s + len / 2.0;
          const Vector2d t = xs.line.tangentAt(mid);
          geom::Rect rect;
          rect.axis = t;
          rect.hl = len / 2.0;
          rect.hw = depth / 2.0;
          rect.c = xs.line.offsetPoint(mid, side * (extent + setback + depth / 2.0));
          if (clearOfRoads(rect, -1, 0.5) && clearOfBuildings(rect)) {
            double ground = 1e300;
            for (const auto& c : rect.corners()) ground = std::min(ground, terrainAt(c));
            Obstacle o;
            o.kind = Obstacle::Kind::kBuilding;
            o.centre = Vector3d(rect.c.x(), rect.c.y(), ground + height / 2.0 - 0.5);
            o.yaw = std::atan2(t.y(), t.x());
            o.half_extent = Vector3d(rect.hl, rect.hw, height / 2.0 + 0.5);  // sunk 0.5 m on slopes
            o.colour = randomColour(r, false);
            impl_->obstacles.push_back(o);
            addBuildingRect(rect);
            ++impl_->stats.buildings;
          }
        }
        s += len + uni(r, 2.0, 8.0);
      }
    }
  }

  void fillStats() {
    WorldStats& st = impl_->stats;
    st.lines = truth().lines.size();
    st.turn_pockets = 0;
    double km = 0.0;
    for (const auto& xs : xss_) {
      for (int k = 0; k < 2; ++k) st.turn_pockets += xs.side[k].pocket ? 1 : 0;
    }
    for (const auto& l : truth().lanelets) {
      if (l.kind != LaneletKind::kRoad) continue;
      for (size_t i = 1; i < l.centre.size(); ++i) km += (l.centre[i] - l.centre[i - 1]).head<2>().norm();
    }
    st.driving_lane_km = km / 1000.0;
  }

  static constexpr double kZoneCell = 25.0;
  const skeleton::Skeleton& sk_;
  WorldOptions o_;
  double m_;  // +1 right-hand traffic, -1 mirrored
  std::unique_ptr<SimWorld::Impl> impl_;
  int64_t next_id_ = 1;
  std::vector<CrossSection> xss_;
  std::unordered_map<int64_t, int64_t> xs_of_road_;
  std::unordered_map<int64_t, int> degree_;
  std::unordered_map<int64_t, double> min_trim_;
  std::unordered_map<int64_t, std::pair<bool, int>> lanelet_meta_;  // pocket, position
  std::unordered_map<int64_t, size_t> lanelet_pos_, line_pos_;
  std::map<int64_t, std::vector<Approach>> incoming_, outgoing_;
  std::map<int64_t, std::vector<Vector2d>> end_points_;
  std::vector<ZoneSeg> zones_;
  std::unordered_map<int64_t, std::vector<uint32_t>> zone_grid_;
  std::vector<Circle> zones_circles_;
  std::vector<geom::Rect> building_rects_;
  std::unordered_map<int64_t, std::vector<uint32_t>> circle_grid_, building_grid_;
};

}  // namespace

std::unique_ptr<SimWorld> buildWorld(const skeleton::Skeleton& skeleton, const WorldOptions& options) {
  options.validate();
  Builder b(skeleton, options);
  return std::make_unique<SimWorld>(b.run());
}

}  // namespace lanemap::sim
