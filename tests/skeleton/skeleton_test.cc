// Tests of skeleton::Skeleton (M0): counts on the real files against numbers derived independently,
// graph consistency (road ends are intersections listed in their incoming/outgoing lists, reverse
// pairs), ROI polygons, nearestRoads / intersectionContaining, ENU round trip, synthetic networks
// (cross, one-way tags, dual carriageway, loops), errors, and the query timing.
//
// Expected numbers: the drivable ways of each file exported with osmium (commands in
// osm_reader_test.cc) to OPL (`osmium cat -f opl drv.osm -t way`), then a 40-line Python count over
// the N (node list) and T (tags) fields, independent of lanemap's code:
//   ways with >= 2 distinct nodes; per node the number of distinct ways using it ("shared" = 2+);
//   "self-touch" = a node a way visits twice (closing node of a ring excluded);
//   dead ends = first/last nodes of open ways used by one way only and not self-touch;
//   one-way ways = oneway in {yes,true,1,-1,reverse}, or junction=roundabout|circular or
//   highway=motorway|motorway_link without oneway=no|false|0.
//                      shared  self-touch  shared|self-touch  dead ends  one-way ways
//   west-oakland.osm     18        0              18              16           6
//   monaco.osm.pbf     1690        5            1694             488         662
// Monaco's dead end n2571904255 sits at exactly the coordinates of junction n3479387901 (osmium
// getid ... -f opl shows x7.3813473 y43.7586068 for both): that zero-length stub is no road, so the
// skeleton has 487 dead ends.
#include "core/skeleton/skeleton.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

using Eigen::Vector2d;
using lanemap::osm::OsmData;
using lanemap::osm::OsmError;
using lanemap::skeleton::AtomicRoad;
using lanemap::skeleton::Intersection;
using lanemap::skeleton::Skeleton;
using lanemap::skeleton::SkeletonOptions;

namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kDataDir = LANEMAP_DATA_DIR;

const OsmData& westOakland() {
  static const OsmData d = lanemap::osm::readOsm(kDataDir + "/osm/west-oakland.osm");
  return d;
}
const OsmData& monaco() {
  static const OsmData d = lanemap::osm::readOsm(kDataDir + "/osm/monaco.osm.pbf");
  return d;
}
const Skeleton& westOaklandSkeleton() {
  static const Skeleton s = Skeleton::build(westOakland());
  return s;
}
const Skeleton& monacoSkeleton() {
  static const Skeleton s = Skeleton::build(monaco());
  return s;
}
Skeleton unmerged(const OsmData& d) {
  SkeletonOptions o;
  o.junction_merge_radius_m = 0.0;
  return Skeleton::build(d, o);
}

struct Counts {
  size_t junctions = 0, dead_ends = 0, oneway_ways = 0;
};
Counts count(const Skeleton& s) {
  Counts c;
  for (const auto& in : s.intersections()) (in.dead_end ? c.dead_ends : c.junctions)++;
  std::set<int64_t> oneway;
  for (const auto& r : s.roads()) {
    if (r.reverse_id < 0) oneway.insert(r.way_id);
  }
  c.oneway_ways = oneway.size();
  return c;
}

double signedArea(const std::vector<Vector2d>& poly) {
  double a = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vector2d& p = poly[i];
    const Vector2d& q = poly[(i + 1) % poly.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * a;
}

// A synthetic network: nodes given in ENU metres around (43.73, 7.42).
class Builder {
 public:
  void node(int64_t id, double x, double y) {
    const double lat0 = 43.73, lon0 = 7.42;
    // Local spherical approximation; the skeleton's own frame is checked against it to 0.5 %.
    data_.nodes[id] = {id, lat0 + y / 111132.0, lon0 + x / (111320.0 * std::cos(lat0 * kPi / 180))};
  }
  void way(int64_t id, std::vector<int64_t> nodes, lanemap::osm::Tags tags) {
    if (!tags.count("highway")) tags["highway"] = "residential";
    data_.ways.push_back({id, std::move(nodes), std::move(tags)});
  }
  Skeleton build(double merge = 12.0) {
    data_.bounds = {43.72, 7.41, 43.74, 7.43};
    SkeletonOptions o;
    o.junction_merge_radius_m = merge;
    o.origin = lanemap::geo::LatLonAlt{43.73, 7.42, 0.0};
    return Skeleton::build(data_, o);
  }
  OsmData data_;
};

const Intersection* byNode(const Skeleton& s, int64_t node) {
  for (const auto& in : s.intersections()) {
    for (int64_t n : in.osm_nodes) {
      if (n == node) return &in;
    }
  }
  return nullptr;
}

void checkGraph(const Skeleton& s) {
  for (const AtomicRoad& r : s.roads()) {
    ASSERT_EQ(s.road(r.id), &r);
    const Intersection* from = s.intersection(r.from);
    const Intersection* to = s.intersection(r.to);
    ASSERT_NE(from, nullptr) << "road " << r.id;
    ASSERT_NE(to, nullptr) << "road " << r.id;
    EXPECT_EQ(std::count(from->outgoing.begin(), from->outgoing.end(), r.id), 1) << "road " << r.id;
    EXPECT_EQ(std::count(to->incoming.begin(), to->incoming.end(), r.id), 1) << "road " << r.id;
    // The polyline runs from a node of I_i to a node of I_j.
    EXPECT_NE(std::find(from->osm_nodes.begin(), from->osm_nodes.end(), r.osm_nodes.front()),
              from->osm_nodes.end());
    EXPECT_NE(std::find(to->osm_nodes.begin(), to->osm_nodes.end(), r.osm_nodes.back()),
              to->osm_nodes.end());
    ASSERT_EQ(r.polyline.size(), r.osm_nodes.size());
    ASSERT_GE(r.polyline.size(), 2u);
    double len = 0;
    for (size_t i = 1; i < r.polyline.size(); ++i) len += (r.polyline[i] - r.polyline[i - 1]).norm();
    EXPECT_NEAR(r.length, len, 1e-6);
    EXPECT_GT(r.length, 0.0);
    EXPECT_LE(0.0, r.s_begin);
    EXPECT_LE(r.s_begin, r.s_end);
    EXPECT_LE(r.s_end, r.length + 1e-9);
    if (r.reverse_id >= 0) {
      const AtomicRoad* rev = s.road(r.reverse_id);
      ASSERT_NE(rev, nullptr);
      EXPECT_EQ(rev->reverse_id, r.id);
      EXPECT_EQ(rev->from, r.to);
      EXPECT_EQ(rev->to, r.from);
      EXPECT_EQ(rev->way_id, r.way_id);
      EXPECT_NE(rev->along_way, r.along_way);
      ASSERT_EQ(rev->polyline.size(), r.polyline.size());
      for (size_t i = 0; i < r.polyline.size(); ++i) {
        EXPECT_EQ(rev->polyline[i], r.polyline[r.polyline.size() - 1 - i]);
      }
      // Both ROIs cut the same places: s_begin of one = length - s_end of the other (1 cm: the
      // crossings are computed on the reversed polyline).
      EXPECT_NEAR(rev->s_begin, r.length - r.s_end, 0.01);
    }
  }
  for (const Intersection& in : s.intersections()) {
    EXPECT_EQ(s.intersection(in.id), &in);
    EXPECT_FALSE(in.incoming.empty() && in.outgoing.empty()) << "intersection " << in.id;
    for (int64_t id : in.outgoing) EXPECT_EQ(s.road(id)->from, in.id);
    for (int64_t id : in.incoming) EXPECT_EQ(s.road(id)->to, in.id);
    // ROI: at least a triangle, counter-clockwise, containing the centre.
    ASSERT_GE(in.roi.size(), 3u);
    EXPECT_GT(signedArea(in.roi), 0.0) << "intersection " << in.id;
    EXPECT_EQ(s.intersectionContaining(in.centre) != nullptr, true) << "intersection " << in.id;
  }
}

}  // namespace

TEST(Skeleton, WestOaklandCountsMatchIndependentCount) {
  const Skeleton s = unmerged(westOakland());
  const Counts c = count(s);
  EXPECT_EQ(c.junctions, 18u);
  EXPECT_EQ(c.dead_ends, 16u);
  EXPECT_EQ(c.oneway_ways, 6u);
  // Default merging joins exactly one pair of junction nodes (two ways meeting Goss Street 7 m
  // apart), every junction node still belongs to exactly one intersection.
  const Skeleton& m = westOaklandSkeleton();
  const Counts cm = count(m);
  EXPECT_EQ(cm.junctions, 17u);
  EXPECT_EQ(cm.dead_ends, 16u);
  size_t junction_nodes = 0;
  for (const auto& in : m.intersections()) junction_nodes += in.dead_end ? 0 : in.osm_nodes.size();
  EXPECT_EQ(junction_nodes, 18u);
}

TEST(Skeleton, MonacoCountsMatchIndependentCount) {
  const Skeleton s = unmerged(monaco());
  const Counts c = count(s);
  EXPECT_EQ(c.junctions, 1694u);  // |shared or self-touch|: one self-touch node is also shared
  EXPECT_EQ(c.dead_ends, 487u);
  EXPECT_EQ(c.oneway_ways, 662u);
}

TEST(Skeleton, GraphIsConsistentOnRealFiles) {
  {
    SCOPED_TRACE("west-oakland");
    checkGraph(westOaklandSkeleton());
  }
  {
    SCOPED_TRACE("monaco");
    checkGraph(monacoSkeleton());
  }
}

TEST(Skeleton, MergedIntersectionsAreCompact) {
  const Skeleton& s = monacoSkeleton();
  size_t merged = 0;
  for (const auto& in : s.intersections()) {
    if (in.osm_nodes.size() < 2) continue;
    ++merged;
    // Every two member nodes within 2 x junction_merge_radius_m (24 m), by construction.
    // The members' positions are the ends of the incident roads.
    std::map<int64_t, Vector2d> pos;
    for (int64_t id : in.outgoing) pos[s.road(id)->osm_nodes.front()] = s.road(id)->polyline.front();
    for (int64_t id : in.incoming) pos[s.road(id)->osm_nodes.back()] = s.road(id)->polyline.back();
    for (const auto& [a, pa] : pos) {
      for (const auto& [b, pb] : pos) EXPECT_LE((pa - pb).norm(), 24.0 + 1e-9);
    }
  }
  EXPECT_GT(merged, 50u);  // Monaco's dual carriageways and small roundabouts (174 today)
}

TEST(Skeleton, EnuRoundTripBelowOneMillimetre) {
  const Skeleton& s = monacoSkeleton();
  double worst = 0;
  for (const auto& [id, n] : monaco().nodes) {
    const Eigen::Vector3d enu = s.frame().toEnu(n.lat, n.lon, 0.0);
    const auto back = s.frame().toWgs84(enu);
    const Eigen::Vector3d again = s.frame().toEnu(back);
    worst = std::max(worst, (again - enu).norm());
    // 1e-8 degree is about 1 mm.
    EXPECT_NEAR(back.lat, n.lat, 1e-8);
    EXPECT_NEAR(back.lon, n.lon, 1e-8);
  }
  EXPECT_LT(worst, 1e-3);
  // Origin defaults to the centre of the header bounds.
  EXPECT_DOUBLE_EQ(s.frame().origin().lat, 0.5 * (43.71 + 43.77));
  EXPECT_DOUBLE_EQ(s.frame().origin().lon, 0.5 * (7.349 + 7.491));
}

TEST(Skeleton, NearestRoadsFindsTheRoadAndItsDirection) {
  const Skeleton& s = westOaklandSkeleton();
  for (const AtomicRoad& r : s.roads()) {
    const double sm = 0.5 * r.length;
    const Vector2d p = s.pointAt(r, sm);
    const Vector2d t = s.tangentAt(r, sm);
    const double heading = std::atan2(t.y(), t.x());
    const auto matches = s.nearestRoads(p, 5.0, heading);
    ASSERT_FALSE(matches.empty());
    EXPECT_EQ(matches[0].road_id, r.id);
    EXPECT_NEAR(matches[0].distance, 0.0, 1e-6);
    EXPECT_NEAR(matches[0].s, sm, 1e-6);
    EXPECT_NEAR(matches[0].heading_error, 0.0, 1e-9);
    if (r.reverse_id >= 0) {
      // The opposite direction is found too, second, with a heading error of pi.
      ASSERT_GE(matches.size(), 2u);
      EXPECT_EQ(matches[1].road_id, r.reverse_id);
      EXPECT_NEAR(std::abs(matches[1].heading_error), kPi, 1e-9);
    }
    // 2.5 m to the side: the distance is 2.5 m (road straight there to 1 cm, or the point is at
    // least as close to another piece of the road).
    const Vector2d side = p + 2.5 * Vector2d(-t.y(), t.x());
    const auto m2 = s.nearestRoads(side, 5.0, heading);
    ASSERT_FALSE(m2.empty());
    EXPECT_LE(m2[0].distance, 2.5 + 1e-6);
    // Beyond max_distance nothing of this road.
    for (const auto& m : s.nearestRoads(side, 2.0)) EXPECT_NE(m.road_id, r.id);
  }
}

TEST(Skeleton, NearestRoadsOnMonacoReturnsAZeroDistanceRoadWithTheHeading) {
  const Skeleton& s = monacoSkeleton();
  int checked = 0;
  for (size_t i = 0; i < s.roads().size(); i += 7) {
    const AtomicRoad& r = s.roads()[i];
    const Vector2d p = s.pointAt(r, 0.5 * r.length);
    const Vector2d t = s.tangentAt(r, 0.5 * r.length);
    const auto m = s.nearestRoads(p, 10.0, std::atan2(t.y(), t.x()));
    ASSERT_FALSE(m.empty());
    // Ways may overlap in OSM, so the first may be another road on the same spot and direction.
    EXPECT_NEAR(m[0].distance, 0.0, 1e-6);
    EXPECT_NEAR(m[0].heading_error, 0.0, 1e-6);
    checked += m[0].road_id == r.id;
  }
  EXPECT_GE(checked, static_cast<int>(s.roads().size() / 7 * 0.99));
}

TEST(Skeleton, IntersectionContainingFindsRoiNotRoadMiddle) {
  const Skeleton& s = westOaklandSkeleton();
  for (const AtomicRoad& r : s.roads()) {
    if (r.s_end - r.s_begin < 20.0) continue;
    // Points well between the ROIs are in none; points just inside the ends are in I_i / I_j.
    const Vector2d mid = s.pointAt(r, 0.5 * (r.s_begin + r.s_end));
    const Intersection* in = s.intersectionContaining(mid);
    EXPECT_TRUE(in == nullptr) << "road " << r.id << " middle in ROI of " << in->id;
    const Intersection* a = s.intersectionContaining(s.pointAt(r, std::max(0.0, r.s_begin - 0.5)));
    const Intersection* b = s.intersectionContaining(s.pointAt(r, r.s_end + 0.5));
    ASSERT_NE(a, nullptr);
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(a->id, r.from);
    EXPECT_EQ(b->id, r.to);
    EXPECT_EQ(s.intersectionContaining(s.pointAt(r, r.s_begin + 0.5)), nullptr);
  }
  EXPECT_EQ(s.intersectionContaining(Vector2d(1e6, 1e6)), nullptr);
}

TEST(Skeleton, CrossOfTwoWayRoads) {
  Builder b;
  b.node(1, -100, 0);
  b.node(2, 0, 0);
  b.node(3, 100, 0);
  b.node(4, 0, -100);
  b.node(5, 0, 100);
  b.node(6, 50, 0.5);  // inner node of the east arm, far from the junction
  b.way(10, {1, 2, 6, 3}, {});
  b.way(11, {4, 2, 5}, {});
  const Skeleton s = b.build();
  checkGraph(s);
  EXPECT_EQ(s.intersections().size(), 5u);
  EXPECT_EQ(s.roads().size(), 8u);
  const Intersection* centre = s.intersection(2);
  ASSERT_NE(centre, nullptr);
  EXPECT_FALSE(centre->dead_end);
  EXPECT_EQ(centre->incoming.size(), 4u);
  EXPECT_EQ(centre->outgoing.size(), 4u);
  EXPECT_TRUE(s.intersection(1)->dead_end);
  EXPECT_NEAR(centre->centre.norm(), 0.0, 0.5);  // frame origin = node 2 (spherical approx.)
  // Residential two-way: half width 3.25 m, ROI extent max(3.25, 6) = 6 m on every arm (the inner
  // node at 50 m is further than roi_max_extent_m = 15 m, so the extent is 15 m on the east arm).
  double max_r = 0;
  for (const auto& q : centre->roi) max_r = std::max(max_r, (q - centre->centre).norm());
  EXPECT_NEAR(max_r, std::hypot(15.0, 3.25), 0.1);
  for (int64_t id : centre->outgoing) {
    const AtomicRoad* r = s.road(id);
    const bool east = r->osm_nodes.back() == 3;
    EXPECT_NEAR(r->s_begin, east ? 15.0 : 6.0, 0.05) << "road " << id;
    // The dead end's ROI reaches back the same extent from the end node.
    EXPECT_NEAR(r->length - r->s_end, east ? 15.0 : 6.0, 0.05) << "road " << id;
  }
  // Road ids: by way id, segment, direction.
  EXPECT_EQ(s.roads()[0].way_id, 10);
  EXPECT_EQ(s.roads()[0].osm_nodes, (std::vector<int64_t>{1, 2}));
  EXPECT_EQ(s.roads()[1].osm_nodes, (std::vector<int64_t>{2, 1}));
  EXPECT_EQ(s.roads()[2].osm_nodes, (std::vector<int64_t>{2, 6, 3}));
  EXPECT_EQ(s.roads()[7].way_id, 11);
}

TEST(Skeleton, OneWayTags) {
  Builder b;
  for (int i = 0; i < 8; ++i) {
    b.node(100 + i, -50, i * 60.0);
    b.node(200 + i, 50, i * 60.0);
  }
  b.way(1, {100, 200}, {{"oneway", "yes"}});
  b.way(2, {101, 201}, {{"oneway", "-1"}});
  b.way(3, {102, 202}, {{"junction", "roundabout"}});
  b.way(4, {103, 203}, {{"highway", "motorway"}});
  b.way(5, {104, 204}, {{"highway", "motorway_link"}, {"oneway", "no"}});
  b.way(6, {105, 205}, {{"oneway", "no"}});
  b.way(7, {106, 206}, {{"oneway", "true"}});
  b.way(8, {107, 207}, {{"oneway", "1"}});
  const Skeleton s = b.build();
  checkGraph(s);
  std::map<int64_t, std::vector<const AtomicRoad*>> by_way;
  for (const auto& r : s.roads()) by_way[r.way_id].push_back(&r);
  auto dirs = [&](int64_t way) {
    std::string d;
    for (const auto* r : by_way[way]) d += r->along_way ? "F" : "B";
    return d;
  };
  EXPECT_EQ(dirs(1), "F");
  EXPECT_EQ(dirs(2), "B");
  EXPECT_EQ(by_way[2][0]->osm_nodes, (std::vector<int64_t>{201, 101}));
  EXPECT_EQ(dirs(3), "F");
  EXPECT_EQ(dirs(4), "F");
  EXPECT_EQ(dirs(5), "FB");
  EXPECT_EQ(dirs(6), "FB");
  EXPECT_EQ(dirs(7), "F");
  EXPECT_EQ(dirs(8), "F");
  EXPECT_EQ(by_way[1][0]->reverse_id, -1);
}

TEST(Skeleton, DualCarriagewayCrossingBecomesOneIntersection) {
  // Two dual carriageways (one-way pairs 10 m apart) crossing: 4 junction nodes on a 10 m square,
  // joined by 10 m pieces that are inside the intersection.
  Builder b;
  b.node(1, -200, -5);
  b.node(2, -5, -5);
  b.node(3, 5, -5);
  b.node(4, 200, -5);  // eastbound y = -5
  b.node(5, 200, 5);
  b.node(6, 5, 5);
  b.node(7, -5, 5);
  b.node(8, -200, 5);  // westbound y = +5
  b.node(9, 5, -200);
  b.node(10, 5, 200);  // northbound x = +5 through 3, 6
  b.node(11, -5, 200);
  b.node(12, -5, -200);  // southbound x = -5 through 7, 2
  b.way(100, {1, 2, 3, 4}, {{"oneway", "yes"}, {"highway", "primary"}});
  b.way(101, {5, 6, 7, 8}, {{"oneway", "yes"}, {"highway", "primary"}});
  b.way(102, {9, 3, 6, 10}, {{"oneway", "yes"}, {"highway", "primary"}});
  b.way(103, {11, 7, 2, 12}, {{"oneway", "yes"}, {"highway", "primary"}});
  const Skeleton s = b.build(12.0);
  checkGraph(s);
  const Intersection* x = byNode(s, 2);
  ASSERT_NE(x, nullptr);
  EXPECT_EQ(x->osm_nodes, (std::vector<int64_t>{2, 3, 6, 7}));
  EXPECT_EQ(x->incoming.size(), 4u);
  EXPECT_EQ(x->outgoing.size(), 4u);
  EXPECT_NEAR(x->centre.norm(), 0.0, 0.5);
  EXPECT_EQ(s.roads().size(), 8u);  // the four 10 m pieces are part of the intersection
  for (const auto& r : s.roads()) EXPECT_GT(r.length, 150.0);
  // Without merging: 4 junctions and the 4 inner pieces are roads.
  const Skeleton u = b.build(0.0);
  checkGraph(u);
  EXPECT_EQ(u.roads().size(), 12u);
  // Merging must not snowball: a chain of 10 m pieces 100 m long stays several intersections.
  Builder c;
  std::vector<int64_t> chain;
  for (int i = 0; i <= 10; ++i) {
    c.node(i + 1, i * 10.0, 0);
    chain.push_back(i + 1);
    c.node(100 + i, i * 10.0, 80.0);
    c.way(1000 + i, {i + 1, 100 + i}, {});
  }
  c.way(999, chain, {});
  const Skeleton cs = c.build(12.0);
  checkGraph(cs);
  for (const auto& in : cs.intersections()) {
    EXPECT_LE(in.osm_nodes.size(), 3u);  // at most 3 nodes fit in 24 m at 10 m spacing
  }
}

TEST(Skeleton, LoopsAndSelfTouchingWays) {
  Builder b;
  // A ring (closed way 1-2-3-4-1) with one connecting road at node 3.
  b.node(1, 0, 0);
  b.node(2, 100, 0);
  b.node(3, 100, 100);
  b.node(4, 0, 100);
  b.node(5, 300, 100);
  b.way(10, {1, 2, 3, 4, 1}, {});
  b.way(11, {3, 5}, {});
  // A P-shaped way: 6-7-8-9-7 (visits 7 twice).
  b.node(6, 0, 500);
  b.node(7, 100, 500);
  b.node(8, 200, 500);
  b.node(9, 150, 600);
  b.way(12, {6, 7, 8, 9, 7}, {});
  const Skeleton s = b.build();
  checkGraph(s);
  // The ring's closing node 1 is no intersection; the ring is one loop road at node 3 each way.
  EXPECT_EQ(byNode(s, 1), nullptr);
  const Intersection* n3 = s.intersection(3);
  ASSERT_NE(n3, nullptr);
  int loops = 0;
  for (const auto& r : s.roads()) {
    if (r.way_id == 10) {
      EXPECT_EQ(r.from, 3);
      EXPECT_EQ(r.to, 3);
      EXPECT_NEAR(r.length, 400.0, 1.0);
      ++loops;
    }
  }
  EXPECT_EQ(loops, 2);
  // The P: node 7 is a junction (the way loops back to it), 6 a dead end, 9 nothing.
  const Intersection* n7 = s.intersection(7);
  ASSERT_NE(n7, nullptr);
  EXPECT_FALSE(n7->dead_end);
  EXPECT_EQ(n7->outgoing.size(), 3u);  // to 6, and the loop in both directions
  EXPECT_TRUE(s.intersection(6)->dead_end);
  EXPECT_EQ(byNode(s, 9), nullptr);
}

TEST(Skeleton, BadInputThrows) {
  OsmData empty;
  EXPECT_THROW(Skeleton::build(empty), OsmError);
  Builder b;
  b.node(1, 0, 0);
  b.way(5, {1, 2}, {});
  try {
    b.build();
    FAIL() << "no OsmError";
  } catch (const OsmError& e) {
    EXPECT_NE(std::string(e.what()).find("node 2"), std::string::npos) << e.what();
  }
  Builder c;
  c.node(1, 0, 0);
  c.node(2, 10, 0);
  c.way(5, {1, 2}, {});
  EXPECT_THROW(c.build(-1.0), OsmError);
}

TEST(Skeleton, NearestRoadsFindsEveryNoisyQueryOnMonaco) {
  // Speed is measured by tools/bench (lanemap-bench-road-tracker), not asserted here.
  const Skeleton& s = monacoSkeleton();
  // Query points: near the roads (where a car is), deterministic.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 3.0);
  size_t found = 0, right_road = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const AtomicRoad& r = s.roads()[rng() % s.roads().size()];
    const double sq = std::uniform_real_distribution<double>(0, r.length)(rng);
    const Vector2d t = s.tangentAt(r, sq);
    const Vector2d p = s.pointAt(r, sq) + Vector2d(noise(rng), noise(rng));
    const auto matches = s.nearestRoads(p, 15.0, std::atan2(t.y(), t.x()));
    found += !matches.empty();
    for (const auto& m : matches) right_road += m.road_id == r.id;
  }
  EXPECT_EQ(found, static_cast<size_t>(n));  // 3 m noise is always within 15 m of the road
  EXPECT_EQ(right_road, static_cast<size_t>(n)) << "the sampled road is among the matches";
}
