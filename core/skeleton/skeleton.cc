// Builds the map skeleton M0 (METHOD.md section 0) from road-level OSM data: intersections
// (junction nodes, merged across dual carriageways, plus dead ends), atomic roads (one per
// direction of travel between two intersections), each intersection's ROI polygon, and a grid
// index over road segments and ROI polygons for fast map matching.
//
// The steps of Skeleton::build, each a function below:
//  1. frame and ENU positions of the nodes;
//  2. split nodes: nodes used by two or more drivable ways (a way counted once per node), nodes a
//     way visits twice (a way that loops back onto itself), and the ends of open ways;
//  3. pieces: every way cut at its split nodes (a closed way is first rotated to start at one);
//  4. clusters: junction nodes joined by a piece no longer than junction_merge_radius_m become one
//     intersection (dual carriageways, small roundabouts), as long as the cluster stays compact
//     (every two of its nodes within 2 x the radius) so that chains of short pieces in a dense
//     network do not snowball into one huge intersection; dead ends are never merged;
//  5. atomic roads: each piece that is not inside a cluster, once per allowed direction;
//  6. ROI polygons and s_begin / s_end;
//  7. the spatial index.
#include "core/skeleton/skeleton.h"
#include "core/geo/polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace lanemap::skeleton {

namespace {

using Eigen::Vector2d;
constexpr double kPi = 3.14159265358979323846;

double wrapAngle(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0) a += 2.0 * kPi;
  return a - kPi;
}

using geo::cross;  // core/geo/polyline.h

std::vector<double> cumulativeLengths(const std::vector<Vector2d>& pts) {
  std::vector<double> cum(pts.size(), 0.0);
  for (size_t i = 1; i < pts.size(); ++i) cum[i] = cum[i - 1] + (pts[i] - pts[i - 1]).norm();
  return cum;
}

// A way cut between two split nodes.
struct Piece {
  const osm::Way* way = nullptr;
  int segment = 0;  // index along the way
  std::vector<int64_t> nodes;
  std::vector<Vector2d> pts;
  double length = 0.0;
  int64_t from_cluster = -1;  // intersection ids (set in step 5)
  int64_t to_cluster = -1;
  double half_width = 3.25;
  double roi_s_front = 0.0;  // ROI extent from the piece's first node, along the piece
  double roi_s_back = 0.0;   // ROI extent from its last node
  bool internal = false;     // lies inside a merged intersection
};

// ---- step 2: split nodes -------------------------------------------------------------------

struct SplitInfo {
  std::unordered_map<int64_t, int> way_count;  // distinct ways using a node
  std::unordered_set<int64_t> self_touch;      // nodes a way visits twice (not a closing node)
  std::unordered_set<int64_t> open_ends;       // first/last nodes of open ways
  bool isSplit(int64_t n) const {
    auto it = way_count.find(n);
    return (it != way_count.end() && it->second >= 2) || self_touch.count(n) || open_ends.count(n);
  }
  bool isDeadEnd(int64_t n) const {
    auto it = way_count.find(n);
    return open_ends.count(n) && it != way_count.end() && it->second == 1 && !self_touch.count(n);
  }
};

bool isClosed(const osm::Way& w) { return w.nodes.size() >= 3 && w.nodes.front() == w.nodes.back(); }

SplitInfo findSplitNodes(const std::vector<osm::Way>& ways) {
  SplitInfo info;
  for (const osm::Way& w : ways) {
    // The nodes of the way without the closing repeat of a closed way.
    const size_t n = isClosed(w) ? w.nodes.size() - 1 : w.nodes.size();
    std::unordered_set<int64_t> seen;
    for (size_t i = 0; i < n; ++i) {
      if (!seen.insert(w.nodes[i]).second) info.self_touch.insert(w.nodes[i]);
    }
    for (int64_t id : seen) ++info.way_count[id];
    if (!isClosed(w)) {
      info.open_ends.insert(w.nodes.front());
      info.open_ends.insert(w.nodes.back());
    }
  }
  return info;
}

// ---- step 3: pieces ------------------------------------------------------------------------

double halfWidthEstimate(const osm::Way& w, bool oneway) {
  // `width` (metres) wins; else lanes x 3.25 m; else lanes by class and direction.
  try {
    const std::string width = w.tag("width");
    if (!width.empty()) {
      const double v = std::stod(width);
      if (v > 2.0 && v < 60.0) return 0.5 * v;
    }
  } catch (const std::exception&) {
  }
  int lanes = 0;
  try {
    const std::string l = w.tag("lanes");
    if (!l.empty()) lanes = std::stoi(l);
  } catch (const std::exception&) {
  }
  if (lanes < 1 || lanes > 12) {
    const std::string hw = w.tag("highway");
    const bool big = hw == "motorway" || hw == "trunk" || hw == "primary";
    lanes = (oneway ? 1 : 2) * (big ? 2 : 1);
  }
  return 0.5 * 3.25 * lanes;
}

struct Directions {
  bool forward = true;
  bool backward = true;
};

Directions allowedDirections(const osm::Way& w) {
  const std::string oneway = w.tag("oneway");
  if (oneway == "yes" || oneway == "true" || oneway == "1") return {true, false};
  if (oneway == "-1" || oneway == "reverse") return {false, true};
  if (oneway == "no" || oneway == "false" || oneway == "0") return {true, true};
  const std::string junction = w.tag("junction");
  const std::string highway = w.tag("highway");
  if (junction == "roundabout" || junction == "circular" || highway == "motorway" ||
      highway == "motorway_link") {
    return {true, false};
  }
  return {true, true};  // including oneway=reversible/alternating: both directions can occur
}

std::vector<Piece> cutWays(const std::vector<osm::Way>& ways, const SplitInfo& split,
                           const std::unordered_map<int64_t, Vector2d>& pos) {
  std::vector<Piece> pieces;
  for (const osm::Way& w : ways) {
    std::vector<int64_t> nodes = w.nodes;
    if (isClosed(w)) {
      // Rotate the ring so that it starts (and ends) at its first split node; a ring with none is
      // one loop piece from its first node.
      nodes.pop_back();
      auto it = std::find_if(nodes.begin(), nodes.end(), [&](int64_t n) { return split.isSplit(n); });
      if (it != nodes.end()) std::rotate(nodes.begin(), it, nodes.end());
      nodes.push_back(nodes.front());
    }
    const Directions dir = allowedDirections(w);
    const double hw = halfWidthEstimate(w, !(dir.forward && dir.backward));
    Piece current;
    int segment = 0;
    for (size_t i = 0; i < nodes.size(); ++i) {
      current.nodes.push_back(nodes[i]);
      const bool last = i + 1 == nodes.size();
      if (i > 0 && (last || split.isSplit(nodes[i]))) {
        current.way = &w;
        current.segment = segment++;
        current.half_width = hw;
        for (int64_t n : current.nodes) current.pts.push_back(pos.at(n));
        current.length = cumulativeLengths(current.pts).back();
        pieces.push_back(std::move(current));
        current = Piece();
        current.nodes.push_back(nodes[i]);
      }
    }
  }
  return pieces;
}

// ---- step 4: clusters ----------------------------------------------------------------------

struct UnionFind {
  std::unordered_map<int64_t, int64_t> parent;
  int64_t find(int64_t x) {
    auto it = parent.find(x);
    if (it == parent.end()) {
      parent[x] = x;
      return x;
    }
    if (it->second == x) return x;
    const int64_t root = find(it->second);
    parent[x] = root;
    return root;
  }
  void unite(int64_t a, int64_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Groups the junction nodes (piece ends) into intersections. Returns node -> cluster root.
std::unordered_map<int64_t, int64_t> clusterJunctions(const std::vector<Piece>& pieces,
                                                     const SplitInfo& split,
                                                     const std::unordered_map<int64_t, Vector2d>& pos,
                                                     double radius) {
  UnionFind uf;
  std::map<int64_t, std::vector<int64_t>> members;  // root -> nodes
  for (const Piece& p : pieces) {
    for (int64_t n : {p.nodes.front(), p.nodes.back()}) {
      if (uf.find(n) == n && !members.count(n)) members[n] = {n};
    }
  }
  // Short pieces, shortest first (ties by way id and segment, for determinism).
  std::vector<const Piece*> shorts;
  for (const Piece& p : pieces) {
    if (p.length <= radius && p.nodes.front() != p.nodes.back() && !split.isDeadEnd(p.nodes.front()) &&
        !split.isDeadEnd(p.nodes.back())) {
      shorts.push_back(&p);
    }
  }
  std::sort(shorts.begin(), shorts.end(), [](const Piece* a, const Piece* b) {
    if (a->length != b->length) return a->length < b->length;
    if (a->way->id != b->way->id) return a->way->id < b->way->id;
    return a->segment < b->segment;
  });
  const double max_diameter = 2.0 * radius;
  for (const Piece* p : shorts) {
    const int64_t a = uf.find(p->nodes.front());
    const int64_t b = uf.find(p->nodes.back());
    if (a == b) continue;
    bool compact = true;
    for (int64_t na : members[a]) {
      for (int64_t nb : members[b]) {
        if ((pos.at(na) - pos.at(nb)).norm() > max_diameter) compact = false;
      }
    }
    if (!compact) continue;
    uf.unite(a, b);
    const int64_t root = uf.find(a);
    const int64_t other = root == a ? b : a;
    auto& m = members[root];
    m.insert(m.end(), members[other].begin(), members[other].end());
    members.erase(other);
  }
  std::unordered_map<int64_t, int64_t> cluster_of;
  for (auto& [root, nodes] : members) {
    for (int64_t n : nodes) cluster_of[n] = root;
  }
  return cluster_of;
}

// ---- step 6: ROI ---------------------------------------------------------------------------

// How far along a piece, from one of its ends, the intersection ROI reaches: to the road node
// closest to the junction (METHOD.md section 0); when that node is closer than
// roi_min_node_distance_m, or the piece has no inner node, to max(half width, roi_default_extent_m);
// never further than roi_max_extent_m (long straight OSM edges have no inner node for 100 m) and
// never beyond the piece's midpoint.
double roiExtent(const std::vector<Vector2d>& pts, double length, double half_width,
                 const SkeletonOptions& opt) {
  const double fallback = std::max(half_width, opt.roi_default_extent_m);
  double s = fallback;
  if (pts.size() > 2) {
    const double s_node = (pts[1] - pts[0]).norm();
    if (s_node >= opt.roi_min_node_distance_m) s = std::min(s_node, std::max(fallback, opt.roi_max_extent_m));
  }
  return std::min(s, 0.5 * length);
}

Vector2d pointOnPolyline(const std::vector<Vector2d>& pts, const std::vector<double>& cum, double s,
                         Vector2d* tangent) {
  if (pts.size() == 1) {
    if (tangent) *tangent = Vector2d(1, 0);
    return pts[0];
  }
  s = std::clamp(s, 0.0, cum.back());
  size_t i = std::upper_bound(cum.begin(), cum.end(), s) - cum.begin();
  i = std::clamp<size_t>(i, 1, pts.size() - 1);
  // Skip zero-length segments for the tangent.
  const double seg = cum[i] - cum[i - 1];
  const double t = seg > 1e-12 ? (s - cum[i - 1]) / seg : 0.0;
  if (tangent) {
    Vector2d d = pts[i] - pts[i - 1];
    for (size_t k = i; d.norm() < 1e-9 && k + 1 < pts.size(); ++k) d = pts[k + 1] - pts[k];
    *tangent = d.norm() > 1e-9 ? Vector2d(d.normalized()) : Vector2d(1, 0);
  }
  return pts[i - 1] + t * (pts[i] - pts[i - 1]);
}

// Arc lengths where a polyline crosses the polygon's edges.
std::vector<double> polygonCrossings(const std::vector<Vector2d>& pts, const std::vector<double>& cum,
                                     const std::vector<Vector2d>& poly) {
  std::vector<double> out;
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const Vector2d p = pts[i];
    const Vector2d r = pts[i + 1] - pts[i];
    for (size_t k = 0; k < poly.size(); ++k) {
      const Vector2d q = poly[k];
      const Vector2d e = poly[(k + 1) % poly.size()] - q;
      const double denom = cross(r, e);
      if (std::abs(denom) < 1e-12) continue;
      const double t = cross(q - p, e) / denom;
      const double u = cross(q - p, r) / denom;
      if (t >= 0 && t <= 1 && u >= 0 && u <= 1) out.push_back(cum[i] + t * r.norm());
    }
  }
  return out;
}

// The ROI: on each incident piece the cross-section at the ROI extent (two points, half a road
// width either side of the road), ordered counter-clockwise by angle around the centre. Where two
// consecutive points are more than 90 degrees apart (a dead end's back, the straight side of a T)
// points at the largest half width from the centre fill the gap, so the polygon is star-shaped
// around the centre and contains it.
struct CrossSection {
  Vector2d point;
  Vector2d tangent;  // pointing away from the junction
  double half_width;
};

std::vector<Vector2d> roiPolygon(const Vector2d& centre, const std::vector<CrossSection>& sections,
                                 double fallback_radius) {
  std::vector<std::pair<double, Vector2d>> pts;
  double max_hw = sections.empty() ? fallback_radius : 1.0;
  for (const CrossSection& c : sections) {
    const Vector2d n(-c.tangent.y(), c.tangent.x());
    for (double side : {-1.0, 1.0}) {
      const Vector2d q = c.point + side * c.half_width * n;
      const Vector2d d = q - centre;
      if (d.norm() < 1e-6) continue;
      pts.emplace_back(std::atan2(d.y(), d.x()), q);
    }
    max_hw = std::max(max_hw, c.half_width);
  }
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Vector2d> poly;
  if (pts.empty()) {
    for (int k = 0; k < 4; ++k) {
      const double a = kPi / 4 + k * kPi / 2;
      poly.push_back(centre + max_hw * Vector2d(std::cos(a), std::sin(a)));
    }
    return poly;
  }
  for (size_t i = 0; i < pts.size(); ++i) {
    poly.push_back(pts[i].second);
    const double a0 = pts[i].first;
    const double a1 = i + 1 < pts.size() ? pts[i + 1].first : pts[0].first + 2 * kPi;
    const double gap = a1 - a0;
    if (gap > kPi / 2) {
      const int n = static_cast<int>(std::ceil(gap / (kPi / 2)));
      for (int k = 1; k < n; ++k) {
        const double a = a0 + gap * k / n;
        poly.push_back(centre + max_hw * Vector2d(std::cos(a), std::sin(a)));
      }
    }
  }
  return poly;
}

}  // namespace

bool pointInPolygon(const std::vector<Vector2d>& poly, const Vector2d& p) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vector2d& a = poly[i];
    const Vector2d& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

// ---- the spatial index (step 7) --------------------------------------------------------------

struct Skeleton::Index {
  double cell = 20.0;
  std::unordered_map<int64_t, std::vector<std::pair<int32_t, int32_t>>> segments;  // cell -> (road, seg)
  std::unordered_map<int64_t, std::vector<int32_t>> rois;  // cell -> intersection index
  std::vector<std::vector<double>> cum;                    // per road id, cumulative arc length
  std::unordered_map<int64_t, size_t> intersection_index;  // id -> position
  size_t total_segments = 0;

  static int64_t key(int64_t cx, int64_t cy) { return (cx << 32) ^ (cy & 0xffffffffLL); }
  int64_t cellOf(double v) const { return static_cast<int64_t>(std::floor(v / cell)); }

  template <typename F>
  void forCells(const Vector2d& lo, const Vector2d& hi, F f) const {
    for (int64_t cx = cellOf(lo.x()); cx <= cellOf(hi.x()); ++cx) {
      for (int64_t cy = cellOf(lo.y()); cy <= cellOf(hi.y()); ++cy) f(key(cx, cy));
    }
  }
};

Skeleton Skeleton::build(const osm::OsmData& data, const SkeletonOptions& options) {
  if (data.ways.empty()) throw osm::OsmError("skeleton: the OSM data has no drivable way");
  if (!(options.junction_merge_radius_m >= 0.0)) {
    throw osm::OsmError("skeleton: junction_merge_radius_m must be >= 0, got " +
                        std::to_string(options.junction_merge_radius_m));
  }

  // Step 1: frame and positions.
  geo::LatLonAlt origin;
  if (options.origin) {
    origin = *options.origin;
  } else if (data.bounds.valid()) {
    origin.lat = 0.5 * (data.bounds.min_lat + data.bounds.max_lat);
    origin.lon = 0.5 * (data.bounds.min_lon + data.bounds.max_lon);
  } else {
    double lat = 0, lon = 0;
    for (const auto& [id, n] : data.nodes) {
      lat += n.lat;
      lon += n.lon;
    }
    if (data.nodes.empty()) throw osm::OsmError("skeleton: the OSM data has no nodes");
    origin.lat = lat / data.nodes.size();
    origin.lon = lon / data.nodes.size();
  }
  Skeleton sk{geo::LocalFrame(origin)};
  std::unordered_map<int64_t, Vector2d> pos;
  for (const osm::Way& w : data.ways) {
    if (w.nodes.size() < 2) {
      throw osm::OsmError("skeleton: way " + std::to_string(w.id) + " has fewer than two nodes");
    }
    for (int64_t id : w.nodes) {
      if (pos.count(id)) continue;
      auto it = data.nodes.find(id);
      if (it == data.nodes.end()) {
        throw osm::OsmError("skeleton: way " + std::to_string(w.id) + " uses node " +
                            std::to_string(id) + " that is not in the data");
      }
      pos[id] = sk.frame_.toEnu(it->second.lat, it->second.lon, 0.0).head<2>();
    }
  }

  // Steps 2-4.
  const SplitInfo split = findSplitNodes(data.ways);
  std::vector<Piece> pieces = cutWays(data.ways, split, pos);
  const auto cluster_of = clusterJunctions(pieces, split, pos, options.junction_merge_radius_m);

  // Intersections: one per cluster; id = the member node nearest the members' centroid.
  std::map<int64_t, std::vector<int64_t>> clusters;  // root -> members
  for (const auto& [node, root] : cluster_of) clusters[root].push_back(node);
  std::unordered_map<int64_t, int64_t> id_of_root;
  std::map<int64_t, Intersection> by_id;
  for (auto& [root, members] : clusters) {
    std::sort(members.begin(), members.end());
    Vector2d centroid = Vector2d::Zero();
    for (int64_t n : members) centroid += pos.at(n);
    centroid /= static_cast<double>(members.size());
    int64_t rep = members.front();
    double best = std::numeric_limits<double>::infinity();
    for (int64_t n : members) {
      const double d = (pos.at(n) - centroid).norm();
      if (d < best - 1e-9) {
        best = d;
        rep = n;
      }
    }
    Intersection in;
    in.id = rep;
    in.osm_nodes = members;
    in.centre = members.size() == 1 ? pos.at(rep) : centroid;
    in.dead_end = members.size() == 1 && split.isDeadEnd(rep);
    id_of_root[root] = rep;
    by_id.emplace(rep, std::move(in));
  }

  // Step 5: atomic roads.
  std::unordered_map<int64_t, size_t> cluster_size;
  for (const auto& [root, members] : clusters) cluster_size[id_of_root[root]] = members.size();
  for (Piece& p : pieces) {
    p.from_cluster = id_of_root.at(cluster_of.at(p.nodes.front()));
    p.to_cluster = id_of_root.at(cluster_of.at(p.nodes.back()));
    p.internal = p.from_cluster == p.to_cluster && cluster_size[p.from_cluster] > 1 &&
                 p.length <= 2.0 * options.junction_merge_radius_m;
    if (p.length < 1e-6) p.internal = true;  // two nodes at the same place: no road
  }
  // ROI extents of each piece end.
  for (Piece& p : pieces) {
    if (p.internal) continue;
    p.roi_s_front = roiExtent(p.pts, p.length, p.half_width, options);
    std::vector<Vector2d> rev(p.pts.rbegin(), p.pts.rend());
    p.roi_s_back = roiExtent(rev, p.length, p.half_width, options);
  }

  for (const Piece& p : pieces) {
    if (p.internal) continue;
    const Directions dir = allowedDirections(*p.way);
    int64_t forward_id = -1;
    for (bool along : {true, false}) {
      if (along ? !dir.forward : !dir.backward) continue;
      AtomicRoad r;
      r.id = static_cast<int64_t>(sk.roads_.size());
      r.way_id = p.way->id;
      r.along_way = along;
      r.osm_nodes = p.nodes;
      r.polyline = p.pts;
      if (!along) {
        std::reverse(r.osm_nodes.begin(), r.osm_nodes.end());
        std::reverse(r.polyline.begin(), r.polyline.end());
      }
      r.from = along ? p.from_cluster : p.to_cluster;
      r.to = along ? p.to_cluster : p.from_cluster;
      r.length = p.length;
      r.s_begin = along ? p.roi_s_front : p.roi_s_back;  // refined below
      r.s_end = p.length - (along ? p.roi_s_back : p.roi_s_front);
      r.tags = p.way->tags;
      if (along) {
        forward_id = r.id;
      } else if (forward_id >= 0) {
        r.reverse_id = forward_id;
        sk.roads_[forward_id].reverse_id = r.id;
      }
      by_id.at(r.from).outgoing.push_back(r.id);
      by_id.at(r.to).incoming.push_back(r.id);
      sk.roads_.push_back(std::move(r));
    }
  }

  // Step 6: ROI polygons from the cross-sections of the incident (non-internal) pieces.
  std::map<int64_t, std::vector<CrossSection>> sections;
  for (const Piece& p : pieces) {
    if (p.internal) continue;
    const auto cum = cumulativeLengths(p.pts);
    Vector2d t;
    Vector2d q = pointOnPolyline(p.pts, cum, p.roi_s_front, &t);
    sections[p.from_cluster].push_back({q, t, p.half_width});
    q = pointOnPolyline(p.pts, cum, p.length - p.roi_s_back, &t);
    sections[p.to_cluster].push_back({q, -t, p.half_width});
  }
  for (auto& [id, in] : by_id) {
    if (in.incoming.empty() && in.outgoing.empty()) continue;  // only internal pieces: no road
    in.roi = roiPolygon(in.centre, sections[id], options.roi_default_extent_m);
    sk.intersections_.push_back(std::move(in));
  }
  if (sk.roads_.empty()) throw osm::OsmError("skeleton: no atomic road could be built from the OSM data");

  auto index = std::make_shared<Index>();
  index->cell = options.index_cell_m;
  for (size_t i = 0; i < sk.intersections_.size(); ++i) {
    index->intersection_index[sk.intersections_[i].id] = i;
  }
  // s_begin / s_end: where the polyline crosses the ROI boundary (the last crossing of I_i's ROI
  // in the first half, the first crossing of I_j's ROI in the second half); the constructed
  // extents remain when the polyline does not cross (e.g. an end node outside a merged ROI).
  for (AtomicRoad& r : sk.roads_) {
    const auto cum = cumulativeLengths(r.polyline);
    const auto& roi_from = sk.intersections_[index->intersection_index.at(r.from)].roi;
    const auto& roi_to = sk.intersections_[index->intersection_index.at(r.to)].roi;
    const double half = 0.5 * r.length;
    double s_begin = -1, s_end = -1;
    for (double s : polygonCrossings(r.polyline, cum, roi_from)) {
      if (s <= half) s_begin = std::max(s_begin, s);
    }
    for (double s : polygonCrossings(r.polyline, cum, roi_to)) {
      if (s >= half && (s_end < 0 || s < s_end)) s_end = s;
    }
    if (s_begin >= 0) r.s_begin = s_begin;
    if (s_end >= 0) r.s_end = s_end;
    r.s_begin = std::clamp(r.s_begin, 0.0, half);
    r.s_end = std::clamp(r.s_end, half, r.length);
    index->cum.push_back(cum);
  }

  // Step 7: the grid index over road segments and ROI bounding boxes.
  for (const AtomicRoad& r : sk.roads_) {
    for (size_t k = 0; k + 1 < r.polyline.size(); ++k) {
      const Vector2d lo = r.polyline[k].cwiseMin(r.polyline[k + 1]);
      const Vector2d hi = r.polyline[k].cwiseMax(r.polyline[k + 1]);
      index->forCells(lo, hi, [&](int64_t key) {
        index->segments[key].emplace_back(static_cast<int32_t>(r.id), static_cast<int32_t>(k));
      });
      ++index->total_segments;
    }
  }
  for (size_t i = 0; i < sk.intersections_.size(); ++i) {
    Vector2d lo = sk.intersections_[i].roi.front(), hi = lo;
    for (const Vector2d& q : sk.intersections_[i].roi) {
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
    index->forCells(lo, hi, [&](int64_t key) { index->rois[key].push_back(static_cast<int32_t>(i)); });
  }
  sk.index_ = std::move(index);
  return sk;
}

const AtomicRoad* Skeleton::road(int64_t id) const {
  if (id < 0 || id >= static_cast<int64_t>(roads_.size())) return nullptr;
  return &roads_[id];
}

const Intersection* Skeleton::intersection(int64_t id) const {
  auto it = index_->intersection_index.find(id);
  return it == index_->intersection_index.end() ? nullptr : &intersections_[it->second];
}

Eigen::Vector2d Skeleton::pointAt(const AtomicRoad& road, double s) const {
  const bool ours = road.id >= 0 && road.id < static_cast<int64_t>(roads_.size()) &&
                    &roads_[road.id] == &road;
  if (ours) return pointOnPolyline(road.polyline, index_->cum[road.id], s, nullptr);
  return pointOnPolyline(road.polyline, cumulativeLengths(road.polyline), s, nullptr);
}

Eigen::Vector2d Skeleton::tangentAt(const AtomicRoad& road, double s) const {
  const bool ours = road.id >= 0 && road.id < static_cast<int64_t>(roads_.size()) &&
                    &roads_[road.id] == &road;
  Vector2d t;
  if (ours) {
    pointOnPolyline(road.polyline, index_->cum[road.id], s, &t);
  } else {
    pointOnPolyline(road.polyline, cumulativeLengths(road.polyline), s, &t);
  }
  return t;
}

std::vector<RoadMatch> Skeleton::nearestRoads(const Eigen::Vector2d& p, double max_distance,
                                              std::optional<double> heading) const {
  std::vector<RoadMatch> out;
  if (!(max_distance >= 0.0) || !p.allFinite()) return out;
  // Best (distance, segment) per road among the candidate segments.
  std::unordered_map<int32_t, std::pair<double, double>> best;  // road -> (distance, s)
  auto visit = [&](int32_t road_id, int32_t k) {
    const auto& pts = roads_[road_id].polyline;
    const Vector2d a = pts[k];
    const Vector2d d = pts[k + 1] - a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (a + t * d - p).norm();
    if (dist > max_distance) return;
    auto it = best.find(road_id);
    if (it == best.end() || dist < it->second.first) {
      best[road_id] = {dist, index_->cum[road_id][k] + t * std::sqrt(len2)};
    }
  };
  const double cells_x = 2 * max_distance / index_->cell + 1;
  if (cells_x * cells_x > static_cast<double>(index_->total_segments)) {
    for (const AtomicRoad& r : roads_) {
      for (size_t k = 0; k + 1 < r.polyline.size(); ++k) visit(static_cast<int32_t>(r.id), static_cast<int32_t>(k));
    }
  } else {
    const Vector2d off(max_distance, max_distance);
    index_->forCells(p - off, p + off, [&](int64_t key) {
      auto it = index_->segments.find(key);
      if (it == index_->segments.end()) return;
      for (const auto& [road_id, k] : it->second) visit(road_id, k);
    });
  }
  out.reserve(best.size());
  for (const auto& [road_id, ds] : best) {
    RoadMatch m;
    m.road_id = road_id;
    m.distance = ds.first;
    m.s = ds.second;
    if (heading) {
      const Vector2d t = tangentAt(roads_[road_id], m.s);
      m.heading_error = wrapAngle(*heading - std::atan2(t.y(), t.x()));
    }
    out.push_back(m);
  }
  const double w = heading ? kHeadingWeightMPerRad : 0.0;
  std::sort(out.begin(), out.end(), [w](const RoadMatch& a, const RoadMatch& b) {
    const double ca = a.distance + w * std::abs(a.heading_error);
    const double cb = b.distance + w * std::abs(b.heading_error);
    if (ca != cb) return ca < cb;
    return a.road_id < b.road_id;
  });
  return out;
}

RoadMatch Skeleton::project(int64_t road_id, const Eigen::Vector2d& p,
                             std::optional<double> heading) const {
  RoadMatch m;
  const AtomicRoad* r = road(road_id);
  if (r == nullptr || !p.allFinite()) return m;
  const auto& pts = r->polyline;
  const auto& cum = index_->cum[road_id];
  double best = std::numeric_limits<double>::infinity();
  size_t best_k = 0;
  for (size_t k = 0; k + 1 < pts.size(); ++k) {
    const Vector2d d = pts[k + 1] - pts[k];
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - pts[k]).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (pts[k] + t * d - p).norm();
    if (dist < best) {
      best = dist;
      best_k = k;
      m.s = cum[k] + t * std::sqrt(len2);
    }
  }
  m.road_id = road_id;
  m.distance = best;
  if (heading) {
    Vector2d t = pts[best_k + 1] - pts[best_k];
    if (t.norm() < 1e-9) t = tangentAt(*r, m.s);
    m.heading_error = wrapAngle(*heading - std::atan2(t.y(), t.x()));
  }
  return m;
}

const Intersection* Skeleton::intersectionContaining(const Eigen::Vector2d& p) const {
  if (!p.allFinite()) return nullptr;
  const Intersection* found = nullptr;
  double best = std::numeric_limits<double>::infinity();
  auto it = index_->rois.find(Index::key(index_->cellOf(p.x()), index_->cellOf(p.y())));
  if (it == index_->rois.end()) return nullptr;
  for (int32_t i : it->second) {
    const Intersection& in = intersections_[i];
    if (!pointInPolygon(in.roi, p)) continue;
    const double d = (in.centre - p).norm();
    if (d < best) {
      best = d;
      found = &in;
    }
  }
  return found;
}

}  // namespace lanemap::skeleton
