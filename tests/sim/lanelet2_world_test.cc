// The simulator's world from a Lanelet2 map (core/sim/lanelet2_world.h): a small hand-made map
// and the Lanelet2 project's Karlsruhe example.
#include "core/sim/lanelet2_world.h"

#include "core/io/lanelet2.h"
#include "core/sim/drive.h"
#include "core/sim/world_builder.h"
#include "tests/common/sim_drive.h"

#include "core/osm/osm_data.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

namespace {

using namespace lanemap;

constexpr double kPi = 3.14159265358979323846;

// A hand-made Lanelet2 map (ENU metres around lat 49, lon 8.4), right-hand traffic:
//  - the west road: two lanelets side by side driving east, x 0..60 (left lane y 0..3.5, right
//    lane y -3.5..0), road_border / dashed / curbstone, a stop line at x = 59;
//  - a junction at x 60..80 where each lane branches in two: the left lane straight on (J3) or
//    left to the north (J4), the right lane straight on (J1) or right to the south (J2);
//  - the east road: two lanelets x 80..140 with a crosswalk lanelet across it at x 100..104;
//  - the north road: one lanelet x 75..78.5 driving north (curb on its left, a solid line on its
//    right); the south road: one two-way lanelet
//    (one_way=no) x 71.5..75 drawn driving south.
struct HandMap {
  std::map<std::string, int64_t> lanelet;  // name -> relation id
  std::string xml;
};

HandMap handMap() {
  HandMap m;
  geo::LatLonAlt o;
  o.lat = 49.0;
  o.lon = 8.4;
  const geo::LocalFrame frame(o);
  std::string nodes, ways, rels;
  int64_t next = 1000;
  char buf[256];
  auto way = [&](const std::vector<Eigen::Vector2d>& pts, const std::string& type, const std::string& subtype) {
    const int64_t id = next++;
    std::string w = "  <way id=\"" + std::to_string(id) + "\">\n";
    for (const auto& p : pts) {
      const int64_t nid = next++;
      const auto g = frame.toWgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
      std::snprintf(buf, sizeof(buf), "  <node id=\"%lld\" lat=\"%.10f\" lon=\"%.10f\"><tag k=\"ele\" v=\"0\"/></node>\n",
                    static_cast<long long>(nid), g.lat, g.lon);
      nodes += buf;
      w += "    <nd ref=\"" + std::to_string(nid) + "\"/>\n";
    }
    w += "    <tag k=\"type\" v=\"" + type + "\"/>\n";
    if (!subtype.empty()) w += "    <tag k=\"subtype\" v=\"" + subtype + "\"/>\n";
    ways += w + "  </way>\n";
    return id;
  };
  auto line = [](double x0, double y0, double x1, double y1) {
    std::vector<Eigen::Vector2d> p;
    for (int i = 0; i <= 6; ++i) p.emplace_back(x0 + (x1 - x0) * i / 6.0, y0 + (y1 - y0) * i / 6.0);
    return p;
  };
  // Quarter circle about c with radius r from angle a0 to a1 (degrees, 0 = +x).
  auto arc = [](Eigen::Vector2d c, double r, double a0, double a1) {
    std::vector<Eigen::Vector2d> p;
    for (int i = 0; i <= 12; ++i) {
      const double a = (a0 + (a1 - a0) * i / 12.0) * kPi / 180.0;
      p.push_back(c + r * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
    return p;
  };
  auto lanelet = [&](const std::string& name, int64_t left, int64_t right, const std::string& subtype,
                     const std::string& one_way) {
    const int64_t id = next++;
    m.lanelet[name] = id;
    rels += "  <relation id=\"" + std::to_string(id) + "\">\n    <member type=\"way\" ref=\"" + std::to_string(left) +
            "\" role=\"left\"/>\n    <member type=\"way\" ref=\"" + std::to_string(right) +
            "\" role=\"right\"/>\n    <tag k=\"type\" v=\"lanelet\"/>\n    <tag k=\"subtype\" v=\"" + subtype +
            "\"/>\n    <tag k=\"location\" v=\"urban\"/>\n    <tag k=\"one_way\" v=\"" + one_way + "\"/>\n  </relation>\n";
  };
  // West road.
  const int64_t a = way(line(0, 3.5, 60, 3.5), "road_border", "");
  const int64_t b = way(line(0, 0, 60, 0), "line_thin", "dashed");
  const int64_t c = way(line(0, -3.5, 60, -3.5), "curbstone", "high");
  lanelet("west_left", a, b, "road", "yes");
  lanelet("west_right", b, c, "road", "yes");
  way(line(59, -3.5, 59, 3.5), "stop_line", "");
  // Junction.
  const int64_t v1 = way(line(60, 3.5, 80, 3.5), "virtual", "");
  const int64_t v2 = way(line(60, 0, 80, 0), "virtual", "");
  const int64_t v3 = way(line(60, -3.5, 80, -3.5), "virtual", "");
  lanelet("j_straight_left", v1, v2, "road", "yes");
  lanelet("j_straight_right", v2, v3, "road", "yes");
  const int64_t r_out = way(arc({60, -15}, 15.0, 90, 0), "virtual", "");
  const int64_t r_in = way(arc({60, -15}, 11.5, 90, 0), "virtual", "");
  lanelet("j_right", r_out, r_in, "road", "yes");
  const int64_t l_in = way(arc({60, 18.5}, 15.0, -90, 0), "virtual", "");
  const int64_t l_out = way(arc({60, 18.5}, 18.5, -90, 0), "virtual", "");
  lanelet("j_left", l_in, l_out, "road", "yes");
  // East road and its crosswalk.
  const int64_t d = way(line(80, 3.5, 140, 3.5), "road_border", "");
  const int64_t e = way(line(80, 0, 140, 0), "line_thin", "dashed");
  const int64_t f = way(line(80, -3.5, 140, -3.5), "curbstone", "high");
  lanelet("east_left", d, e, "road", "yes");
  lanelet("east_right", e, f, "road", "yes");
  const int64_t cw_left = way(line(100, -3.5, 100, 3.5), "pedestrian_marking", "");
  const int64_t cw_right = way(line(104, -3.5, 104, 3.5), "pedestrian_marking", "");
  lanelet("crosswalk", cw_left, cw_right, "crosswalk", "no");
  // North road (one way) and south road (one two-way lanelet, drawn driving south).
  const int64_t nl = way(line(75, 18.5, 75, 48.5), "curbstone", "high");
  const int64_t nr = way(line(78.5, 18.5, 78.5, 48.5), "line_thin", "solid");
  lanelet("north", nl, nr, "road", "yes");
  const int64_t sl = way(line(75, -15, 75, -45), "curbstone", "high");
  const int64_t sr = way(line(71.5, -15, 71.5, -45), "curbstone", "high");
  lanelet("south", sl, sr, "road", "no");
  m.xml = "<?xml version=\"1.0\"?>\n<osm version=\"0.6\" generator=\"lanelet2_world_test\">\n" + nodes + ways + rels + "</osm>\n";
  return m;
}

struct Built {
  HandMap map;
  sim::Lanelet2World world;
};

const Built& handWorld() {
  static Built* b = [] {
    auto* out = new Built;
    out->map = handMap();
    lanemap::testing::TempDir dir("l2world");
    const std::string path = dir.str("hand.osm");
    std::ofstream(path) << out->map.xml;
    geo::LatLonAlt origin;
    origin.lat = 49.0;
    origin.lon = 8.4;
    out->world = sim::buildLanelet2World(path, origin, sim::WorldOptions{});
    return out;
  }();
  return *b;
}

const osm::Way* wayThrough(const osm::OsmData& d, const skeleton::Skeleton& sk, double x, double y) {
  // The way whose atomic road passes closest to (x, y).
  const auto m = sk.nearestRoads(Eigen::Vector2d(x, y), 10.0);
  if (m.empty()) return nullptr;
  const auto* r = sk.road(m.front().road_id);
  for (const auto& w : d.ways) {
    if (w.id == r->way_id) return &w;
  }
  return nullptr;
}

TEST(Lanelet2World, DerivedOsmHasTheRoadsTheJunctionNodeAndLaneTags) {
  const auto& b = handWorld();
  const auto& d = b.world.roads;
  ASSERT_EQ(d.ways.size(), 4u);
  // Exactly one node is shared, by all four ways: the junction node.
  std::map<int64_t, int> uses;
  for (const auto& w : d.ways) {
    for (int64_t n : std::set<int64_t>(w.nodes.begin(), w.nodes.end())) uses[n]++;
  }
  std::vector<int64_t> shared;
  for (const auto& [n, k] : uses) {
    if (k > 1) shared.push_back(n);
  }
  ASSERT_EQ(shared.size(), 1u);
  EXPECT_EQ(uses[shared[0]], 4);
  const auto& sk = *b.world.skeleton;
  const auto* junction = sk.intersection(shared[0]);
  ASSERT_NE(junction, nullptr);
  EXPECT_FALSE(junction->dead_end);
  EXPECT_NEAR(junction->centre.x(), 70.0, 6.0);
  EXPECT_NEAR(junction->centre.y(), 0.0, 6.0);
  // Lane tags from the lanelets.
  const auto* west = wayThrough(d, sk, 30, 0);
  const auto* east = wayThrough(d, sk, 120, 0);
  const auto* north = wayThrough(d, sk, 76.75, 35);
  const auto* south = wayThrough(d, sk, 73.25, -35);
  ASSERT_TRUE(west && east && north && south);
  EXPECT_EQ(west->tag("oneway"), "yes");
  EXPECT_EQ(west->tag("lanes"), "2");
  EXPECT_EQ(east->tag("oneway"), "yes");
  EXPECT_EQ(east->tag("lanes"), "2");
  EXPECT_EQ(north->tag("oneway"), "yes");
  EXPECT_EQ(north->tag("lanes"), "1");
  EXPECT_EQ(south->tag("oneway"), "");
  EXPECT_EQ(south->tag("lanes:forward"), "1");
  EXPECT_EQ(south->tag("lanes:backward"), "1");
  // The west way runs along the middle of its two lanes (y = 0), east to the junction.
  const auto m = sk.nearestRoads(Eigen::Vector2d(30, 0), 10.0);
  ASSERT_FALSE(m.empty());
  EXPECT_LT(m.front().distance, 0.3);
  const auto* west_road = sk.road(m.front().road_id);
  EXPECT_EQ(west_road->to, junction->id);
  EXPECT_EQ(west_road->reverse_id, -1);
  EXPECT_EQ(sk.roads().size(), 5u);  // four ways, the south one in both directions
}

TEST(Lanelet2World, TruthIsTheDrawnLaneletsLabelledWithTheDerivedRoads) {
  const auto& b = handWorld();
  const auto& t = b.world.world->truth();
  const auto& sk = *b.world.skeleton;
  // 10 vehicle lanelets drawn (the crosswalk is not one), the two-way one split in two.
  EXPECT_EQ(b.world.stats.map_vehicle_lanelets, 10u);
  EXPECT_EQ(b.world.stats.two_way_split, 1u);
  EXPECT_EQ(t.lanelets.size(), 11u);
  EXPECT_EQ(b.world.stats.junction_lanelets, 4u);
  const auto* wl = t.lanelet(b.map.lanelet.at("west_left"));
  const auto* wr = t.lanelet(b.map.lanelet.at("west_right"));
  ASSERT_TRUE(wl && wr);
  EXPECT_EQ(wl->kind, map::LaneletKind::kRoad);
  EXPECT_EQ(wl->road_id, wr->road_id);
  EXPECT_EQ(wl->index_from_left, 0);
  EXPECT_EQ(wr->index_from_left, 1);
  const auto* road = sk.road(wl->road_id);
  ASSERT_NE(road, nullptr);
  EXPECT_EQ(wl->from_node, road->from);
  EXPECT_EQ(wl->to_node, road->to);
  // The junction pieces: intersection lanelets of the junction, with their turns.
  const std::map<std::string, map::TurnDirection> turns = {
      {"j_straight_left", map::TurnDirection::kStraight}, {"j_straight_right", map::TurnDirection::kStraight},
      {"j_left", map::TurnDirection::kLeft}, {"j_right", map::TurnDirection::kRight}};
  for (const auto& [name, turn] : turns) {
    const auto* j = t.lanelet(b.map.lanelet.at(name));
    ASSERT_NE(j, nullptr) << name;
    EXPECT_EQ(j->kind, map::LaneletKind::kIntersection) << name;
    EXPECT_EQ(j->intersection_id, road->to) << name;
    EXPECT_EQ(j->turn, turn) << name;
  }
  // Successors: each west lane branches in two; the right turn leads onto the south road.
  EXPECT_EQ(wl->successors.size(), 2u);
  EXPECT_EQ(wr->successors.size(), 2u);
  const auto* jr = t.lanelet(b.map.lanelet.at("j_right"));
  ASSERT_EQ(jr->successors.size(), 1u);
  EXPECT_EQ(jr->successors[0], b.map.lanelet.at("south"));
  // The south lanelet's reverse half runs north, on the east half of the drawn lanelet.
  const auto twin_it = b.world.split_twin.find(b.map.lanelet.at("south"));
  ASSERT_NE(twin_it, b.world.split_twin.end());
  const auto* s_fwd = t.lanelet(b.map.lanelet.at("south"));
  const auto* s_bwd = t.lanelet(twin_it->second);
  ASSERT_TRUE(s_fwd && s_bwd);
  EXPECT_LT(s_fwd->centre.back().y(), s_fwd->centre.front().y());
  EXPECT_GT(s_bwd->centre.back().y(), s_bwd->centre.front().y());
  EXPECT_NEAR(s_fwd->centre[s_fwd->centre.size() / 2].x(), 72.375, 0.05);
  EXPECT_NEAR(s_bwd->centre[s_bwd->centre.size() / 2].x(), 74.125, 0.05);
  EXPECT_EQ(sk.road(s_bwd->road_id)->reverse_id, s_fwd->road_id);
}

TEST(Lanelet2World, SampleGivesThePaintCurbsAndLaneletsAsDrawn) {
  const auto& b = handWorld();
  const auto& w = *b.world.world;
  const int64_t wl = b.map.lanelet.at("west_left"), wr = b.map.lanelet.at("west_right");
  // Inside each lane: asphalt carrying the lanelet id.
  EXPECT_EQ(w.sample(30, 1.75).surface, sim::Surface::kAsphalt);
  EXPECT_EQ(w.sample(30, 1.75).lanelet, wl);
  EXPECT_EQ(w.sample(30, -1.75).surface, sim::Surface::kAsphalt);
  EXPECT_EQ(w.sample(30, -1.75).lanelet, wr);
  // The shared dashed line: paint on a dash (27..30 m), asphalt between dashes (30..36 m).
  EXPECT_EQ(w.sample(28.5, 0.02).surface, sim::Surface::kDashedPaint);
  EXPECT_EQ(w.sample(33.0, 0.02).surface, sim::Surface::kAsphalt);
  // The outer bounds: curb (road_border and curbstone) just outside, sidewalk behind it.
  EXPECT_EQ(w.sample(30, 3.57).surface, sim::Surface::kCurb);
  EXPECT_EQ(w.sample(30, -3.57).surface, sim::Surface::kCurb);
  EXPECT_EQ(w.sample(30, 4.8).surface, sim::Surface::kSidewalk);
  EXPECT_EQ(w.sample(30, 8.0).surface, sim::Surface::kOffRoad);
  // The north road: a solid line on its right, the curb on its left (outside the lane: x < 75).
  EXPECT_EQ(w.sample(78.5, 30).surface, sim::Surface::kSolidPaint);
  EXPECT_EQ(w.sample(76.75, 30).surface, sim::Surface::kAsphalt);
  EXPECT_EQ(w.sample(74.93, 30).surface, sim::Surface::kCurb);
  EXPECT_EQ(w.sample(74.5, 30).surface, sim::Surface::kSidewalk);
  // The stop line and the crosswalk's stripes.
  EXPECT_EQ(w.sample(59.0, 1.0).surface, sim::Surface::kStopLinePaint);
  EXPECT_EQ(w.sample(102.0, -3.0).surface, sim::Surface::kCrosswalkPaint);
  EXPECT_EQ(w.sample(102.0, -2.5).surface, sim::Surface::kAsphalt);
  // The junction is intersection asphalt without a lane.
  EXPECT_EQ(w.sample(70.0, 1.75).surface, sim::Surface::kIntersection);
  EXPECT_EQ(w.sample(70.0, 1.75).lanelet, -1);
  // Lanes side by side are one lane apart; the two halves of the two-way lanelet face each other.
  EXPECT_EQ(w.laneOffset(wr, wl), -1);
  EXPECT_EQ(w.laneOffset(wl, wr), 1);
  EXPECT_EQ(w.laneOffset(wl, wl), 0);
  const int64_t s = b.map.lanelet.at("south");
  EXPECT_EQ(w.laneOffset(s, b.world.split_twin.at(s)), -1);
  EXPECT_FALSE(w.laneOffset(wl, s).has_value());
}

TEST(Lanelet2World, ADriveFollowsTheDrawnLanesThroughTheJunction) {
  const auto& b = handWorld();
  const auto& sk = *b.world.skeleton;
  const auto& t = b.world.world->truth();
  const auto* west = t.lanelet(b.map.lanelet.at("west_right"));
  const auto* south = t.lanelet(b.map.lanelet.at("south"));
  sim::DriveOptions o;
  o.duration_s = 30.0;
  o.route_nodes = {west->from_node, west->to_node, south->to_node};
  const auto plan = sim::planDrive(sk, t, o);
  ASSERT_EQ(plan.roads.size(), 2u);
  EXPECT_EQ(plan.roads[0], west->road_id);
  EXPECT_EQ(plan.roads[1], south->road_id);
  // West road (right lane, perhaps after a lane change), the drawn right turn, the south road.
  std::vector<int64_t> legs;
  for (const auto& l : plan.legs) legs.push_back(l.lanelet);
  EXPECT_NE(std::find(legs.begin(), legs.end(), b.map.lanelet.at("j_right")), legs.end());
  EXPECT_EQ(legs.back(), south->id);
  const sim::Trajectory traj(t, *b.world.world, plan, o);
  EXPECT_GT(traj.length(), 60.0);
  // The car ends on the south road's right half (x 71.5..73.25), driving south.
  const auto end = traj.at(traj.duration()).vehicle_to_enu;
  EXPECT_NEAR(end.translation().x(), 72.375, 0.5);
  EXPECT_LT(end.linear().col(0).y(), -0.9);
}

const sim::Lanelet2World& karlsruhe() {
  static sim::Lanelet2World* w = [] {
    sim::WorldOptions o;
    geo::LatLonAlt origin;
    origin.lat = 49.0;
    origin.lon = 8.4;
    return new sim::Lanelet2World(sim::buildLanelet2World(
        lanemap::testing::dataPath("lanelet2/karlsruhe_mapping_example.osm"), origin, o));
  }();
  return *w;
}

TEST(Lanelet2World, KarlsruheTruthIsTheMapsVehicleLanelets) {
  const auto& w = karlsruhe();
  const auto& t = w.world->truth();
  const auto file = io::readLanelet2File(lanemap::testing::dataPath("lanelet2/karlsruhe_mapping_example.osm"), 49.0, 8.4);
  std::set<int64_t> drawn;
  for (const auto& [id, subtype] : file.lanelet_subtype) {
    if (subtype == "road" || subtype == "highway" || subtype == "bus_lane" || subtype == "play_street") drawn.insert(id);
  }
  EXPECT_EQ(w.stats.map_vehicle_lanelets, drawn.size());
  EXPECT_GT(drawn.size(), 300u);
  // Every drawn vehicle lanelet is in the truth: as itself, or as a piece of a joined junction
  // lanelet; every truth lanelet is a drawn one, a reverse half or a joined one.
  std::set<int64_t> covered, twins;
  for (const auto& [id, twin] : w.split_twin) twins.insert(twin);
  for (const auto& l : t.lanelets) {
    if (drawn.count(l.id)) {
      covered.insert(l.id);
    } else if (w.joined.count(l.id)) {
      covered.insert(w.joined.at(l.id).begin(), w.joined.at(l.id).end());
    } else {
      EXPECT_TRUE(twins.count(l.id)) << "truth lanelet " << l.id << " is not from the map";
    }
  }
  std::vector<int64_t> missing, extra;
  std::set_difference(drawn.begin(), drawn.end(), covered.begin(), covered.end(), std::back_inserter(missing));
  std::set_difference(covered.begin(), covered.end(), drawn.begin(), drawn.end(), std::back_inserter(extra));
  for (int64_t id : missing) ADD_FAILURE() << "drawn lanelet " << id << " is not in the truth";
  for (int64_t id : extra) EXPECT_TRUE(twins.count(id)) << "joined piece " << id << " is not drawn nor a reverse half";
  EXPECT_EQ(w.split_twin.size(), w.stats.two_way_split);
  EXPECT_EQ(w.stats.road_lanelets + w.stats.junction_lanelets, t.lanelets.size());
  // Labels in terms of the derived skeleton.
  const auto& sk = *w.skeleton;
  size_t on_way = 0, roads = 0, sampled_own = 0;
  for (const auto& l : t.lanelets) {
    if (l.kind == map::LaneletKind::kIntersection) {
      EXPECT_NE(sk.intersection(l.intersection_id), nullptr) << "junction lanelet " << l.id;
      continue;
    }
    ++roads;
    const auto* r = sk.road(l.road_id);
    ASSERT_NE(r, nullptr) << "road lanelet " << l.id << " has road_id " << l.road_id;
    EXPECT_EQ(l.from_node, r->from);
    EXPECT_EQ(l.to_node, r->to);
    EXPECT_GE(l.index_from_left, 0);
    const Eigen::Vector2d mid = l.centre[l.centre.size() / 2].head<2>();
    on_way += sk.project(l.road_id, mid).distance < 12.0;
    sampled_own += w.world->sample(mid.x(), mid.y()).lanelet == l.id;
  }
  EXPECT_GT(roads, 250u);
  // The derived ways do not fold back on themselves (a junction node placed behind a road's end).
  for (const auto& r : sk.roads()) {
    for (size_t i = 1; i + 1 < r.polyline.size(); ++i) {
      const Eigen::Vector2d u = r.polyline[i] - r.polyline[i - 1], v = r.polyline[i + 1] - r.polyline[i];
      if (u.norm() < 1e-6 || v.norm() < 1e-6) continue;
      EXPECT_GT(u.normalized().dot(v.normalized()), std::cos(100.0 * kPi / 180.0)) << "road " << r.id << " point " << i;
    }
  }
  EXPECT_GE(on_way, roads * 95 / 100);        // the way runs along its lanelets
  EXPECT_GE(sampled_own, roads * 90 / 100);   // sample() finds the lanelet at its own centre
  // Junction connections: road -> intersection lanelet -> road, in the skeleton from the first
  // road's end intersection (the one the intersection lanelet names) to the next road's start.
  size_t joins = 0, consistent = 0;
  for (const auto& l : t.lanelets) {
    if (l.kind != map::LaneletKind::kRoad) continue;
    for (int64_t s1 : l.successors) {
      const auto* j = t.lanelet(s1);
      if (!j || j->kind != map::LaneletKind::kIntersection) continue;
      for (int64_t s2 : j->successors) {
        const auto* n = t.lanelet(s2);
        if (!n || n->road_id == l.road_id) continue;
        ++joins;
        const auto* ra = sk.road(l.road_id);
        const auto* rb = sk.road(n->road_id);
        consistent += ra && rb && ra->to == rb->from && j->intersection_id == ra->to;
      }
    }
  }
  EXPECT_GT(joins, 50u);
  EXPECT_GE(consistent, joins * 90 / 100);
  // Auto drives go over several roads, from intersection to intersection (the map's pieces are
  // small: most drives reach a dead end after 3-4 roads).
  sim::DriveOptions o;
  o.duration_s = 60;
  size_t most = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    o.seed = seed;
    const auto plan = sim::planDrive(sk, t, o);
    const size_t distinct = std::set<int64_t>(plan.roads.begin(), plan.roads.end()).size();
    std::printf("seed %lu: %zu distinct roads\n", static_cast<unsigned long>(seed), distinct);
    most = std::max(most, distinct);
    for (size_t i = 0; i + 1 < plan.roads.size(); ++i) {  // through the skeleton's intersections
      EXPECT_EQ(sk.road(plan.roads[i])->to, sk.road(plan.roads[i + 1])->from) << "seed " << seed << " step " << i;
    }
  }
  EXPECT_GE(most, 4u);
  std::printf("Karlsruhe: %zu vehicle lanelets (%zu two-way, split), %zu road + %zu junction lanelets in the truth "
              "(%zu joined from pieces), %zu junction areas (%zu on a through carriageway), %zu ways (%zu stubs in junctions), %zu atomic roads; on way %zu/%zu, sampled %zu/%zu; junction connections consistent %zu/%zu\n",
              drawn.size(), w.stats.two_way_split, w.stats.road_lanelets, w.stats.junction_lanelets,
              w.stats.joined_junction_paths, w.stats.junction_areas, w.stats.through_junctions, w.stats.roads, w.stats.stubs_in_junctions, sk.roads().size(), on_way, roads,
              sampled_own, roads, consistent, joins);
}

// The round trip: the OSM world's own truth (West Oakland), written as Lanelet2 and read back as a
// world, gives back the street network it was laid out from: its junctions where the OSM's are,
// about as many atomic roads, the road lanelets as road lanelets.
TEST(Lanelet2World, OwnTruthGivesBackTheStreetNetwork) {
  const auto osm_data = osm::readOsm(lanemap::testing::dataPath("osm/west-oakland.osm"));
  const auto sk = skeleton::Skeleton::build(osm_data);
  sim::WorldOptions o;
  o.seed = 1;
  const auto world = sim::buildWorld(sk, o);
  lanemap::testing::TempDir dir("l2world-roundtrip");
  io::writeLanelet2(world->truth(), dir.str("truth.osm"));
  const auto l2 = sim::buildLanelet2World(dir.str("truth.osm"), sk.frame().origin(), sim::WorldOptions{});
  const auto& dsk = *l2.skeleton;
  size_t junctions = 0, found = 0;
  for (const auto& in : sk.intersections()) {
    if (in.dead_end || in.incoming.size() + in.outgoing.size() < 3) continue;
    ++junctions;
    double best = 1e9;
    for (const auto& d : dsk.intersections()) {
      if (!d.dead_end) best = std::min(best, (d.centre - in.centre).norm());
    }
    found += best < 15.0;
    if (best >= 15.0) std::printf("  junction %ld at (%.0f,%.0f), %zu roads: nearest derived %.1f m\n", in.id, in.centre.x(), in.centre.y(), in.incoming.size() + in.outgoing.size(), best);
  }
  const size_t roads = sk.roads().size(), droads = dsk.roads().size();
  size_t road_lanelets = 0, kept_road = 0;
  for (const auto& l : world->truth().lanelets) {
    if (l.kind != map::LaneletKind::kRoad) continue;
    ++road_lanelets;
    const auto* d = l2.world->truth().lanelet(l.id);
    kept_road += d && d->kind == map::LaneletKind::kRoad;
  }
  std::printf("West Oakland round trip: junctions %zu/%zu found, atomic roads %zu (OSM %zu), road lanelets kept %zu/%zu\n",
              found, junctions, droads, roads, kept_road, road_lanelets);
  EXPECT_GT(junctions, 10u);
  EXPECT_GE(found, junctions * 85 / 100);  // 14 of 16
  EXPECT_LE(std::abs(static_cast<long>(droads) - static_cast<long>(roads)), static_cast<long>(roads / 10));
  EXPECT_GE(kept_road, road_lanelets * 90 / 100);
}

// lanemap-sim --lanelet2 end to end: a few seconds of a Karlsruhe drive. roads.osm read back gives
// the skeleton the truth was labelled with (what lanemap-offline builds from it), and the
// route's roads are its roads.
TEST(Lanelet2WorldTool, KarlsruheDriveWritesAConsistentScenario) {
  using lanemap::testing::binPath;
  using lanemap::testing::runCommand;
  lanemap::testing::TempDir dir("l2world-tool");
  const auto r = runCommand(binPath("lanemap-sim") + " -q --lanelet2 " +
                            lanemap::testing::dataPath("lanelet2/karlsruhe_mapping_example.osm") +
                            " --origin 49,8.4 --no-lidar --camera-hz 1 --duration 4 --seed 1 --out " + dir.str("drive"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto roads = osm::readOsm(dir.str("drive/roads.osm"));
  const auto sk = skeleton::Skeleton::build(roads);
  const auto& w = karlsruhe();
  ASSERT_EQ(sk.roads().size(), w.skeleton->roads().size());
  for (size_t i = 0; i < sk.roads().size(); ++i) {
    EXPECT_EQ(sk.roads()[i].from, w.skeleton->roads()[i].from);
    EXPECT_EQ(sk.roads()[i].to, w.skeleton->roads()[i].to);
    EXPECT_EQ(sk.roads()[i].way_id, w.skeleton->roads()[i].way_id);
  }
  const auto truth = io::readLanelet2(dir.str("drive/groundtruth.osm"), 49.0, 8.4);
  EXPECT_EQ(truth.lanelets.size(), w.world->truth().lanelets.size());
  std::ifstream in(dir.str("drive/scenario.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["lanelet2_world"]["map_vehicle_lanelets"].get<size_t>(), w.stats.map_vehicle_lanelets);
  ASSERT_FALSE(j["route"].empty());
  for (const auto& e : j["route"]) {
    const auto* road = sk.road(e["road_id"].get<int64_t>());
    ASSERT_NE(road, nullptr);
    EXPECT_EQ(road->from, e["from"].get<int64_t>());
    EXPECT_EQ(road->to, e["to"].get<int64_t>());
  }
  // Deterministic: the same map, seed and options give the same files.
  const auto again = runCommand(binPath("lanemap-sim") + " -q --lanelet2 " +
                                lanemap::testing::dataPath("lanelet2/karlsruhe_mapping_example.osm") +
                                " --origin 49,8.4 --no-lidar --camera-hz 1 --duration 4 --seed 1 --out " + dir.str("again"));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  for (const char* f : {"roads.osm", "groundtruth.osm", "trajectory.csv", "drive.lcmlog"}) {
    const auto c = runCommand("cmp " + dir.str("drive/") + f + " " + dir.str("again/") + f);
    EXPECT_EQ(c.exit_code, 0) << f << ": " << c.output;
  }
  // The car was on a truth road lanelet of the first route road at the start.
  std::ifstream csv(dir.str("drive/trajectory.csv"));
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  EXPECT_NE(first.rfind("," + std::to_string(j["route"][0]["road_id"].get<int64_t>())), std::string::npos) << first;
}

void expectLanelet2Failure(const std::string& args, const std::string& message_part) {
  lanemap::testing::TempDir dir("l2world-bad");
  const auto r = lanemap::testing::runCommand(lanemap::testing::binPath("lanemap-sim") + " -q --out " +
                                              dir.str("out") + " " + args);
  EXPECT_NE(r.exit_code, 0) << args;
  EXPECT_NE(r.output.find(message_part), std::string::npos) << "for '" << args << "' got: " << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.str("out"))) << args;
}

TEST(Lanelet2WorldTool, BadInputIsRejectedClearly) {
  const std::string map = lanemap::testing::dataPath("lanelet2/karlsruhe_mapping_example.osm");
  expectLanelet2Failure("--lanelet2 /nonexistent/map.osm", "/nonexistent/map.osm");
  expectLanelet2Failure("--lanelet2 " + map + " --origin 49", "--origin");
  expectLanelet2Failure("--lanelet2 " + map + " --origin 149,8.4", "--origin");
  expectLanelet2Failure("--osm " + lanemap::testing::dataPath("osm/west-oakland.osm") + " --origin 49,8.4", "--origin");
  expectLanelet2Failure("--osm " + lanemap::testing::dataPath("osm/west-oakland.osm") + " --lanelet2 " + map, "excludes");
  expectLanelet2Failure("", "--lanelet2");
  // A Lanelet2 map without a vehicle lanelet.
  lanemap::testing::TempDir dir("l2world-src");
  std::ofstream(dir.str("walk.osm"))
      << "<?xml version='1.0'?>\n<osm version='0.6'>\n"
         "<node id='1' lat='49.0' lon='8.4'/><node id='2' lat='49.0001' lon='8.4'/>\n"
         "<node id='3' lat='49.0' lon='8.40005'/><node id='4' lat='49.0001' lon='8.40005'/>\n"
         "<way id='10'><nd ref='1'/><nd ref='2'/><tag k='type' v='curbstone'/></way>\n"
         "<way id='11'><nd ref='3'/><nd ref='4'/><tag k='type' v='curbstone'/></way>\n"
         "<relation id='20'><member type='way' ref='10' role='left'/><member type='way' ref='11' role='right'/>"
         "<tag k='type' v='lanelet'/><tag k='subtype' v='walkway'/></relation>\n</osm>\n";
  expectLanelet2Failure("--lanelet2 " + dir.str("walk.osm"), "no vehicle lanelet");
}

}  // namespace
