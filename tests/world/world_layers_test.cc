// Roads on different OSM levels in the simulator's one-ground world (WorldOptions::osm_layers): a
// bridge (layer=1) over a street, a tunnel (layer=-1) under it. Seen from above (sample()) and
// from the bridge, where they cross the upper road's surface and paint lie over the lower one's:
// along the bridge's lanes nothing of the street shows (no kerb, no line, no lane of it), where,
// with every road on one level, the street's kerbs cut across the bridge's lanes; nothing of the
// tunnel shows on the street. Seen from the street (what the simulator renders for a car on it,
// WorldSeenFromLevel), the bridge above is not on its ground: its lanes run on under it.
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace lanemap::sim {
namespace {

constexpr double kLat0 = 37.80, kLon0 = -122.27;

// An OSM file of three straight two-way ways (two lanes), none sharing a node: a bridge along x,
// a street along y crossing it at the origin, a tunnel along x 60 m north crossing the street.
std::string crossingOsm() {
  std::ostringstream o;
  o.precision(10);
  const double m_lat = 1.0 / 111320.0, m_lon = 1.0 / (111320.0 * std::cos(kLat0 * M_PI / 180.0));
  int id = 1;
  auto node = [&](double x, double y) {
    o << "  <node id=\"" << id << "\" lat=\"" << kLat0 + y * m_lat << "\" lon=\"" << kLon0 + x * m_lon << "\"/>\n";
    return id++;
  };
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<osm version=\"0.6\">\n";
  const int b0 = node(-150, 0), b1 = node(150, 0);
  const int s0 = node(0, -150), s1 = node(0, 150);
  const int t0 = node(-150, 60), t1 = node(150, 60);
  const int r1 = node(300, 0), r2 = node(150, -100);  // ground roads from the bridge's east end
  auto way = [&](int wid, int a, int b, const std::string& extra) {
    o << "  <way id=\"" << wid << "\">\n    <nd ref=\"" << a << "\"/>\n    <nd ref=\"" << b << "\"/>\n"
      << "    <tag k=\"highway\" v=\"secondary\"/>\n    <tag k=\"lanes\" v=\"2\"/>\n" << extra << "  </way>\n";
  };
  way(100, b0, b1, "    <tag k=\"bridge\" v=\"yes\"/>\n    <tag k=\"layer\" v=\"1\"/>\n");
  way(200, s0, s1, "");
  way(300, t0, t1, "    <tag k=\"tunnel\" v=\"yes\"/>\n");  // no layer tag: a tunnel is level -1
  way(400, b1, r1, "");  // the bridge comes down at its east end (node b1) onto two ground roads:
  way(500, b1, r2, "");  // b1 is a junction of levels 1 and 0
  o << "</osm>\n";
  return o.str();
}

struct Crossing {
  skeleton::Skeleton sk;
  std::map<int64_t, int64_t> way_of_road;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();  // the skeleton's ENU minus the layout's metres
};

const Crossing& crossing() {
  static const Crossing c = [] {
    lanemap::testing::TempDir tmp("world-layers");
    const std::string path = tmp.str("crossing.osm");
    std::ofstream(path) << crossingOsm();
    Crossing out{skeleton::Skeleton::build(osm::readOsm(path)), {}};
    for (const auto& r : out.sk.roads()) {
      out.way_of_road[r.id] = r.way_id;
      if (r.way_id == 200 && r.polyline.front().y() < 0) out.offset = r.polyline.front() - Eigen::Vector2d(0.0, -150.0);
    }
    return out;
  }();
  return c;
}

// What the ground shows along a line across the crossing: the set of surfaces and the ways whose
// lanelets it lies in.
struct Seen {
  std::set<Surface> surfaces;
  std::set<int64_t> ways;
};
Seen along(const SimWorld& sw, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const World* view = nullptr) {
  const World& w = view ? *view : sw;
  const Eigen::Vector2d o = crossing().offset;
  Seen seen;
  std::map<int64_t, int64_t> road_of_lanelet;
  for (const auto& l : sw.truth().lanelets) road_of_lanelet[l.id] = l.road_id;
  const int n = static_cast<int>((b - a).norm() / 0.05);
  for (int k = 0; k <= n; ++k) {
    const Eigen::Vector2d p = o + a + (b - a) * k / n;
    const GroundSample g = w.sample(p.x(), p.y());
    seen.surfaces.insert(g.surface);
    if (g.lanelet >= 0 && road_of_lanelet.count(g.lanelet)) seen.ways.insert(crossing().way_of_road.at(road_of_lanelet.at(g.lanelet)));
  }
  return seen;
}

std::unique_ptr<SimWorld> build(bool osm_layers) {
  WorldOptions o;
  o.seed = 5;
  o.flat = true;
  o.osm_layers = osm_layers;
  return buildWorld(crossing().sk, o);
}

}  // namespace

TEST(WorldLayers, TheUpperRoadIsPaintedOverTheLowerWhereTheyCross) {
  const auto layered = build(true), flat = build(false);
  // Along each of the bridge's two lanes (1.5 m either side of its line), 12 m across the street.
  for (double y : {-1.5, 1.5}) {
    const Seen on = along(*layered, {-12.0, y}, {12.0, y});
    EXPECT_FALSE(on.surfaces.count(Surface::kCurb)) << "a kerb across the bridge's lane at y " << y;
    EXPECT_EQ(on.ways, std::set<int64_t>{100}) << "the bridge's lane at y " << y << " shows another road's lanes";
    const Seen before = along(*flat, {-12.0, y}, {12.0, y});
    EXPECT_TRUE(before.surfaces.count(Surface::kCurb)) << "one level: the street's kerbs cross the bridge's lane (the test shows nothing)";
    EXPECT_TRUE(before.ways.count(200)) << "one level: the street's lanes show on the bridge";
  }
  // The street beside the tunnel: the tunnel's paint is under the street's, so the street's lanes
  // run on there unbroken; on one level the tunnel's kerbs cross them.
  for (double x : {-1.5, 1.5}) {
    const Seen on = along(*layered, {x, 50.0}, {x, 70.0});
    EXPECT_FALSE(on.surfaces.count(Surface::kCurb)) << "a kerb across the street's lane at x " << x;
    EXPECT_EQ(on.ways, std::set<int64_t>{200});
    EXPECT_TRUE(along(*flat, {x, 50.0}, {x, 70.0}).surfaces.count(Surface::kCurb));
  }
  // The levels of the roads' lanelets, and the ground as seen from each road's level.
  std::map<int64_t, std::set<int>> levels;
  for (const auto& l : layered->truth().lanelets) {
    if (l.road_id >= 0) levels[crossing().way_of_road.at(l.road_id)].insert(layered->levelOf(l.id));
  }
  EXPECT_EQ(levels[100], std::set<int>{1});
  EXPECT_EQ(levels[200], std::set<int>{0});
  EXPECT_EQ(levels[300], std::set<int>{-1});
  const WorldSeenFromLevel from_street(*layered, 0), from_bridge(*layered, 1), from_tunnel(*layered, -1);
  for (double x : {-1.5, 1.5}) {
    const Seen under = along(*layered, {x, -12.0}, {x, 12.0}, &from_street);
    EXPECT_FALSE(under.surfaces.count(Surface::kCurb)) << "the bridge's kerb on the street's lane at x " << x;
    EXPECT_EQ(under.ways, std::set<int64_t>{200}) << "the street's lane under the bridge at x " << x;
    EXPECT_TRUE(along(*layered, {x, -12.0}, {x, 12.0}).ways.count(100)) << "from above the bridge covers the street";
  }
  for (double y : {-1.5, 1.5}) {
    const Seen on = along(*layered, {-12.0, y}, {12.0, y}, &from_bridge);
    EXPECT_EQ(on.ways, std::set<int64_t>{100});
    EXPECT_FALSE(on.surfaces.count(Surface::kCurb));
    const Seen in = along(*layered, {-12.0, 60.0 + y}, {12.0, 60.0 + y}, &from_tunnel);
    EXPECT_EQ(in.ways, std::set<int64_t>{300}) << "the tunnel's lane under the street at y " << 60.0 + y;
    EXPECT_FALSE(in.surfaces.count(Surface::kCurb));
  }
  // The junction where the bridge comes down (b1, 150 m east) is on its lower road's level: seen
  // from that road it is there (drivable asphalt around the node), not left out with the bridge.
  int drivable = 0, total = 0;
  for (double dx = -3.0; dx <= 3.0; dx += 1.0) {
    for (double dy = -3.0; dy <= 3.0; dy += 1.0) {
      const Eigen::Vector2d p = crossing().offset + Eigen::Vector2d(150.0 + dx, dy);
      const GroundSample g = from_street.sample(p.x(), p.y());
      drivable += g.surface == Surface::kIntersection || g.surface == Surface::kAsphalt ||
                  g.surface == Surface::kDashedPaint || g.surface == Surface::kSolidPaint || g.surface == Surface::kStopLinePaint;
      ++total;
    }
  }
  EXPECT_GE(drivable, total * 9 / 10) << "the bridge's end junction, seen from the ground road it joins";
  // Away from the crossings every road is as it was.
  for (const auto& [a, b] : {std::pair<Eigen::Vector2d, Eigen::Vector2d>{{-100.0, -1.5}, {-60.0, -1.5}},
                             {{1.5, -100.0}, {1.5, -60.0}}, {{-100.0, 61.5}, {-60.0, 61.5}}}) {
    const Seen x = along(*layered, a, b), y = along(*flat, a, b);
    EXPECT_EQ(x.surfaces, y.surfaces);
    EXPECT_EQ(x.ways, y.ways);
  }
}
}  // namespace lanemap::sim
