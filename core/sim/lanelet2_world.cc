// The simulator's world from a Lanelet2 map (see lanelet2_world.h for the rules): the helpers, the
// file's extras, Builder::build and the entry points; the steps are in lanelet2_world_*.cc.
#include "core/sim/lanelet2_world_build.h"

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
namespace l2w {

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

// ---------- what the file says beyond io::Lanelet2File ----------

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

Lanelet2World Builder::build() {
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

}  // namespace l2w

geo::LatLonAlt lanelet2MapCentre(const std::string& path) {
  const l2w::Extra e = l2w::readExtra(path);
  if (e.nodes == 0) throw std::runtime_error(path + ": no node with a location");
  geo::LatLonAlt o;
  o.lat = 0.5 * (e.min_lat + e.max_lat);
  o.lon = 0.5 * (e.min_lon + e.max_lon);
  return o;
}

Lanelet2World buildLanelet2World(const std::string& path, const geo::LatLonAlt& origin,
                                 const WorldOptions& options) {
  return l2w::Builder(path, origin, options).build();
}

}  // namespace lanemap::sim
