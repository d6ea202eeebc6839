// The world builder's parts (buildWorld, core/sim/world_builder.h): the Builder class and the
// cross-section types that the files implementing it share, one job a file:
//   world_builder.cc         buildWorld and the order of the jobs (Builder::run)
//   world_surface.cc         the terrain and the road surface's profile (crown, curbs)
//   world_cross_sections.cc  cross-sections, their sections, the roads' lanelets and lines
//   world_paint.cc           paint and fills: markings, crosswalks, stop lines
//   world_junctions.cc       intersection lanelets (the truth's own pairing rules)
//   world_obstacles.cc       parked cars and buildings
// Private to core/sim.
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
#pragma once

#include "core/intersections/curve.h"
#include "core/io/lanelet2_orientation.h"
#include "core/map/simplify.h"
#include "core/osm/turn_lanes.h"
#include "core/sim/world_builder.h"
#include "core/sim/world_geometry.h"
#include "core/sim/world_scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace lanemap::sim::world_build {

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

inline uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Independent, order-free random streams: one per (seed, object, purpose).
inline std::mt19937_64 rngFor(uint64_t seed, int64_t object, uint64_t purpose) {
  return std::mt19937_64(mix64(mix64(seed) ^ mix64(static_cast<uint64_t>(object) * 31 + purpose)));
}
inline double uni(std::mt19937_64& r, double a, double b) { return std::uniform_real_distribution<double>(a, b)(r); }
inline bool chance(std::mt19937_64& r, double p) { return uni(r, 0.0, 1.0) < p; }

inline std::string baseClass(const std::string& highway) {
  if (highway.size() > 5 && highway.substr(highway.size() - 5) == "_link") return highway.substr(0, highway.size() - 5);
  return highway;
}
inline bool isMajor(const std::string& c) { return c == "primary" || c == "secondary" || c == "tertiary" || c == "trunk"; }
inline bool isMinorStreet(const std::string& c) {
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
  Builder(const skeleton::Skeleton& sk, const WorldOptions& o, const std::vector<osm::Restriction>& restrictions)
      : sk_(sk), o_(o), restrictions_(restrictions), m_(o.right_hand_traffic ? 1.0 : -1.0) {
    impl_ = std::make_unique<SimWorld::Impl>();
    impl_->options = o;
    impl_->right_hand = o.right_hand_traffic;
  }

  std::unique_ptr<SimWorld::Impl> run();

 private:
  map::LaneMap& truth() { return impl_->truth; }
  int64_t nextId() { return next_id_++; }

  // ---------- surface (world_surface.cc) ----------
  void makeTerrain();

  double terrainAt(const Vector2d& p) const { return o_.flat ? 0.0 : impl_->terrain.at(p.x(), p.y()); }

  // Road-surface offset of a point at actual offset d of a cross-section (crown, curb step).
  double profileAt(const CrossSection& xs, double s, double d, double left_curb, double right_curb) const;

  // ---------- cross-sections (world_cross_sections.cc; addFill, stripPolygon, emitLinePaint,
  // emitStroke, chooseGaps, emitCrosswalk, emitStopLine: world_paint.cc) ----------
  void groupCrossSections();
  void layoutCrossSection(CrossSection& xs);

  // How far from each junction the lanes of every incident cross-section end (its trim there): the
  // widest carriageway half width at the junction + 1 m. (A rule that also cleared the corners of
  // roads meeting at acute angles, (h_i + h_j) / sin theta, made the truth's lanes end up to 25 m
  // before such junctions, where lanemap's mapper, which ends lanes at the OSM junction's ROI,
  // cannot follow: West Oakland's oracle intersection RMS went from 0.07 to 0.47 m. Not used.)
  void computeNodeInfo();
  int degree(int64_t node) const;

  // Canonical offsets of a section's columns at s.
  std::vector<double> columnValues(const CrossSection& xs, const Section& sec, double s) const;
  std::vector<Column> columnTemplate(const CrossSection& xs, const Section& sec) const;
  LineType lineTypeOf(const CrossSection& xs, const Section& sec, const Column& c) const;
  void chooseTrim(CrossSection& xs);
  void choosePocketsAndBays(CrossSection& xs);

  // The section's columns: template, samples and offsets (what buildSection lays its lines on).
  void fillColumns(const CrossSection& xs, Section& sec) const;

  // A boundary line of a section as buildSection makes it (before its id, type and direction).
  std::vector<Vector3d> boundaryPoints(const CrossSection& xs, const Section& sec, int col) const;

  // The lanes of one side of a section as (inner column, outer column), inner -> outer.
  std::vector<std::pair<int, int>> laneColumns(const Section& sec, int k) const;

  // True when Lanelet2 would read every lanelet of the section as meant.
  bool sectionIsSound(const CrossSection& xs, Section sec) const;

  // Where half of the reference line's heading change over [s0, s1] is done (a hairpin's tip).
  double halfTurn(const CrossSection& xs, double s0, double s1) const;
  std::vector<Section> makeSections(const CrossSection& xs) const;

  // Index of the curb column of a side (its outermost carriageway edge) in a section; the anchor
  // when the side has none. Columns run left to right: side 1 first (outer to inner), side 0 last.
  int curbColumn(const Section& sec, int k) const { return edgeColumn(sec, k, false); }
  // Index of the outermost column of a side (sidewalk edge when there is a sidewalk).
  int outerColumn(const Section& sec, int k) const { return edgeColumn(sec, k, true); }
  int edgeColumn(const Section& sec, int k, bool with_sidewalk) const;
  Vector2d at(const CrossSection& xs, double s, double canonical_d) const;

  // Road-surface offset at canonical column value d of a section at sample index i.
  double profileForColumn(const CrossSection& xs, const Section& sec, size_t i, double dcan) const;
  std::vector<Vector2d> columnPoints(const CrossSection& xs, const Section& sec, int col) const;
  std::vector<Vector3d> columnPoints3(const CrossSection& xs, const Section& sec, int col) const;
  void addFill(Surface s, detail::Layer layer, std::vector<Vector2d> poly, int64_t lanelet = -1, bool faded = false);
  std::vector<Vector2d> stripPolygon(const CrossSection& xs, const Section& sec, int ca, int cb) const;

  // Marking paint of one LineString (2-D points), with its worn and missing stretches.
  void emitLinePaint(const std::vector<Vector2d>& pts, LineType type, double outward, const std::vector<MarkingGap>& gaps);

  // A band of `width` centred `offset` to the left of the sub-polyline [a, b] (arc lengths).
  void emitStroke(const std::vector<Vector2d>& pts, const std::vector<double>& cum, double a, double b, double offset,
                  double width, Surface surface, detail::Layer layer, bool faded);
  std::vector<MarkingGap> chooseGaps(int64_t line_id, LineType type, double length);
  void buildCrossSection(CrossSection& xs);
  void buildSection(CrossSection& xs, Section& sec);

  int64_t makeRoadLanelet(const CrossSection& xs, const Section& sec, int k, int inner, int outer, int pos, int count,
                          bool pocket);

  Lanelet& laneletRef(int64_t id) { return truth().lanelets[lanelet_pos_.at(id)]; }
  void pushLanelet(Lanelet&& l);
  void pushLine(LineString&& l);
  void linkSections(CrossSection& xs);

  // Lane ends at both ends of the cross-section; crosswalks and stop lines.
  void buildEnds(CrossSection& xs);
  const Section* sectionContaining(const CrossSection& xs, double a, double b) const;
  Approach laneEnds(const CrossSection& xs, const Section& sec, int k, bool at_end);

  const LineString& lineRef(int64_t id) { return truth().lines[line_pos_.at(id)]; }

  void emitCrosswalk(const CrossSection& xs, const Section& sec, double a, double b);

  // Intersection lanelets whose bounds lie on top of each other share one line string: two of
  // opposite directions along the road's centre line carried through a junction (two opposed
  // straight-on paths, or a left turn and the opposing right turn; the second uses it reversed, as
  // the road lanelets of both directions share their centre line), and two side by side in one
  // direction. Two copies of one border are what Autoware's requirements (lanemap-check
  // shared_borders) forbid.
  void shareOpposedIntersectionBounds();
  void emitStopLine(const CrossSection& xs, const Section& sec, int k, double s);

  // ---------- intersections (world_junctions.cc) ----------
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

  void buildIntersection(const skeleton::Intersection& in);
  bool turnRestricted(const Approach& a, const Approach& d) const;

  // (incoming lane, outgoing lane) pairs for one movement (METHOD.md 5 + our rules): straight k->k
  // from the left over lanes that may go straight; left turns from the left-most lane(s), right
  // turns from the right-most, honouring turn:lanes where tagged.
  std::vector<std::pair<int, int>> pairLanes(const Approach& a, const Approach& d, TurnDirection turn) const;

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
  bool connect(const skeleton::Intersection& in, const LaneEnd& a, const LaneEnd& b, TurnDirection turn, double* radius);

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

  // ---------- obstacles (world_obstacles.cc; fillStats: world_builder.cc) ----------
  struct Circle {
    Vector2d c;
    double r;
  };
  void indexZones();

  template <typename F>
  void forCells(const Vector2d& lo, const Vector2d& hi, F f) const {
    const int64_t x0 = static_cast<int64_t>(std::floor(lo.x() / kZoneCell)), x1 = static_cast<int64_t>(std::floor(hi.x() / kZoneCell));
    const int64_t y0 = static_cast<int64_t>(std::floor(lo.y() / kZoneCell)), y1 = static_cast<int64_t>(std::floor(hi.y() / kZoneCell));
    for (int64_t x = x0; x <= x1; ++x) {
      for (int64_t y = y0; y <= y1; ++y) f((x << 32) ^ (y & 0xffffffffLL));
    }
  }

  // False as soon as `blocks(i)` holds for an item i indexed in `grid` (a cell map of forCells) over
  // the cells of the rectangle's bounding box; true when none does.
  template <typename F>
  bool noneBlocks(const std::unordered_map<int64_t, std::vector<uint32_t>>& grid, const geom::Rect& r, F blocks) const {
    Eigen::AlignedBox2d box;
    for (const auto& c : r.corners()) box.extend(c);
    bool clear = true;
    forCells(box.min(), box.max(), [&](int64_t key) {
      if (!clear) return;
      auto it = grid.find(key);
      if (it == grid.end()) return;
      for (uint32_t idx : it->second) {
        if (blocks(idx)) {
          clear = false;
          return;
        }
      }
    });
    return clear;
  }

  // True when the rectangle keeps clear of every road (but `skip_xs`) and intersection.
  bool clearOfRoads(const geom::Rect& r, int64_t skip_xs, double margin) const;
  bool clearOfBuildings(const geom::Rect& r) const;
  void addBuildingRect(const geom::Rect& r);
  Eigen::Vector3f randomColour(std::mt19937_64& r, bool car);
  void placeObstacles();
  void addCar(const CrossSection& xs, std::mt19937_64& r, const geom::Rect& rect, double s, double dcan);

  // A car stopped at the curb of a bus bay (asphalt beside the lanes, not a driving lane).
  // The columns of side k's edge strip (parking, bike lane, bus bay) in a section: its outer edge
  // and the outer edge of the outermost lane (-1 where there is none).
  std::pair<int, int> edgeStripColumns(const Section& sec, int k, const Side& sd) const;
  void placeBayCar(const CrossSection& xs, int k, std::mt19937_64& r);
  void placeParkedCars(const CrossSection& xs, std::mt19937_64& r);
  void placeBuildings(const CrossSection& xs, std::mt19937_64& r);
  void fillStats();
  static constexpr double kZoneCell = 25.0;
  const skeleton::Skeleton& sk_;
  WorldOptions o_;
  const std::vector<osm::Restriction>& restrictions_;
  double m_;  // +1 right-hand traffic, -1 mirrored
  std::unique_ptr<SimWorld::Impl> impl_;
  int64_t next_id_ = 1;
  int fill_level_ = 0;  // the OSM level of what is being painted (WorldOptions::osm_layers)
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

}  // namespace lanemap::sim::world_build
