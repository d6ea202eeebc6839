// Internal to the simulator's Lanelet2 world (lanelet2_world.h has the rules): the helpers and
// the Builder, whose steps are defined one job a file:
//   lanelet2_world.cc           polylines, the file's extras, build() and the entry points
//   lanelet2_world_lanelets.cc  steps 1-6: vehicle lanelets, successors, lateral neighbours,
//                               junction lanelets, junction areas, roads
//   lanelet2_world_osm.cc       step 7: the road-level OSM and the skeleton
//   lanelet2_world_truth.cc     step 8: the truth lanelets labelled
//   lanelet2_world_scene.cc     step 9: the scene painted
#pragma once

#include "core/io/lanelet2.h"
#include "core/sim/lanelet2_world.h"
#include "core/sim/world_geometry.h"
#include "core/sim/world_scene.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::sim::l2w {

using Eigen::Vector2d;
using Eigen::Vector3d;
using map::LaneletKind;
using map::LineType;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kCurbWidth = 0.15;       // curb band (as the OSM world builder paints it)
inline constexpr double kSidewalkWidth = 2.0;    // sidewalk band behind a curb
inline constexpr double kStopLineWidth = 0.4;
inline constexpr double kSuccessorGap = 0.2;     // bound ends this close: one lanelet follows the other
inline constexpr double kCastStep = 0.2;         // lateral casts (lane counts, road middle)
inline constexpr double kCastGap = 0.6;          // a cast stops after this much off the lanes
inline constexpr double kCastMax = 25.0;
inline constexpr double kMinRoadLength = 8.0;    // shorter road stubs beside a junction belong to it

// ---------- polylines ----------
double length(const std::vector<Vector2d>& p);

std::vector<Vector2d> xy(const std::vector<Vector3d>& pts);

// n points evenly spaced by arc length (n >= 2).
std::vector<Vector2d> resample(const std::vector<Vector2d>& p, size_t n);

std::vector<Vector2d> resampleSpacing(const std::vector<Vector2d>& p, double spacing);

struct Projection {
  double distance = std::numeric_limits<double>::infinity();
  double s = 0.0;
  Vector2d point = Vector2d::Zero();
  Vector2d tangent = Vector2d::UnitX();
};

Projection project(const std::vector<Vector2d>& p, const Vector2d& q);

Vector2d direction(const std::vector<Vector2d>& p);

double headingChange(const std::vector<Vector2d>& c);

// Douglas-Peucker on 2-D points.
void simplifyInto(const std::vector<Vector2d>& p, size_t i0, size_t i1, double tol, std::vector<char>& keep);
std::vector<Vector2d> simplify(const std::vector<Vector2d>& p, double tol);

struct UnionFind {
  std::vector<size_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), size_t{0}); }
  size_t find(size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(size_t a, size_t b) { parent[find(a)] = find(b); }
};

// ---------- what the file says beyond io::Lanelet2File ----------
struct Extra {
  std::map<int64_t, std::string> one_way;  // lanelet relation id -> one_way tag
  double min_lat = 1e9, max_lat = -1e9, min_lon = 1e9, max_lon = -1e9;
  size_t nodes = 0;
};

Extra readExtra(const std::string& path);

bool isVehicleSubtype(const std::string& s);

bool isTwoWay(const std::string& subtype, const std::string& one_way);

// ---------- the lanelets being built ----------
struct VL {
  map::Lanelet ll;
  std::vector<Vector2d> left, right, centre;  // in the driving direction
  std::vector<Vector2d> poly;
  Eigen::AlignedBox2d box;
  int64_t left_key = 0, right_key = 0;        // original way of each bound
  std::vector<size_t> succ, pred;
  std::set<size_t> lateral;                   // side-by-side vehicle lanelets
  bool junction = false;
  int comp = -1, area = -1;
  int left_same = 0, right_same = 0;          // same-direction lanes to the left / right
};

void finishGeometry(VL& v);

bool inside(const VL& v, const Vector2d& p);

// Lanelets whose box is within `margin` of `box`.
std::vector<size_t> near(const std::vector<VL>& vls, const Eigen::AlignedBox2d& box, double margin);

// A cast from p along unit vector n over the lanelets `cands`: the lanelets met in order (each
// once) until the cast has been off them for kCastGap; `extent` = the last distance on a lanelet.
std::vector<size_t> cast(const std::vector<VL>& vls, const std::vector<size_t>& cands, const Vector2d& p,
                         const Vector2d& n, double* extent);

class Builder {
 public:
  Builder(const std::string& path, const geo::LatLonAlt& origin, const WorldOptions& options)
      : path_(path), origin_(origin), frame_(origin), impl_(std::make_unique<SimWorld::Impl>()) {
    impl_->options = options;
    impl_->options.flat = true;
    impl_->options.validate();
    impl_->right_hand = options.right_hand_traffic;
  }

  Lanelet2World build();

 private:
  int64_t key(int64_t line_id) const {
    auto it = file_.reversed_copy_of.find(line_id);
    if (it != file_.reversed_copy_of.end()) return it->second;
    auto k = extra_keys_.find(line_id);
    return k != extra_keys_.end() ? k->second : line_id;
  }

  const map::LineString& fileLine(int64_t id) const {
    const auto* l = file_.map.line(id);
    if (!l) throw std::runtime_error(path_ + ": line " + std::to_string(id) + " missing");
    return *l;
  }

  const map::LineString* anyLine(int64_t id) const {
    if (const auto* l = file_.map.line(id)) return l;
    for (const auto& l : new_lines_) {
      if (l.id == id) return &l;
    }
    return nullptr;
  }

  int64_t addLine(LineType type, const std::vector<Vector2d>& pts, int64_t k) {
    map::LineString ls;
    ls.id = next_id_++;
    ls.type = type;
    for (const auto& p : pts) ls.points.emplace_back(p.x(), p.y(), 0.0);
    extra_keys_[ls.id] = k;
    new_lines_.push_back(ls);
    return ls.id;
  }

  // The steps (their files above), in the order build() runs them.
  void makeVehicleLanelets();
  void findSuccessors();
  void findLateral();
  void findJunctions();
  void groupAreas();
  void groupRoads();
  void addOsmNode(int64_t id, const Vector2d& p);
  std::vector<size_t> spine(const std::vector<size_t>& members) const;
  void deriveOsm();
  void labelTruth();
  void addFill(Surface s, detail::Layer layer, std::vector<Vector2d> poly, int64_t lanelet = -1);
  void stroke(const std::vector<Vector2d>& pts, double a, double b, double offset, double width, Surface s,
              detail::Layer layer);
  void buildScene();

  struct Area {
    std::vector<size_t> lanelets;
    Vector2d centre = Vector2d::Zero();
    int64_t node = 0;
    bool pinned = false;  // its node was moved onto a road's middle line
  };
  struct Comp {
    std::vector<size_t> lanelets;
    int64_t way_id = -1;
    std::vector<Vector2d> way_line;   // the spine (lanelet centre lines), in its direction
    std::vector<Vector2d> mid;        // the cross-section's middle, every ~2 m of the spine
    double length = 0.0;
    int a0 = -1, a1 = -1;             // junction areas at the start and the end
    std::vector<std::pair<double, int>> inner;  // (s, area) of the junctions it passes
    int forward = 1, backward = 0;
    bool has_way = false;
  };

  std::string path_;
  geo::LatLonAlt origin_;
  geo::LocalFrame frame_;
  std::unique_ptr<SimWorld::Impl> impl_;
  io::Lanelet2File file_;
  Extra extra_;
  Lanelet2WorldStats stats_;
  int64_t next_id_ = 1;
  int64_t next_osm_node_ = 1;
  std::map<int64_t, int64_t> extra_keys_;
  std::vector<map::LineString> new_lines_;
  std::vector<VL> vls_;
  std::vector<std::set<size_t>> conflicts_;
  std::vector<Area> areas_;
  std::vector<Comp> comps_;
  osm::OsmData roads_;
  std::unique_ptr<skeleton::Skeleton> skeleton_;
  std::map<int64_t, int64_t> split_twin_;
  std::map<int64_t, std::vector<int64_t>> joined_;
};

}  // namespace lanemap::sim::l2w
