// The simulator's world from a Lanelet2 map (see lanelet2_world.h for the rules).
#include "core/sim/lanelet2_world.h"

#include "core/io/lanelet2.h"
#include "core/sim/world_geometry.h"
#include "core/sim/world_scene.h"

#include <osmium/handler.hpp>
#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/relation.hpp>
#include <osmium/visitor.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace lanemap::sim {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using map::LaneletKind;
using map::LineType;

constexpr double kPi = 3.14159265358979323846;
constexpr double kCurbWidth = 0.15;       // curb band (as the OSM world builder paints it)
constexpr double kSidewalkWidth = 2.0;    // sidewalk band behind a curb
constexpr double kStopLineWidth = 0.4;
constexpr double kSuccessorGap = 0.2;     // bound ends this close: one lanelet follows the other
constexpr double kCastStep = 0.2;         // lateral casts (lane counts, road middle)
constexpr double kCastGap = 0.6;          // a cast stops after this much off the lanes
constexpr double kCastMax = 25.0;
constexpr double kMinRoadLength = 8.0;    // shorter road stubs beside a junction belong to it

// ---------- polylines ----------
double length(const std::vector<Vector2d>& p) { return geom::polylineLength(p); }

std::vector<Vector2d> xy(const std::vector<Vector3d>& pts) {
  std::vector<Vector2d> out;
  out.reserve(pts.size());
  for (const auto& p : pts) {
    if (out.empty() || (p.head<2>() - out.back()).norm() > 1e-6) out.push_back(p.head<2>());
  }
  return out;
}

// n points evenly spaced by arc length (n >= 2).
std::vector<Vector2d> resample(const std::vector<Vector2d>& p, size_t n) {
  std::vector<Vector2d> out;
  if (p.empty()) return out;
  if (p.size() == 1) return std::vector<Vector2d>(n, p.front());
  std::vector<double> cum(p.size(), 0.0);
  for (size_t i = 1; i < p.size(); ++i) cum[i] = cum[i - 1] + (p[i] - p[i - 1]).norm();
  const double L = cum.back();
  size_t j = 1;
  for (size_t k = 0; k < n; ++k) {
    const double s = L * static_cast<double>(k) / static_cast<double>(n - 1);
    while (j + 1 < p.size() && cum[j] < s) ++j;
    const double seg = cum[j] - cum[j - 1];
    const double u = seg > 0 ? std::clamp((s - cum[j - 1]) / seg, 0.0, 1.0) : 0.0;
    out.push_back(p[j - 1] + u * (p[j] - p[j - 1]));
  }
  return out;
}

std::vector<Vector2d> resampleSpacing(const std::vector<Vector2d>& p, double spacing) {
  const double L = length(p);
  const size_t n = std::max<size_t>(2, static_cast<size_t>(std::ceil(L / spacing)) + 1);
  return resample(p, n);
}

struct Projection {
  double distance = std::numeric_limits<double>::infinity();
  double s = 0.0;
  Vector2d point = Vector2d::Zero();
  Vector2d tangent = Vector2d::UnitX();
};

Projection project(const std::vector<Vector2d>& p, const Vector2d& q) {
  Projection best;
  double acc = 0.0;
  for (size_t i = 1; i < p.size(); ++i) {
    const Vector2d ab = p[i] - p[i - 1];
    const double l2 = ab.squaredNorm();
    const double len = std::sqrt(l2);
    const double u = l2 > 0 ? std::clamp((q - p[i - 1]).dot(ab) / l2, 0.0, 1.0) : 0.0;
    const Vector2d c = p[i - 1] + u * ab;
    const double d = (c - q).norm();
    if (d < best.distance) {
      best.distance = d;
      best.s = acc + u * len;
      best.point = c;
      if (len > 0) best.tangent = ab / len;
    }
    acc += len;
  }
  return best;
}

Vector2d direction(const std::vector<Vector2d>& p) {
  if (p.size() < 2) return Vector2d::UnitX();
  const Vector2d d = p.back() - p.front();
  return d.norm() > 1e-9 ? Vector2d(d.normalized()) : Vector2d::UnitX();
}

double headingChange(const std::vector<Vector2d>& c) {
  if (c.size() < 2) return 0.0;
  const double L = length(c);
  const auto r = resample(c, std::max<size_t>(3, static_cast<size_t>(L / 0.5) + 1));
  const Vector2d a = r[1] - r[0], b = r[r.size() - 1] - r[r.size() - 2];
  return std::atan2(geom::cross(a, b), a.dot(b));
}

// Douglas-Peucker on 2-D points.
void simplifyInto(const std::vector<Vector2d>& p, size_t i0, size_t i1, double tol, std::vector<char>& keep) {
  if (i1 <= i0 + 1) return;
  double worst = -1.0;
  size_t at = i0;
  for (size_t i = i0 + 1; i < i1; ++i) {
    const double d = geom::pointSegmentDistance(p[i], p[i0], p[i1]);
    if (d > worst) {
      worst = d;
      at = i;
    }
  }
  if (worst > tol) {
    keep[at] = 1;
    simplifyInto(p, i0, at, tol, keep);
    simplifyInto(p, at, i1, tol, keep);
  }
}
std::vector<Vector2d> simplify(const std::vector<Vector2d>& p, double tol) {
  if (p.size() < 3) return p;
  std::vector<char> keep(p.size(), 0);
  keep.front() = keep.back() = 1;
  simplifyInto(p, 0, p.size() - 1, tol, keep);
  std::vector<Vector2d> out;
  for (size_t i = 0; i < p.size(); ++i) {
    if (keep[i]) out.push_back(p[i]);
  }
  return out;
}

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

Extra readExtra(const std::string& path) {
  struct Handler : osmium::handler::Handler {
    Extra* e;
    void node(const osmium::Node& n) {
      if (!n.location().valid()) return;
      e->min_lat = std::min(e->min_lat, n.location().lat());
      e->max_lat = std::max(e->max_lat, n.location().lat());
      e->min_lon = std::min(e->min_lon, n.location().lon());
      e->max_lon = std::max(e->max_lon, n.location().lon());
      ++e->nodes;
    }
    void relation(const osmium::Relation& r) {
      const char* type = r.tags()["type"];
      const char* ow = r.tags()["one_way"];
      if (type && std::string(type) == "lanelet" && ow) e->one_way[r.id()] = ow;
    }
  } handler;
  Extra extra;
  handler.e = &extra;
  try {
    osmium::io::Reader reader{osmium::io::File{path, "osm"}};
    osmium::apply(reader, handler);
    reader.close();
  } catch (const std::exception& ex) {
    throw io::Lanelet2Error(path + ": " + ex.what());
  }
  return extra;
}

bool isVehicleSubtype(const std::string& s) {
  return s == "road" || s == "highway" || s == "bus_lane" || s == "play_street";
}

bool isTwoWay(const std::string& subtype, const std::string& one_way) {
  if (one_way == "no" || one_way == "false") return true;
  if (one_way.empty()) return subtype == "play_street";  // Lanelet2's defaults: road/highway one way
  return false;
}

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

void finishGeometry(VL& v) {
  v.poly = v.left;
  v.poly.insert(v.poly.end(), v.right.rbegin(), v.right.rend());
  v.box = Eigen::AlignedBox2d();
  for (const auto& p : v.poly) v.box.extend(p);
}

bool inside(const VL& v, const Vector2d& p) {
  return v.box.contains(p) && geom::pointInPolygon(p, v.poly);
}

// Lanelets whose box is within `margin` of `box`.
std::vector<size_t> near(const std::vector<VL>& vls, const Eigen::AlignedBox2d& box, double margin) {
  Eigen::AlignedBox2d b = box;
  b.min() -= Vector2d(margin, margin);
  b.max() += Vector2d(margin, margin);
  std::vector<size_t> out;
  for (size_t i = 0; i < vls.size(); ++i) {
    if (vls[i].box.intersects(b)) out.push_back(i);
  }
  return out;
}

// A cast from p along unit vector n over the lanelets `cands`: the lanelets met in order (each
// once) until the cast has been off them for kCastGap; `extent` = the last distance on a lanelet.
std::vector<size_t> cast(const std::vector<VL>& vls, const std::vector<size_t>& cands, const Vector2d& p,
                         const Vector2d& n, double* extent) {
  std::vector<size_t> met;
  double last_on = 0.0;
  for (double d = 0.0; d <= kCastMax; d += kCastStep) {
    const Vector2d q = p + d * n;
    bool on = false;
    for (size_t c : cands) {
      if (!inside(vls[c], q)) continue;
      on = true;
      if (std::find(met.begin(), met.end(), c) == met.end()) met.push_back(c);
    }
    if (on) last_on = d;
    if (d - last_on > kCastGap) break;
  }
  if (extent) *extent = last_on;
  return met;
}

class Builder {
 public:
  Builder(const std::string& path, const geo::LatLonAlt& origin, const WorldOptions& options)
      : path_(path), origin_(origin), frame_(origin), impl_(std::make_unique<SimWorld::Impl>()) {
    impl_->options = options;
    impl_->options.flat = true;
    impl_->options.validate();
    impl_->right_hand = options.right_hand_traffic;
  }

  Lanelet2World build() {
    io::Lanelet2ReadOptions ro;
    ro.origin_alt = origin_.alt;
    file_ = io::readLanelet2File(path_, origin_.lat, origin_.lon, ro);
    extra_ = readExtra(path_);
    stats_.map_lanelets = file_.map.lanelets.size();
    for (const auto& l : file_.map.lines) next_id_ = std::max(next_id_, l.id + 1);
    for (const auto& l : file_.map.lanelets) next_id_ = std::max(next_id_, l.id + 1);
    for (const auto& [copy, way] : file_.reversed_copy_of) next_id_ = std::max(next_id_, copy + 1);

    makeVehicleLanelets();
    if (vls_.empty()) throw std::runtime_error(path_ + ": no vehicle lanelet (subtype road, highway, bus_lane, play_street)");
    findSuccessors();
    findLateral();
    findJunctions();
    groupAreas();
    groupRoads();
    deriveOsm();
    labelTruth();
    buildScene();

    Lanelet2World out;
    impl_->stats.road_lanelets = stats_.road_lanelets;
    impl_->stats.intersection_lanelets = stats_.junction_lanelets;
    impl_->stats.lines = impl_->truth.lines.size();
    impl_->stats.crosswalks = stats_.crosswalks;
    impl_->stats.stop_lines = stats_.stop_lines;
    impl_->finalize();
    out.world = std::make_unique<SimWorld>(std::move(impl_));
    out.roads = std::move(roads_);
    out.skeleton = std::move(skeleton_);
    out.stats = stats_;
    out.split_twin = split_twin_;
    out.joined = joined_;
    return out;
  }

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

  // 1. Vehicle lanelets, bounds in the driving direction; two-way lanelets split in two.
  void makeVehicleLanelets() {
    for (const auto& l : file_.map.lanelets) {
      const auto st = file_.lanelet_subtype.find(l.id);
      const std::string subtype = st == file_.lanelet_subtype.end() ? "" : st->second;
      if (!isVehicleSubtype(subtype)) continue;
      ++stats_.map_vehicle_lanelets;
      VL v;
      v.ll = l;
      v.ll.kind = LaneletKind::kRoad;
      v.ll.successors.clear();
      v.ll.road_id = v.ll.from_node = v.ll.to_node = v.ll.intersection_id = -1;
      v.ll.index_from_left = -1;
      v.ll.turn = map::TurnDirection::kNone;
      v.left = xy(fileLine(l.left_id).points);
      v.right = xy(fileLine(l.right_id).points);
      v.centre = xy(l.centre);
      if (v.left.size() < 2 || v.right.size() < 2 || v.centre.size() < 2) continue;
      const Vector2d dir = direction(v.centre);
      bool left_rev = false, right_rev = false;
      if (direction(v.left).dot(dir) < 0) {
        std::reverse(v.left.begin(), v.left.end());
        left_rev = true;
      }
      if (direction(v.right).dot(dir) < 0) {
        std::reverse(v.right.begin(), v.right.end());
        right_rev = true;
      }
      v.left_key = key(l.left_id);
      v.right_key = key(l.right_id);
      if (left_rev) v.ll.left_id = addLine(fileLine(l.left_id).type, v.left, v.left_key);
      if (right_rev) v.ll.right_id = addLine(fileLine(l.right_id).type, v.right, v.right_key);
      const auto ow = extra_.one_way.find(l.id);
      if (!isTwoWay(subtype, ow == extra_.one_way.end() ? "" : ow->second)) {
        finishGeometry(v);
        vls_.push_back(std::move(v));
        continue;
      }
      // Two ways: the drawn direction drives on the right half (left-hand traffic: the left half).
      ++stats_.two_way_split;
      const size_t n = std::max({v.left.size(), v.right.size(),
                                 static_cast<size_t>(std::ceil(std::max(length(v.left), length(v.right)))) + 1});
      const auto L = resample(v.left, n), R = resample(v.right, n);
      std::vector<Vector2d> M(n), cf(n), cb(n);
      for (size_t i = 0; i < n; ++i) M[i] = 0.5 * (L[i] + R[i]);
      const int64_t mid_key = next_id_;  // the new middle line's own id
      const int64_t mid_id = addLine(LineType::kVirtual, M, mid_key);
      std::vector<Vector2d> Mr(M.rbegin(), M.rend());
      const int64_t mid_rev_id = addLine(LineType::kVirtual, Mr, mid_key);
      const bool rh = impl_->right_hand;
      // Forward half: between M and R (right-hand) or between L and M (left-hand).
      VL f = v, b = v;
      const std::vector<Vector2d>& f_left = rh ? M : L;
      const std::vector<Vector2d>& f_right = rh ? R : M;
      f.left = f_left;
      f.right = f_right;
      f.left_key = rh ? mid_key : v.left_key;
      f.right_key = rh ? v.right_key : mid_key;
      if (rh) f.ll.left_id = mid_id;
      else f.ll.right_id = mid_id;
      for (size_t i = 0; i < n; ++i) cf[i] = 0.5 * (f_left[i] + f_right[i]);
      f.centre = cf;
      // Backward half: the other half, driven the other way; its bounds are reversed copies.
      std::vector<Vector2d> b_left_fwd = rh ? L : M, b_right_fwd = rh ? M : R;  // in the drawn direction
      // Driving backwards, the drawn right side is on the left.
      b.left.assign(b_right_fwd.rbegin(), b_right_fwd.rend());
      b.right.assign(b_left_fwd.rbegin(), b_left_fwd.rend());
      b.left_key = rh ? mid_key : v.right_key;
      b.right_key = rh ? v.left_key : mid_key;
      b.ll.left_id = rh ? mid_rev_id : addLine(fileLine(l.right_id).type, b.left, v.right_key);
      b.ll.right_id = rh ? addLine(fileLine(l.left_id).type, b.right, v.left_key) : mid_rev_id;
      for (size_t i = 0; i < n; ++i) cb[i] = 0.5 * (b.left[i] + b.right[i]);
      b.centre = cb;
      b.ll.id = next_id_++;
      b.ll.stop_line_id.reset();
      split_twin_[f.ll.id] = b.ll.id;
      finishGeometry(f);
      finishGeometry(b);
      vls_.push_back(std::move(f));
      vls_.push_back(std::move(b));
    }
    for (auto& v : vls_) {
      v.ll.centre.clear();
      for (const auto& p : v.centre) v.ll.centre.emplace_back(p.x(), p.y(), 0.0);
    }
  }

  // 2. B follows A when A's bounds end where B's begin.
  void findSuccessors() {
    for (size_t a = 0; a < vls_.size(); ++a) {
      for (size_t b = 0; b < vls_.size(); ++b) {
        if (a == b) continue;
        const VL &A = vls_[a], &B = vls_[b];
        const bool l = (A.left.back() - B.left.front()).norm() < kSuccessorGap;
        const bool r = (A.right.back() - B.right.front()).norm() < kSuccessorGap;
        // Or the lane goes on where it widens or narrows, or where a two-way lanelet (split in
        // halves) meets one-way ones: headings agree and the centre ends are close (one shared
        // bound end: within half the wider lane; none: within 0.3 m).
        const Vector2d ta = A.centre.back() - A.centre[A.centre.size() - 2];
        const Vector2d tb = B.centre[1] - B.centre.front();
        const bool ahead = ta.normalized().dot(tb.normalized()) > std::cos(35.0 * kPi / 180.0);
        const double dc = (A.centre.back() - B.centre.front()).norm();
        const double wide = std::max((A.left.back() - A.right.back()).norm(), (B.left.front() - B.right.front()).norm());
        const bool goes_on = ahead && (((l || r) && dc < 0.5 * wide + 0.1) || dc < 0.3);
        if ((l && r) || goes_on) {
          vls_[a].succ.push_back(b);
          vls_[b].pred.push_back(a);
        }
      }
    }
  }

  // 3. Side by side: a shared bound, or most of one's bound runs along one of the other's bounds.
  void findLateral() {
    auto along = [](const std::vector<Vector2d>& a, const std::vector<Vector2d>& b) {
      const auto s = resampleSpacing(a, 1.0);
      size_t hits = 0;
      for (const auto& p : s) hits += project(b, p).distance < 0.15;
      return static_cast<double>(hits) / static_cast<double>(s.size());
    };
    for (size_t a = 0; a < vls_.size(); ++a) {
      for (size_t b : near(vls_, vls_[a].box, 0.5)) {
        if (b <= a) continue;
        const VL &A = vls_[a], &B = vls_[b];
        bool side = false;
        for (int64_t ka : {A.left_key, A.right_key}) {
          if (ka == B.left_key || ka == B.right_key) side = true;
        }
        for (int sa = 0; sa < 2 && !side; ++sa) {
          for (int sb = 0; sb < 2 && !side; ++sb) {
            const auto& la = sa ? A.right : A.left;
            const auto& lb = sb ? B.right : B.left;
            if (std::max(along(la, lb), along(lb, la)) >= 0.5) side = true;
          }
        }
        if (side) {
          vls_[a].lateral.insert(b);
          vls_[b].lateral.insert(a);
        }
      }
    }
  }

  // 4. Junction lanelets: the centre line runs inside another vehicle lanelet that is neither
  //    side by side nor a successor/predecessor (crossing, branching, merging movements).
  void findJunctions() {
    conflicts_.assign(vls_.size(), {});
    for (size_t a = 0; a < vls_.size(); ++a) {
      const VL& A = vls_[a];
      const double L = length(A.centre);
      if (L < 1.6) continue;
      const auto pts = resampleSpacing(A.centre, 0.5);
      std::vector<size_t> cands;
      for (size_t b : near(vls_, A.box, 0.0)) {
        if (b == a || A.lateral.count(b)) continue;
        if (std::find(A.succ.begin(), A.succ.end(), b) != A.succ.end()) continue;
        if (std::find(A.pred.begin(), A.pred.end(), b) != A.pred.end()) continue;
        cands.push_back(b);
      }
      for (size_t b : cands) {
        int hits = 0;
        double s = 0.0;
        for (size_t i = 0; i < pts.size(); ++i) {
          if (i > 0) s += (pts[i] - pts[i - 1]).norm();
          if (s < 0.75 || s > L - 0.75) continue;
          if (inside(vls_[b], pts[i])) ++hits;
        }
        if (hits >= 2) {
          conflicts_[a].insert(b);
          conflicts_[b].insert(a);
        }
      }
    }
    for (size_t a = 0; a < vls_.size(); ++a) {
      if (!conflicts_[a].empty()) vls_[a].junction = true;
    }
    // Branches and merges that are not side by side (the lanes go different ways).
    for (const auto& v : vls_) {
      for (const auto* set : {&v.succ, &v.pred}) {
        bool apart = false;
        for (size_t x : *set) {
          for (size_t y : *set) {
            if (x < y && !vls_[x].lateral.count(y)) apart = true;
          }
        }
        if (!apart) continue;
        for (size_t x : *set) vls_[x].junction = true;
      }
    }
  }

  // 5. Junction areas and their OSM nodes.
  void groupAreas() {
    UnionFind uf(vls_.size());
    for (size_t a = 0; a < vls_.size(); ++a) {
      if (!vls_[a].junction) continue;
      auto link = [&](size_t b) {
        if (vls_[b].junction) uf.join(a, b);
      };
      for (size_t b : conflicts_[a]) link(b);
      for (size_t b : vls_[a].succ) link(b);
      for (size_t b : vls_[a].pred) link(b);
      for (size_t b : vls_[a].lateral) link(b);
    }
    for (const auto& v : vls_) {  // pieces that branch from or merge into one lanelet
      for (const auto* set : {&v.succ, &v.pred}) {
        for (size_t x : *set) {
          for (size_t y : *set) {
            if (vls_[x].junction && vls_[y].junction) uf.join(x, y);
          }
        }
      }
    }
    std::map<size_t, int> area_of_root;
    for (size_t a = 0; a < vls_.size(); ++a) {
      if (!vls_[a].junction) continue;
      const size_t r = uf.find(a);
      auto [it, inserted] = area_of_root.emplace(r, static_cast<int>(areas_.size()));
      if (inserted) areas_.push_back({});
      vls_[a].area = it->second;
      areas_[it->second].lanelets.push_back(a);
    }
    for (auto& area : areas_) {
      Vector2d sum = Vector2d::Zero();
      size_t n = 0;
      for (size_t a : area.lanelets) {
        for (const auto& p : resampleSpacing(vls_[a].centre, 1.0)) {
          sum += p;
          ++n;
        }
      }
      area.centre = sum / static_cast<double>(std::max<size_t>(1, n));
      area.node = next_osm_node_++;
      addOsmNode(area.node, area.centre);
    }
    stats_.junction_areas = areas_.size();
  }

  // 6. Roads: road lanelets joined by succession or side by side.
  void groupRoads() {
    UnionFind uf(vls_.size());
    for (size_t a = 0; a < vls_.size(); ++a) {
      if (vls_[a].junction) continue;
      for (size_t b : vls_[a].succ) {
        if (!vls_[b].junction) uf.join(a, b);
      }
      for (size_t b : vls_[a].lateral) {
        if (!vls_[b].junction) uf.join(a, b);
      }
    }
    std::map<size_t, int> comp_of_root;
    for (size_t a = 0; a < vls_.size(); ++a) {
      if (vls_[a].junction) continue;
      auto [it, inserted] = comp_of_root.emplace(uf.find(a), static_cast<int>(comps_.size()));
      if (inserted) comps_.push_back({});
      vls_[a].comp = it->second;
      comps_[it->second].lanelets.push_back(a);
    }
    // Same-direction lanes to each road lanelet's left and right, at its middle.
    for (auto& v : vls_) {
      if (v.junction) continue;
      std::vector<size_t> cands;
      for (size_t i : comps_[v.comp].lanelets) cands.push_back(i);
      const auto pr = project(v.centre, resample(v.centre, 3)[1]);
      const Vector2d p = pr.point, t = pr.tangent, n(-t.y(), t.x());
      for (int side = 0; side < 2; ++side) {
        const auto met = cast(vls_, cands, p, side == 0 ? n : Vector2d(-n), nullptr);
        int same = 0;
        for (size_t m : met) {
          if (&vls_[m] == &v) continue;
          const auto pm = project(vls_[m].centre, p);
          if (pm.tangent.dot(t) <= 0.0) break;  // the other direction begins
          ++same;
        }
        (side == 0 ? v.left_same : v.right_same) = same;
      }
    }
  }

  void addOsmNode(int64_t id, const Vector2d& p) {
    const geo::LatLonAlt g = frame_.toWgs84(Vector3d(p.x(), p.y(), 0.0));
    osm::Node n;
    n.id = id;
    // OSM's precision (what roads.osm stores), so a skeleton built from the file is this one.
    n.lat = std::round(g.lat * 1e7) / 1e7;
    n.lon = std::round(g.lon * 1e7) / 1e7;
    roads_.nodes[id] = n;
  }

  // The longest chain of successors inside a road (its spine), in its driving direction.
  std::vector<size_t> spine(const std::vector<size_t>& members) const {
    std::set<size_t> in(members.begin(), members.end());
    std::vector<size_t> best;
    double best_len = -1.0;
    for (size_t start : members) {
      bool has_pred = false;
      for (size_t p : vls_[start].pred) has_pred |= in.count(p) > 0;
      if (has_pred) continue;
      std::vector<size_t> chain{start};
      std::set<size_t> seen{start};
      double len = length(vls_[start].centre);
      for (;;) {
        const VL& cur = vls_[chain.back()];
        size_t next = SIZE_MAX;
        double best_turn = 1e9;
        for (size_t s : cur.succ) {
          if (!in.count(s) || seen.count(s)) continue;
          const double turn = std::abs(headingChange({cur.centre[cur.centre.size() - 2], cur.centre.back(),
                                                      vls_[s].centre[1]}));
          if (turn < best_turn) {
            best_turn = turn;
            next = s;
          }
        }
        if (next == SIZE_MAX) break;
        chain.push_back(next);
        seen.insert(next);
        len += length(vls_[next].centre);
      }
      if (len > best_len) {
        best_len = len;
        best = chain;
      }
    }
    if (best.empty()) best.push_back(members.front());  // a ring: any lanelet
    return best;
  }

  // 7. The road-level OSM: one way per road, junction node to junction node; then the skeleton.
  void deriveOsm() {
    int64_t way_id = 1;
    for (auto& comp : comps_) {
      const auto chain = spine(comp.lanelets);
      std::vector<Vector2d> centre;
      for (size_t i : chain) {
        for (const auto& p : vls_[i].centre) {
          if (centre.empty() || (p - centre.back()).norm() > 1e-3) centre.push_back(p);
        }
      }
      if (centre.size() < 2 || length(centre) < 0.5) continue;
      // The middle of the whole cross-section at every 2 m of the spine.
      const auto samples = resampleSpacing(centre, 2.0);
      std::vector<size_t> cands = comp.lanelets;
      std::vector<Vector2d> mid, normals;
      std::vector<double> offsets;
      int fwd_max = 0, bwd_max = 0;
      for (size_t k = 0; k < samples.size(); ++k) {
        const Vector2d p = samples[k];
        const Vector2d t = (samples[std::min(k + 1, samples.size() - 1)] - samples[k > 0 ? k - 1 : 0]).normalized();
        const Vector2d n(-t.y(), t.x());
        double dl = 0.0, dr = 0.0;
        const auto ml = cast(vls_, cands, p, n, &dl);
        const auto mr = cast(vls_, cands, p, -n, &dr);
        offsets.push_back(0.5 * (dl - dr));
        normals.push_back(n);
        std::set<size_t> met(ml.begin(), ml.end());
        met.insert(mr.begin(), mr.end());
        int f = 0, b = 0;
        for (size_t m : met) (project(vls_[m].centre, p).tangent.dot(t) > 0 ? f : b)++;
        fwd_max = std::max({fwd_max, f, 1});
        bwd_max = std::max(bwd_max, b);
      }
      // The offset of the middle from the spine, robustly smoothed (a cast that runs into a
      // branching lane jumps): median of 7, then mean of 5.
      std::vector<double> med(offsets.size());
      for (size_t k = 0; k < offsets.size(); ++k) {
        std::vector<double> win;
        for (size_t q = k >= 3 ? k - 3 : 0; q < std::min(offsets.size(), k + 4); ++q) win.push_back(offsets[q]);
        std::nth_element(win.begin(), win.begin() + win.size() / 2, win.end());
        med[k] = win[win.size() / 2];
      }
      for (size_t k = 0; k < offsets.size(); ++k) {
        double sum = 0.0;
        int cnt = 0;
        for (size_t q = k >= 2 ? k - 2 : 0; q < std::min(offsets.size(), k + 3); ++q, ++cnt) sum += med[q];
        mid.push_back(samples[k] + normals[k] * (sum / cnt));
      }
      for (size_t m : comp.lanelets) {
        const Vector2d pm = resample(vls_[m].centre, 3)[1];
        if (project(centre, pm).tangent.dot(project(vls_[m].centre, pm).tangent) < 0) bwd_max = std::max(bwd_max, 1);
      }
      // Junction areas along the road: where its lanelets lead into or come from junction
      // lanelets. Those near an end end the way there (the closest at each end); those further in
      // (a junction the road's other lanes pass by, e.g. an entry into a roundabout's ring) are
      // junction nodes on the way, moved onto its middle line.
      const double L = length(centre);
      const double end_zone = std::min(12.0, 0.3 * L);
      std::map<int, Projection> attached;  // area -> its attachment nearest the spine
      for (size_t m : comp.lanelets) {
        auto attach = [&](size_t other, const Vector2d& where) {
          const int a = vls_[other].area;
          if (a < 0) return;
          const auto pr = project(centre, where);
          if (!attached.count(a) || pr.distance < attached[a].distance) attached[a] = pr;
        };
        for (size_t s : vls_[m].succ) attach(s, vls_[m].centre.back());
        for (size_t p : vls_[m].pred) attach(p, vls_[m].centre.front());
      }
      int a0 = -1, a1 = -1;
      double d0 = 1e300, d1 = 1e300;
      std::vector<std::pair<double, int>> inner;  // (s, area)
      for (const auto& [a, pr] : attached) {
        if (pr.s < end_zone) {
          if (pr.s + pr.distance < d0) {
            d0 = pr.s + pr.distance;
            a0 = a;
          }
        } else if (pr.s > L - end_zone) {
          if (L - pr.s + pr.distance < d1) {
            d1 = L - pr.s + pr.distance;
            a1 = a;
          }
        } else {
          inner.emplace_back(pr.s, a);
        }
      }
      std::sort(inner.begin(), inner.end());
      // A stub shorter than kMinRoadLength beside one junction (a short lane piece drawn at its
      // edge) is part of that junction, not a road of its own; a short link between two
      // junctions stays a road.
      std::set<int> areas_met;
      for (const auto& [a, pr] : attached) areas_met.insert(a);
      if (L < kMinRoadLength && areas_met.size() == 1) {
        int best = -1;
        double bd = 1e300;
        for (const auto& [a, pr] : attached) {
          if (pr.distance < bd) {
            bd = pr.distance;
            best = a;
          }
        }
        for (size_t m : comp.lanelets) {
          vls_[m].junction = true;
          vls_[m].area = best;
        }
        ++stats_.stubs_in_junctions;
        continue;
      }
      // Interior junctions move onto this road's middle line (the first road to pass one wins).
      for (const auto& [s_in, a] : inner) {
        if (a == a0 || a == a1) continue;
        auto& area = areas_[a];
        if (!area.pinned) {
          area.pinned = true;
          const double step = samples.size() > 1 ? L / static_cast<double>(samples.size() - 1) : L;
          area.centre = mid[std::min(mid.size() - 1, static_cast<size_t>(std::lround(s_in / step)))];
          addOsmNode(area.node, area.centre);
        }
      }
      comp.way_line = centre;  // for the direction of each lanelet
      comp.mid = std::move(mid);
      comp.length = L;
      comp.a0 = a0;
      comp.a1 = a1;
      comp.inner = std::move(inner);
      comp.forward = fwd_max;
      comp.backward = bwd_max;
      comp.has_way = true;
    }
    // A junction that a one-way carriageway runs through (it ends one road and begins the next
    // going on in nearly the same direction, e.g. a roundabout's ring past an entry): its node
    // goes onto the carriageway, between the two roads, as OSM draws it (and as OSM's, a small
    // roundabout's nodes are then close enough for the skeleton to make it one intersection).
    for (size_t a = 0; a < areas_.size(); ++a) {
      auto& area = areas_[a];
      if (area.pinned) continue;
      int pairs = 0;
      Vector2d at = Vector2d::Zero();
      for (const auto& x : comps_) {
        if (!x.has_way || x.a1 != static_cast<int>(a) || x.backward > 0 || x.way_line.size() < 2) continue;
        for (const auto& y : comps_) {
          if (&x == &y || !y.has_way || y.a0 != static_cast<int>(a) || y.backward > 0 || y.way_line.size() < 2) continue;
          const Vector2d tx = (x.way_line.back() - x.way_line[x.way_line.size() - 2]).normalized();
          const Vector2d ty = (y.way_line[1] - y.way_line.front()).normalized();
          const Vector2d gap = y.mid.front() - x.mid.back();
          if (tx.dot(ty) < std::cos(100.0 * kPi / 180.0) || gap.norm() > 40.0) continue;
          ++pairs;
          at = 0.5 * (x.mid.back() + y.mid.front());
        }
      }
      if (pairs != 1) continue;
      area.pinned = true;
      area.centre = at;
      addOsmNode(area.node, at);
      ++stats_.through_junctions;
    }
    // The ways, once every junction node has its place.
    for (auto& comp : comps_) {
      if (!comp.has_way) continue;
      struct WayPoint {
        int64_t node;  // -1: a new node
        Vector2d p;
      };
      std::vector<WayPoint> pts;
      const auto& mid = comp.mid;
      const double step = mid.size() > 1 ? comp.length / static_cast<double>(mid.size() - 1) : comp.length;
      size_t k = 0;
      auto run_until = [&](double s_stop) {  // the middle line's points before s_stop, simplified
        std::vector<Vector2d> run;
        for (; k < mid.size() && static_cast<double>(k) * step < s_stop; ++k) run.push_back(mid[k]);
        for (const auto& p : simplify(run, 0.2)) pts.push_back({-1, p});
      };
      if (comp.a0 >= 0) pts.push_back({areas_[comp.a0].node, areas_[comp.a0].centre});
      for (const auto& [s_in, a] : comp.inner) {
        if (a == comp.a0 || a == comp.a1) continue;
        run_until(s_in - 2.5);
        while (k < mid.size() && static_cast<double>(k) * step < s_in + 2.5) ++k;
        if (pts.empty() || pts.back().node != areas_[a].node) pts.push_back({areas_[a].node, areas_[a].centre});
      }
      run_until(1e300);
      if (comp.a1 >= 0 && (comp.a1 != comp.a0 || pts.size() > 2)) pts.push_back({areas_[comp.a1].node, areas_[comp.a1].centre});
      // No fold-backs: drop middle-line points where the way would turn by more than 100 degrees
      // (a junction node beside or behind the road's first lane points), and points closer than
      // 0.5 m to the one before.
      for (bool changed = true; changed;) {
        changed = false;
        for (size_t i = 1; i + 1 < pts.size() && !changed; ++i) {
          const Vector2d u = pts[i].p - pts[i - 1].p, v = pts[i + 1].p - pts[i].p;
          const bool close = u.norm() < 0.5;
          const bool fold = !close && v.norm() > 1e-6 && u.normalized().dot(v.normalized()) < std::cos(100.0 * kPi / 180.0);
          if (!close && !fold) continue;
          size_t drop = SIZE_MAX;
          if (pts[i].node < 0) drop = i;
          else if (close && pts[i - 1].node < 0 && i - 1 > 0) drop = i - 1;
          else if (fold && pts[i - 1].node < 0 && i - 1 > 0) drop = i - 1;
          else if (fold && pts[i + 1].node < 0 && i + 1 < pts.size() - 1) drop = i + 1;
          if (drop != SIZE_MAX) {
            pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(drop));
            changed = true;
          }
        }
      }
      osm::Way w;
      w.id = way_id++;
      for (const auto& q : pts) {
        int64_t id = q.node;
        if (id < 0) {
          id = next_osm_node_++;
          addOsmNode(id, q.p);
        }
        if (w.nodes.empty() || w.nodes.back() != id) w.nodes.push_back(id);
      }
      if (w.nodes.size() < 2) continue;
      const int fwd_max = comp.forward, bwd_max = comp.backward;
      const int lanes = fwd_max + bwd_max;
      w.tags["highway"] = std::max(fwd_max, bwd_max) >= 2 ? "secondary" : "residential";
      w.tags["lanes"] = std::to_string(std::max(1, lanes));
      if (bwd_max == 0) {
        w.tags["oneway"] = "yes";
      } else {
        w.tags["lanes:forward"] = std::to_string(fwd_max);
        w.tags["lanes:backward"] = std::to_string(bwd_max);
      }
      w.tags["lanemap:source"] = "lanelet2";
      comp.way_id = w.id;
      roads_.ways.push_back(std::move(w));
      ++stats_.roads;
    }
    if (roads_.ways.empty()) throw std::runtime_error(path_ + ": no road could be derived from the lanelets");
    // Drop the junction nodes no way uses; bounds from the nodes.
    std::set<int64_t> used;
    for (const auto& w : roads_.ways) used.insert(w.nodes.begin(), w.nodes.end());
    for (auto it = roads_.nodes.begin(); it != roads_.nodes.end();) {
      it = used.count(it->first) ? std::next(it) : roads_.nodes.erase(it);
    }
    osm::Bounds b{1e9, 1e9, -1e9, -1e9};
    for (const auto& [id, n] : roads_.nodes) {
      b.min_lat = std::min(b.min_lat, n.lat);
      b.max_lat = std::max(b.max_lat, n.lat);
      b.min_lon = std::min(b.min_lon, n.lon);
      b.max_lon = std::max(b.max_lon, n.lon);
    }
    roads_.bounds = b;
    skeleton::SkeletonOptions so;
    so.origin = origin_;
    skeleton_ = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(roads_, so));
  }

  // 8. Truth labels in terms of the skeleton.
  void labelTruth() {
    const auto& sk = *skeleton_;
    std::unordered_map<int64_t, int64_t> inter_of_node;
    for (const auto& in : sk.intersections()) {
      for (int64_t n : in.osm_nodes) inter_of_node[n] = in.id;
    }
    std::map<std::pair<int64_t, bool>, std::vector<int64_t>> road_of;  // (way, along) -> road ids
    for (const auto& r : sk.roads()) road_of[{r.way_id, r.along_way}].push_back(r.id);
    for (auto& v : vls_) {
      if (v.junction) continue;
      const auto& comp = comps_[v.comp];
      const Vector2d mid = resample(v.centre, 3)[1];
      const bool along = comp.way_id >= 0 && project(comp.way_line, mid).tangent.dot(project(v.centre, mid).tangent) > 0;
      auto it = road_of.find({comp.way_id, along});
      if (it != road_of.end()) {
        // The way's atomic road (a way with junction nodes along it has several) nearest the
        // lanelet's middle.
        int64_t best_road = it->second.front();
        double best_d = 1e300;
        for (int64_t rid : it->second) {
          const double d = sk.project(rid, mid).distance;
          if (d < best_d) {
            best_d = d;
            best_road = rid;
          }
        }
        const auto* r = sk.road(best_road);
        v.ll.road_id = r->id;
        v.ll.from_node = r->from;
        v.ll.to_node = r->to;
        v.ll.index_from_left = impl_->right_hand ? v.left_same : v.right_same;
        continue;
      }
      // The skeleton has no road there (a piece inside a merged intersection): a junction lanelet
      // of the nearest intersection.
      ++stats_.unassigned_lanelets;
      v.junction = true;
      const skeleton::Intersection* best = nullptr;
      double bd = 1e300;
      for (const auto& in : sk.intersections()) {
        const double d = (in.centre - mid).norm();
        if (d < bd) {
          bd = d;
          best = &in;
        }
      }
      v.ll.intersection_id = best ? best->id : -1;
    }
    for (auto& v : vls_) {
      if (!v.junction) continue;
      v.ll.kind = LaneletKind::kIntersection;
      if (v.area >= 0) {
        auto it = inter_of_node.find(areas_[v.area].node);
        v.ll.intersection_id = it != inter_of_node.end() ? it->second : areas_[v.area].node;
      }
      const double h = headingChange(v.centre);
      v.ll.turn = h > 0.5 ? map::TurnDirection::kLeft : h < -0.5 ? map::TurnDirection::kRight
                                                         : map::TurnDirection::kStraight;
    }
    // The truth: the vehicle lanelets, their bounds and stop lines.
    auto& truth = impl_->truth;
    truth.origin_lat = origin_.lat;
    truth.origin_lon = origin_.lon;
    truth.origin_alt = origin_.alt;
    // Junction lanelets drawn in pieces (road -> J1 -> J2 -> road) are joined into one
    // intersection lanelet per path, as lanemap's truth has one lanelet per junction connection.
    std::vector<std::vector<size_t>> paths;
    std::map<size_t, std::vector<size_t>> paths_from;  // entry piece -> path indices
    for (size_t j = 0; j < vls_.size(); ++j) {
      const VL& v = vls_[j];
      if (!v.junction) continue;
      bool entry = v.pred.empty();
      for (size_t p : v.pred) entry |= !vls_[p].junction;
      if (!entry) continue;
      std::vector<size_t> path{j};
      std::function<void()> walk = [&]() {
        const VL& cur = vls_[path.back()];
        bool road_next = cur.succ.empty();
        for (size_t s : cur.succ) road_next |= !vls_[s].junction;
        if (road_next || path.size() >= 8) {
          paths_from[path.front()].push_back(paths.size());
          paths.push_back(path);
        }
        if (path.size() >= 8 || paths.size() > 20000) return;
        for (size_t s : cur.succ) {
          if (!vls_[s].junction || std::find(path.begin(), path.end(), s) != path.end()) continue;
          path.push_back(s);
          walk();
          path.pop_back();
        }
      };
      walk();
    }
    std::vector<map::Lanelet> junction_out;
    std::set<size_t> in_paths;
    std::vector<int64_t> path_id(paths.size());
    for (size_t k = 0; k < paths.size(); ++k) {
      const auto& path = paths[k];
      in_paths.insert(path.begin(), path.end());
      if (path.size() == 1) {
        path_id[k] = vls_[path[0]].ll.id;
        continue;
      }
      path_id[k] = next_id_++;
      ++stats_.joined_junction_paths;
      for (size_t j : path) joined_[path_id[k]].push_back(vls_[j].ll.id);
    }
    for (size_t k = 0; k < paths.size(); ++k) {
      const auto& path = paths[k];
      map::Lanelet ll = vls_[path.front()].ll;
      if (path.size() > 1) {
        std::vector<Vector2d> left, right, centre;
        auto append = [](std::vector<Vector2d>& to, const std::vector<Vector2d>& from) {
          for (const auto& p : from) {
            if (to.empty() || (p - to.back()).norm() > 1e-3) to.push_back(p);
          }
        };
        for (size_t j : path) {
          append(left, vls_[j].left);
          append(right, vls_[j].right);
          append(centre, vls_[j].centre);
        }
        ll.id = path_id[k];
        ll.left_id = addLine(anyLine(vls_[path.front()].ll.left_id)->type, left, next_id_);
        ll.right_id = addLine(anyLine(vls_[path.front()].ll.right_id)->type, right, next_id_);
        ll.centre.clear();
        for (const auto& p : centre) ll.centre.emplace_back(p.x(), p.y(), 0.0);
        ll.stop_line_id = vls_[path.back()].ll.stop_line_id;
        const double h = headingChange(centre);
        ll.turn = h > 0.5 ? map::TurnDirection::kLeft : h < -0.5 ? map::TurnDirection::kRight
                                                       : map::TurnDirection::kStraight;
      }
      ll.successors.clear();
      for (size_t s : vls_[path.back()].succ) {
        if (!vls_[s].junction) ll.successors.push_back(vls_[s].ll.id);
      }
      junction_out.push_back(std::move(ll));
    }
    auto successorIds = [&](const VL& v) {
      std::vector<int64_t> out;
      for (size_t s : v.succ) {
        if (!vls_[s].junction) {
          out.push_back(vls_[s].ll.id);
        } else if (auto it = paths_from.find(s); it != paths_from.end()) {
          for (size_t k : it->second) out.push_back(path_id[k]);
        }
      }
      return out;
    };
    std::set<int64_t> lines;
    auto keep = [&](const map::Lanelet& ll) {
      lines.insert(ll.left_id);
      lines.insert(ll.right_id);
      if (ll.stop_line_id) lines.insert(*ll.stop_line_id);
      truth.lanelets.push_back(ll);
      (ll.kind == LaneletKind::kIntersection ? stats_.junction_lanelets : stats_.road_lanelets)++;
    };
    for (auto& v : vls_) {
      if (v.junction) {
        if (in_paths.count(&v - vls_.data())) continue;
        map::Lanelet ll = v.ll;  // on a cycle of junction pieces: as drawn
        ll.successors = successorIds(v);
        keep(ll);
        continue;
      }
      v.ll.successors = successorIds(v);
      keep(v.ll);
    }
    for (const auto& ll : junction_out) keep(ll);
    for (const auto& l : file_.map.lines) {
      if (lines.count(l.id)) truth.lines.push_back(l);
    }
    for (const auto& l : new_lines_) {
      if (lines.count(l.id)) truth.lines.push_back(l);
    }
    // Lateral slots for laneOffset: the road is the cross-section.
    for (auto& v : vls_) {
      if (v.junction) continue;
      detail::LaneSlot slot;
      slot.cross_section = v.comp;
      const auto& comp = comps_[v.comp];
      const Vector2d mid = resample(v.centre, 3)[1];
      slot.dir = project(comp.way_line, mid).tangent.dot(project(v.centre, mid).tangent) > 0 ? 1 : -1;
      slot.rank_curb = impl_->right_hand ? v.right_same : v.left_same;
      slot.rank_centre = impl_->right_hand ? v.left_same : v.right_same;
      impl_->slots[v.ll.id] = slot;
    }
  }

  void addFill(Surface s, detail::Layer layer, std::vector<Vector2d> poly, int64_t lanelet = -1) {
    if (poly.size() < 3) return;
    detail::FillPrimitive f;
    f.surface = s;
    f.layer = layer;
    f.lanelet = lanelet;
    f.polygon = std::move(poly);
    impl_->fills.push_back(std::move(f));
  }

  // A band of `width` centred `offset` to the left of pts[a..b] (arc lengths).
  void stroke(const std::vector<Vector2d>& pts, double a, double b, double offset, double width, Surface s,
              detail::Layer layer) {
    std::vector<double> cum(pts.size(), 0.0);
    for (size_t i = 1; i < pts.size(); ++i) cum[i] = cum[i - 1] + (pts[i] - pts[i - 1]).norm();
    auto interp = [&](double x) {
      size_t i = std::upper_bound(cum.begin(), cum.end(), x) - cum.begin();
      i = std::clamp<size_t>(i, 1, cum.size() - 1);
      const double l = cum[i] - cum[i - 1];
      const double u = l > 0 ? std::clamp((x - cum[i - 1]) / l, 0.0, 1.0) : 0.0;
      return Vector2d(pts[i - 1] + u * (pts[i] - pts[i - 1]));
    };
    std::vector<Vector2d> sub{interp(a)};
    for (size_t i = 0; i < cum.size(); ++i) {
      if (cum[i] > a + 1e-3 && cum[i] < b - 1e-3) sub.push_back(pts[i]);
    }
    sub.push_back(interp(b));
    if ((sub.back() - sub.front()).norm() < 1e-4) return;
    std::vector<double> d1(sub.size(), offset + width / 2.0), d2(sub.size(), offset - width / 2.0);
    auto left = geom::offsetPolyline(sub, d1);
    const auto right = geom::offsetPolyline(sub, d2);
    left.insert(left.end(), right.rbegin(), right.rend());
    addFill(s, layer, std::move(left));
  }

  // 9. The scene.
  void buildScene() {
    // Lanes: road lanelets carry their id; junction lanelets are intersection asphalt.
    for (const auto& v : vls_) {
      if (v.junction) addFill(Surface::kIntersection, detail::kLayerIntersection, v.poly);
      else addFill(Surface::kAsphalt, detail::kLayerLane, v.poly, v.ll.id);
    }
    // Zebra stripes of a crosswalk between its two edges (same direction).
    auto paintCrosswalk = [&](const std::vector<Vector2d>& left, const std::vector<Vector2d>& right) {
      // Zebra stripes across the walking direction: 0.5 m of paint every 1 m.
      const double len = 0.5 * (length(left) + length(right));
      if (len < 0.6) return;
      const size_t n = static_cast<size_t>(std::ceil(len / 0.05)) + 1;
      const auto L = resample(left, n), R = resample(right, n);
      auto at = [&](const std::vector<Vector2d>& P, double s) {
        const double f = std::clamp(s / len, 0.0, 1.0) * static_cast<double>(n - 1);
        const size_t i = std::min(static_cast<size_t>(f), n - 2);
        return Vector2d(P[i] + (f - static_cast<double>(i)) * (P[i + 1] - P[i]));
      };
      for (double s = 0.25; s + 0.5 <= len - 0.1; s += 1.0) {
        // Inset 0.2 m from the ends of each stripe.
        Vector2d a0 = at(L, s), b0 = at(R, s), a1 = at(L, s + 0.5), b1 = at(R, s + 0.5);
        const Vector2d u0 = (b0 - a0).normalized(), u1 = (b1 - a1).normalized();
        addFill(Surface::kCrosswalkPaint, detail::kLayerCrosswalk,
                {a0 + 0.2 * u0, a1 + 0.2 * u1, b1 - 0.2 * u1, b0 - 0.2 * u0});
      }
      ++stats_.crosswalks;
    };
    // Other lanelets: bicycle lanes, walkways, crosswalks.
    for (const auto& l : file_.map.lanelets) {
      const auto st = file_.lanelet_subtype.find(l.id);
      const std::string subtype = st == file_.lanelet_subtype.end() ? "" : st->second;
      const auto* lb = file_.map.line(l.left_id);
      const auto* rb = file_.map.line(l.right_id);
      if (!lb || !rb || isVehicleSubtype(subtype)) continue;
      auto left = xy(lb->points), right = xy(rb->points);
      if (left.size() < 2 || right.size() < 2) continue;
      if (direction(left).dot(direction(right)) < 0) std::reverse(right.begin(), right.end());
      std::vector<Vector2d> poly = left;
      poly.insert(poly.end(), right.rbegin(), right.rend());
      if (subtype == "bicycle_lane") {
        addFill(Surface::kBikeLane, detail::kLayerShoulder, poly);
      } else if (subtype == "walkway") {
        addFill(Surface::kSidewalk, detail::kLayerSidewalk, poly);
      } else if (subtype == "crosswalk") {
        paintCrosswalk(left, right);
      }
    }
    // Crosswalks as the Lanelet2 reader gives them (map.crosswalks: their two edges).
    for (const auto& c : file_.map.crosswalks) {
      auto left = xy(c.left), right = xy(c.right);
      if (left.size() < 2 || right.size() < 2) continue;
      if (direction(left).dot(direction(right)) < 0) std::reverse(right.begin(), right.end());
      paintCrosswalk(left, right);
    }
    // Which side of a line the road is on: from a lanelet that uses it as a bound.
    std::map<int64_t, std::pair<int64_t, int>> outward;  // key -> (line id, +1: paint to its left)
    auto note = [&](int64_t line_id, bool is_left, const std::vector<Vector2d>& dir_pts) {
      const auto* ls = anyLine(line_id);
      if (!ls) return;
      const int64_t k = key(line_id);
      if (outward.count(k)) return;
      const auto pts = xy(ls->points);
      if (pts.size() < 2) return;
      const bool same = direction(pts).dot(direction(dir_pts)) > 0;
      outward[k] = {line_id, (is_left == same) ? 1 : -1};
    };
    for (const auto& v : vls_) {
      note(v.ll.left_id, true, v.centre);
      note(v.ll.right_id, false, v.centre);
    }
    for (const auto& l : file_.map.lanelets) {
      const auto st = file_.lanelet_subtype.find(l.id);
      if (st == file_.lanelet_subtype.end() || st->second != "bicycle_lane" || l.centre.size() < 2) continue;
      note(l.left_id, true, xy(l.centre));
      note(l.right_id, false, xy(l.centre));
    }
    std::set<int64_t> painted;
    for (const auto& ls : file_.map.lines) {
      const int64_t k = key(ls.id);
      if (!painted.insert(k).second) continue;
      const auto pts = xy(ls.points);
      if (pts.size() < 2) continue;
      const double L = length(pts);
      if (L < 1e-3) continue;
      switch (ls.type) {
        case LineType::kCurb: {
          auto it = outward.find(k);
          const int out = it == outward.end() ? 0 : it->second.second;
          // The curb band beside the road edge, the sidewalk behind it.
          const auto& geo_pts = it == outward.end() ? pts : xy(anyLine(it->second.first)->points);
          stroke(geo_pts, 0.0, length(geo_pts), out * kCurbWidth / 2.0, kCurbWidth, Surface::kCurb, detail::kLayerCurb);
          if (out != 0) {
            stroke(geo_pts, 0.0, length(geo_pts), out * (kCurbWidth + kSidewalkWidth / 2.0), kSidewalkWidth,
                   Surface::kSidewalk, detail::kLayerSidewalk);
          }
          ++stats_.curbs;
          break;
        }
        case LineType::kDashed:
          for (double a = 0.0; a < L; a += kDashPeriod) {
            stroke(pts, a, std::min(L, a + kDashLength), 0.0, kLinePaintWidth, Surface::kDashedPaint,
                   detail::kLayerLinePaint);
          }
          ++stats_.painted_lines;
          break;
        case LineType::kSolid:
          stroke(pts, 0.0, L, 0.0, kLinePaintWidth, Surface::kSolidPaint, detail::kLayerLinePaint);
          ++stats_.painted_lines;
          break;
        case LineType::kSolidSolid:
          stroke(pts, 0.0, L, kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint);
          stroke(pts, 0.0, L, -kDoubleLineOffset, 0.1, Surface::kSolidPaint, detail::kLayerLinePaint);
          ++stats_.painted_lines;
          break;
        case LineType::kStopLine:
          stroke(pts, 0.0, L, 0.0, kStopLineWidth, Surface::kStopLinePaint, detail::kLayerStopLine);
          ++stats_.stop_lines;
          break;
        case LineType::kVirtual:
          break;
      }
    }
    double km = 0.0;
    for (const auto& v : vls_) {
      if (!v.junction) km += length(v.centre);
    }
    impl_->stats.driving_lane_km = km / 1000.0;
  }

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

}  // namespace

geo::LatLonAlt lanelet2MapCentre(const std::string& path) {
  const Extra e = readExtra(path);
  if (e.nodes == 0) throw std::runtime_error(path + ": no node with a location");
  geo::LatLonAlt o;
  o.lat = 0.5 * (e.min_lat + e.max_lat);
  o.lon = 0.5 * (e.min_lon + e.max_lon);
  return o;
}

Lanelet2World buildLanelet2World(const std::string& path, const geo::LatLonAlt& origin,
                                 const WorldOptions& options) {
  return Builder(path, origin, options).build();
}

}  // namespace lanemap::sim
