// Tests of the Lanelet2 OSM writer and reader (core/io/lanelet2.h): a hand-made map survives a
// round trip, the file follows Lanelet2's rules, foreign maps (JOSM ids, reversed bounds, the
// Lanelet2 project's Karlsruhe example) read correctly, bad input throws with the path.
#include "core/io/lanelet2.h"
#include "tests/common/read_file.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>

#include <osmium/handler.hpp>
#include <osmium/io/reader.hpp>
#include <osmium/io/xml_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/relation.hpp>
#include <osmium/osm/way.hpp>
#include <osmium/visitor.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <nlohmann/json.hpp>
#include <unistd.h>

namespace lanemap::io {
namespace {

using lanemap::testing::readFile;
using map::LaneletKind;
using map::LaneMap;
using map::LineType;
using map::TurnDirection;

const std::string kKarlsruhe = std::string(LANEMAP_DATA_DIR) + "/lanelet2/karlsruhe_mapping_example.osm";

// The file's scratch folder (tests/common/temp_dir.h), made on first use and removed at exit.
const lanemap::testing::TempDir& scratch() {
  static const lanemap::testing::TempDir dir("io-lanelet2");
  return dir;
}
std::string tempPath(const std::string& name) { return scratch().str(name); }

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

map::LineString line(int64_t id, LineType type, std::vector<Eigen::Vector3d> pts) {
  map::LineString l;
  l.id = id;
  l.type = type;
  l.points = std::move(pts);
  return l;
}

// A straight line along x at height y, with a gentle grade (z) so elevations are exercised.
std::vector<Eigen::Vector3d> alongX(double x0, double x1, double y, int n) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) {
    const double x = x0 + (x1 - x0) * i / (n - 1);
    pts.emplace_back(x, y + 0.002 * x * x / 50.0, 0.01 * x);
  }
  return pts;
}

// Two eastbound lanes sharing the dashed line 2 (lanelets 100 left, 101 right), and intersection
// lanelet 102 continuing lanelet 100 straight on; lanelet 101 ends at stop line 6.
LaneMap handMadeMap() {
  LaneMap m;
  m.origin_lat = 49.0;
  m.origin_lon = 8.4;
  m.origin_alt = 112.5;
  m.lines.push_back(line(1, LineType::kSolid, alongX(0, 50, 3.5, 6)));
  m.lines.push_back(line(2, LineType::kDashed, alongX(0, 50, 0.0, 6)));
  m.lines.push_back(line(3, LineType::kCurb, alongX(0, 50, -3.5, 6)));
  m.lines.push_back(line(4, LineType::kVirtual, alongX(50, 70, 3.5, 3)));
  m.lines.push_back(line(5, LineType::kVirtual, alongX(50, 70, 0.0, 3)));
  m.lines.push_back(line(6, LineType::kStopLine, {alongX(50, 50, 0.0, 2)[0], alongX(50, 50, -3.5, 2)[0]}));
  const auto lanelet = [&](int64_t id, int64_t left, int64_t right, int index) {
    map::Lanelet ll;
    ll.id = id;
    ll.left_id = left;
    ll.right_id = right;
    ll.index_from_left = index;
    const auto& l = m.line(left)->points;
    const auto& r = m.line(right)->points;
    for (size_t i = 0; i < l.size(); ++i) ll.centre.push_back(0.5 * (l[i] + r[i]));
    return ll;
  };
  auto a = lanelet(100, 1, 2, 0);
  auto b = lanelet(101, 2, 3, 1);
  auto c = lanelet(102, 4, 5, 0);
  for (auto* ll : {&a, &b}) {
    ll->road_id = 7;
    ll->from_node = 1001;
    ll->to_node = 1002;
  }
  a.successors = {102};
  b.stop_line_id = 6;
  c.kind = LaneletKind::kIntersection;
  c.turn = TurnDirection::kStraight;
  c.intersection_id = 1002;
  m.lanelets = {a, b, c};
  return m;
}

// What libosmium sees in a written file.
struct FileStats : osmium::handler::Handler {
  size_t nodes = 0, nodes_with_ele = 0, non_positive_ids = 0, ways = 0, relations = 0;
  std::map<int64_t, std::vector<int64_t>> way_nodes;
  std::map<int64_t, std::map<std::string, std::string>> relation_tags;
  std::map<int64_t, std::map<std::string, int64_t>> relation_members;  // role -> way
  void node(const osmium::Node& n) {
    ++nodes;
    nodes_with_ele += n.tags().has_key("ele");
    non_positive_ids += n.id() <= 0;
  }
  void way(const osmium::Way& w) {
    ++ways;
    non_positive_ids += w.id() <= 0;
    for (const auto& nr : w.nodes()) way_nodes[w.id()].push_back(nr.ref());
  }
  void relation(const osmium::Relation& r) {
    ++relations;
    non_positive_ids += r.id() <= 0;
    for (const auto& t : r.tags()) relation_tags[r.id()][t.key()] = t.value();
    for (const auto& m : r.members()) relation_members[r.id()][m.role()] = m.ref();
  }
};

FileStats statsOf(const std::string& path) {
  FileStats s;
  osmium::io::Reader reader{osmium::io::File{path, "osm"}};
  osmium::apply(reader, s);
  reader.close();
  return s;
}

double maxPointDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  return worst;
}

TEST(Lanelet2, RoundTripKeepsGeometryTopologyAndAttributes) {
  const LaneMap m = handMadeMap();
  const std::string path = tempPath("roundtrip.osm");
  writeLanelet2(m, path);
  const Lanelet2File f = readLanelet2File(path, m.origin_lat, m.origin_lon);
  const LaneMap& back = f.map;

  ASSERT_EQ(back.lanelets.size(), 3u);
  ASSERT_EQ(back.lines.size(), 6u);
  EXPECT_TRUE(f.used_local_xy);
  EXPECT_TRUE(f.reversed_copy_of.empty());
  EXPECT_EQ(f.computed_centres, 0u);  // centre lines came back from the centerline ways

  const auto* a = back.lanelet(100);
  const auto* b = back.lanelet(101);
  const auto* c = back.lanelet(102);
  ASSERT_TRUE(a && b && c);
  // The shared dashed line is one way: the right bound of 100 is the left bound of 101.
  EXPECT_EQ(a->right_id, 2);
  EXPECT_EQ(b->left_id, 2);
  EXPECT_EQ(a->left_id, 1);
  EXPECT_EQ(b->right_id, 3);
  // Successors come back from shared end/start points only (Lanelet2 has no successor tags).
  EXPECT_EQ(a->successors, std::vector<int64_t>{102});
  EXPECT_TRUE(b->successors.empty());
  EXPECT_TRUE(c->successors.empty());

  EXPECT_EQ(c->kind, LaneletKind::kIntersection);
  EXPECT_EQ(c->turn, TurnDirection::kStraight);
  EXPECT_EQ(c->intersection_id, 1002);
  EXPECT_EQ(a->kind, LaneletKind::kRoad);
  EXPECT_EQ(a->road_id, 7);
  EXPECT_EQ(a->from_node, 1001);
  EXPECT_EQ(a->to_node, 1002);
  EXPECT_EQ(b->index_from_left, 1);
  ASSERT_TRUE(b->stop_line_id.has_value());
  EXPECT_EQ(*b->stop_line_id, 6);
  EXPECT_FALSE(a->stop_line_id.has_value());

  // Points within 1 mm: local_x/y and ele are written with 0.1 mm resolution. The read map's
  // origin altitude is 0, so its z are the written ones plus the writer's origin altitude.
  const Eigen::Vector3d alt(0, 0, m.origin_alt);
  for (const auto& l : m.lines) {
    const auto* r = back.line(l.id);
    ASSERT_NE(r, nullptr) << l.id;
    EXPECT_EQ(r->type, l.type) << l.id;
    std::vector<Eigen::Vector3d> shifted;
    for (const auto& p : l.points) shifted.push_back(p + alt);
    EXPECT_LT(maxPointDistance(r->points, shifted), 1e-3) << "line " << l.id;
  }
  for (const auto& ll : m.lanelets) {
    std::vector<Eigen::Vector3d> shifted;
    for (const auto& p : ll.centre) shifted.push_back(p + alt);
    EXPECT_LT(maxPointDistance(back.lanelet(ll.id)->centre, shifted), 1e-3) << "lanelet " << ll.id;
  }

  // Read with the writer's origin altitude: the very same points.
  Lanelet2ReadOptions same_origin;
  same_origin.origin_alt = m.origin_alt;
  const LaneMap exact = readLanelet2(path, m.origin_lat, m.origin_lon, same_origin);
  EXPECT_EQ(exact.origin_alt, m.origin_alt);
  for (const auto& l : m.lines) {
    EXPECT_LT(maxPointDistance(exact.line(l.id)->points, l.points), 1e-3) << "line " << l.id;
  }
}

TEST(Lanelet2, WrittenFileFollowsLanelet2Rules) {
  const LaneMap m = handMadeMap();
  const std::string path = tempPath("rules.osm");
  writeLanelet2(m, path);

  std::ifstream in(path);
  std::string head;
  std::getline(in, head);
  std::getline(in, head);
  EXPECT_EQ(head, "<osm version=\"0.6\" generator=\"lanemap\">");

  const FileStats s = statsOf(path);
  EXPECT_EQ(s.non_positive_ids, 0u);
  EXPECT_GT(s.nodes, 0u);
  EXPECT_EQ(s.nodes_with_ele, s.nodes);
  EXPECT_EQ(s.ways, 6u + 3u);  // 6 line strings + 3 centre lines
  EXPECT_EQ(s.relations, 3u);  // no regulatory element: plain Lanelet2 has none for a bare stop line
  // Successors share nodes: line 1 ends where line 4 starts, line 2 where line 5 starts.
  EXPECT_EQ(s.way_nodes.at(1).back(), s.way_nodes.at(4).front());
  EXPECT_EQ(s.way_nodes.at(2).back(), s.way_nodes.at(5).front());
  // ... and the stop line starts on the end node of the dashed line.
  EXPECT_EQ(s.way_nodes.at(6).front(), s.way_nodes.at(2).back());
  // Every point of the map is one node: 6+6+6+3+3 line points, 2 shared with lines 4/5, the stop
  // line's 2 points both coincide with line ends, centre lines 6+6+3 of which 1 shared (100->102).
  EXPECT_EQ(s.nodes, (6u + 6u + 6u + 3u + 3u - 2u) + 0u + (6u + 6u + 3u - 1u));

  const auto& tags = s.relation_tags.at(102);
  EXPECT_EQ(tags.at("type"), "lanelet");
  EXPECT_EQ(tags.at("subtype"), "road");
  EXPECT_EQ(tags.at("location"), "urban");
  EXPECT_EQ(tags.at("one_way"), "yes");
  EXPECT_EQ(tags.at("speed_limit"), "40");
  // turn_direction is Autoware's (Lanelet2's validator does not know it): only in its folder layout.
  EXPECT_EQ(tags.count("turn_direction"), 0u);
  for (const auto& [id, t] : s.relation_tags) {
    for (const auto& [k, v] : t) EXPECT_NE(k.rfind("lanemap:", 0), 0u) << id << " " << k;
  }
  EXPECT_EQ(s.relation_members.at(100).at("left"), 1);
  EXPECT_EQ(s.relation_members.at(100).at("right"), 2);
  EXPECT_EQ(s.relation_members.at(101).at("left"), 2);
  EXPECT_TRUE(std::filesystem::exists(path));
  // No temporary file left behind by the atomic write.
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(path).parent_path())) {
    EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();
  }
}

TEST(Lanelet2, RenumbersWhenIdsCollideOrAreNotPositive) {
  LaneMap m = handMadeMap();
  // Lanelet ids equal to line ids, and a negative line id: the writer must renumber.
  std::map<int64_t, int64_t> relabel{{1, -1}, {2, 2}, {3, 3}, {4, 4}, {5, 5}, {6, 6}};
  for (auto& l : m.lines) l.id = relabel[l.id];
  for (auto& ll : m.lanelets) {
    ll.left_id = relabel[ll.left_id];
    ll.right_id = relabel[ll.right_id];
  }
  m.lanelets[0].id = 1;
  m.lanelets[1].id = 2;
  m.lanelets[2].id = 3;
  m.lanelets[0].successors = {3};
  const std::string path = tempPath("renumbered.osm");
  writeLanelet2(m, path);
  const FileStats s = statsOf(path);
  EXPECT_EQ(s.non_positive_ids, 0u);
  const LaneMap back = readLanelet2(path, m.origin_lat, m.origin_lon);
  ASSERT_EQ(back.lanelets.size(), 3u);
  // Renumbered in vector order: ways 1..6, relations 7..9; topology is kept.
  EXPECT_EQ(back.lanelets[0].id, 7);
  EXPECT_EQ(back.lanelets[0].right_id, back.lanelets[1].left_id);
  EXPECT_EQ(back.lanelets[0].successors, std::vector<int64_t>{9});
}

TEST(Lanelet2, WriterRejectsInconsistentMaps) {
  const std::string path = tempPath("bad.osm");
  {
    LaneMap m = handMadeMap();
    m.lanelets[0].left_id = 42;
    try {
      writeLanelet2(m, path);
      FAIL() << "no exception";
    } catch (const Lanelet2Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("42"), std::string::npos) << e.what();
    }
  }
  {
    LaneMap m = handMadeMap();  // left and right swapped: the left bound lies on the right
    std::swap(m.lanelets[0].left_id, m.lanelets[0].right_id);
    EXPECT_EQ(orientationProblems(m).size(), 1u);
    EXPECT_THROW(writeLanelet2(m, path), Lanelet2Error);
    Lanelet2WriteOptions lenient;
    lenient.check_orientation = false;
    EXPECT_NO_THROW(writeLanelet2(m, path, lenient));
  }
  {
    // A right bound drawn against the driving direction is what Lanelet2 itself aligns (as for a
    // line shared with a lane of the opposite direction): fine.
    LaneMap m = handMadeMap();
    std::reverse(m.lines[2].points.begin(), m.lines[2].points.end());
    EXPECT_TRUE(orientationProblems(m).empty());
    // Even both bounds drawn backwards: Lanelet2 turns them back by geometry (left on the left).
    std::reverse(m.lines[0].points.begin(), m.lines[0].points.end());
    std::reverse(m.lines[1].points.begin(), m.lines[1].points.end());
    EXPECT_TRUE(orientationProblems(m).empty());
    EXPECT_NO_THROW(writeLanelet2(m, path));
  }
  EXPECT_TRUE(orientationProblems(handMadeMap()).empty());
}

// orientationProblem follows Lanelet2's geometry::align (the middle point of each bound against
// the nearest segment of the other). A U-turn of radius 6 m, 3.5 m wide: the right bound's middle
// point is the outer apex, right of the inner bound's apex segment; the left bound's middle point is
// the inner apex, left of the outer one: read as meant, whichever way its bounds are stored.
// A 10 m lanelet whose right bound's middle point lies 2 m left of the left bound (the bounds
// cross): align turns the left bound (that point is on its left), and then the right one too (the
// left's middle point (-1.75, 5) is 1.35 m right of the right bound's first segment): read backwards.
TEST(Lanelet2, OrientationFollowsLanelet2Align) {
  const auto arc = [](double r, int n) {
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i <= n; ++i) {
      const double a = -M_PI / 2 + M_PI * i / n;  // from south, counter-clockwise, to north
      pts.emplace_back(r * std::cos(a), r * std::sin(a), 0.0);
    }
    return pts;
  };
  map::Lanelet ll;
  ll.id = 1;
  ll.left_id = 2;
  ll.right_id = 3;
  ll.centre = arc(6.0, 40);  // a left U-turn: heading east at the south, west at the north
  map::LineString left{2, LineType::kVirtual, arc(6.0 - 1.75, 40)};
  map::LineString right{3, LineType::kVirtual, arc(6.0 + 1.75, 55)};
  EXPECT_EQ(orientationProblem(ll, left, right), "");
  std::reverse(left.points.begin(), left.points.end());
  EXPECT_EQ(orientationProblem(ll, left, right), "");
  std::swap(left, right);  // left bound outside: misread
  EXPECT_NE(orientationProblem(ll, left, right), "");

  map::Lanelet straight;
  straight.id = 4;
  straight.centre = {{0, 0, 0}, {0, 5, 0}, {0, 10, 0}};
  map::LineString l{5, LineType::kVirtual, {{-1.75, 0, 0}, {-1.75, 5, 0}, {-1.75, 10, 0}}};
  map::LineString r{6, LineType::kVirtual, {{1.75, 0, 0}, {-3.75, 5, 0}, {1.75, 10, 0}}};
  EXPECT_NE(orientationProblem(straight, l, r).find("against its driving direction"), std::string::npos)
      << orientationProblem(straight, l, r);
  r.points[1].x() = 1.75;
  EXPECT_EQ(orientationProblem(straight, l, r), "");
}

// A right turn around a tight corner whose inner lane ends overlap (the broad benchmark's Fremantle
// loop, 2026-12-07: the shapes below, in metres): the inner (right) bound's end lies behind its
// start along the turn. Stored in the driving direction, Lanelet2's align turns it (the left bound's
// middle point lies on its right), yet by its ends the turned bound still looks aligned, so
// orientationProblem finds nothing; boundTurnedOnLoad does. The same turn with its inner lane ends
// apart is read as stored; a line stored against the driving direction (one shared with an opposite
// lane) is turned on load, as meant there, and boundTurnedOnLoad says so (it is for a lanelet's own
// bounds, stored in its driving direction).
TEST(Lanelet2, ABoundTurnedOnLoadAtATightCornerIsFound) {
  map::Lanelet ll;
  ll.id = 1;
  ll.left_id = 2;
  ll.right_id = 3;
  ll.centre = {{165.8, 89.6, 0}, {166.3, 90.3, 0}, {167.0, 90.7, 0}, {167.7, 91.0, 0}};
  map::LineString left{2, LineType::kVirtual,
                       {{164.6, 90.7, 0}, {165.1, 91.4, 0}, {166.0, 92.0, 0}, {167.0, 92.4, 0}, {168.8, 92.2, 0}}};
  map::LineString right{3, LineType::kVirtual, {{167.1, 88.4, 0}, {166.8, 88.8, 0}, {166.6, 89.1, 0}, {166.4, 89.7, 0}}};
  EXPECT_EQ(orientationProblem(ll, left, right), "") << "orientationProblem alone misses it";
  EXPECT_TRUE(boundTurnedOnLoad(left, right));
  // The same turn with its inner lane ends apart: the inner bound runs on around the corner.
  right.points = {{167.1, 88.4, 0}, {167.6, 89.2, 0}, {168.2, 89.6, 0}, {169.0, 89.8, 0}};
  left.points.back() = {169.4, 92.0, 0};
  ll.centre.back() = {169.2, 90.9, 0};
  EXPECT_FALSE(boundTurnedOnLoad(left, right));
  EXPECT_EQ(orientationProblem(ll, left, right), "");
  std::reverse(left.points.begin(), left.points.end());
  EXPECT_TRUE(boundTurnedOnLoad(left, right)) << "a line stored against the driving direction is turned";
}

// A JOSM-style file: negative ids, no ele, the right bound drawn against the driving direction,
// a successor found by node id, and one by position only (separate nodes 4 mm apart).
TEST(Lanelet2, ReadsForeignMapWithNegativeIdsAndReversedBounds) {
  const geo::LocalFrame frame({49.0, 8.4, 0.0});
  std::string xml = "<?xml version='1.0' encoding='UTF-8'?>\n<osm version='0.6' generator='JOSM'>\n";
  const auto node = [&](int id, double x, double y) {
    const auto ll = frame.toWgs84(Eigen::Vector3d(x, y, 0));
    char buf[200];
    std::snprintf(buf, sizeof(buf), "  <node id='%d' lat='%.11f' lon='%.11f' />\n", id, ll.lat, ll.lon);
    xml += buf;
  };
  // Lanelet -100 northbound x in [0,3], y 0..20; -101 continues y 20..40 (shares nodes -3/-4);
  // -102 continues y 40..60 with its own nodes 4 mm from -101's ends.
  node(-1, 0, 0); node(-2, 3, 0); node(-3, 0, 20); node(-4, 3, 20);
  node(-5, 0, 40); node(-6, 3, 40);
  node(-7, 0.004, 40); node(-8, 3, 40.004); node(-9, 0, 60); node(-10, 3, 60);
  const auto way = [&](int id, std::vector<int> refs, const char* type, const char* subtype) {
    xml += "  <way id='" + std::to_string(id) + "'>\n";
    for (int r : refs) xml += "    <nd ref='" + std::to_string(r) + "' />\n";
    xml += std::string("    <tag k='type' v='") + type + "' />\n";
    if (subtype) xml += std::string("    <tag k='subtype' v='") + subtype + "' />\n";
    xml += "  </way>\n";
  };
  way(-20, {-1, -3}, "line_thin", "solid");  // left of -100 (x = 0 is the left when heading north)
  way(-21, {-4, -2}, "curbstone", "high");   // right of -100, drawn southwards
  way(-22, {-3, -5}, "line_thin", "dashed");
  way(-23, {-4, -6}, "virtual", nullptr);
  way(-24, {-7, -9}, "road_border", nullptr);
  way(-25, {-10, -8}, "line_thin", "solid_solid");  // drawn southwards
  const auto lanelet = [&](int id, int left, int right, const char* subtype) {
    xml += "  <relation id='" + std::to_string(id) + "'>\n";
    xml += "    <member type='way' ref='" + std::to_string(left) + "' role='left' />\n";
    xml += "    <member type='way' ref='" + std::to_string(right) + "' role='right' />\n";
    xml += "    <tag k='type' v='lanelet' />\n";
    xml += std::string("    <tag k='subtype' v='") + subtype + "' />\n";
    xml += "  </relation>\n";
  };
  lanelet(-100, -20, -21, "road");
  lanelet(-101, -22, -23, "road");
  lanelet(-102, -24, -25, "bicycle_lane");
  xml += "</osm>\n";
  const std::string path = tempPath("josm.osm");
  writeText(path, xml);

  const Lanelet2File f = readLanelet2File(path, 49.0, 8.4);
  ASSERT_EQ(f.map.lanelets.size(), 3u);
  EXPECT_FALSE(f.used_local_xy);
  EXPECT_EQ(f.computed_centres, 3u);
  EXPECT_EQ(f.lanelet_subtype.at(-102), "bicycle_lane");
  const auto* first = f.map.lanelet(-100);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->successors, std::vector<int64_t>{-101});
  EXPECT_EQ(f.map.lanelet(-101)->successors, std::vector<int64_t>{-102});  // 4 mm < 1 cm
  EXPECT_TRUE(f.map.lanelet(-102)->successors.empty());
  // The southward right bound of -100 is read northwards (only this lanelet uses that way, so the
  // way itself is reversed and keeps its id).
  const auto* right = f.map.line(first->right_id);
  ASSERT_NE(right, nullptr);
  EXPECT_EQ(right->id, -21);
  EXPECT_EQ(right->type, LineType::kCurb);
  EXPECT_NEAR(right->points.front().y(), 0.0, 0.02);  // osmium keeps 7 decimals (~1 cm)
  EXPECT_NEAR(right->points.back().y(), 20.0, 0.02);
  EXPECT_EQ(f.map.line(-25)->type, LineType::kSolidSolid);
  EXPECT_EQ(f.map.line(-24)->type, LineType::kCurb);
  // Centre line: mid-lane, northwards, 1 m spacing over 20 m -> 21 points.
  ASSERT_EQ(first->centre.size(), 21u);
  EXPECT_NEAR(first->centre.front().x(), 1.5, 0.02);
  EXPECT_NEAR(first->centre.front().y(), 0.0, 0.02);
  EXPECT_NEAR(first->centre.back().y(), 20.0, 0.02);
  EXPECT_NEAR(first->centre[10].y(), 10.0, 0.02);
  // Filtering by subtype.
  Lanelet2ReadOptions roads;
  roads.subtypes = {"road"};
  EXPECT_EQ(readLanelet2(path, 49.0, 8.4, roads).lanelets.size(), 2u);
}

// Point-in-polygon (even-odd), xy.
bool inside(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& p) {
  bool in = false;
  for (size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const auto& a = ring[i];
    const auto& b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      in = !in;
    }
  }
  return in;
}

double distanceToRing(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d a = ring[i], b = ring[(i + 1) % ring.size()];
    const double len2 = (b - a).squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * (b - a) - p).norm());
  }
  return best;
}

TEST(Lanelet2, ReadsKarlsruheExample) {
  const Lanelet2File f = readLanelet2File(kKarlsruhe, 49.0, 8.4);
  // grep -c "<tag k='type' v='lanelet' />" data/lanelet2/karlsruhe_mapping_example.osm  -> 371
  EXPECT_EQ(f.map.lanelets.size(), 363u);  // and 8 crosswalks
  // Lanelets per subtype, from the relation blocks of the file:
  //   awk "/<relation /{r=1;t=\"\";s=\"\"} r&&/k='type'/{match(\$0,/v='[^']*'/);t=substr(\$0,RSTART+3,RLENGTH-4)}
  //        r&&/k='subtype'/{match(\$0,/v='[^']*'/);s=substr(\$0,RSTART+3,RLENGTH-4)}
  //        /<\/relation>/{if(t==\"lanelet\")print s; r=0}" FILE | sort | uniq -c
  //   -> 14 bicycle_lane, 8 crosswalk, 8 highway, 2 rail, 337 road, 2 walkway
  std::map<std::string, size_t> per_subtype;
  for (const auto& [id, subtype] : f.lanelet_subtype) ++per_subtype[subtype];
  EXPECT_EQ(per_subtype["road"], 337u);
  EXPECT_EQ(per_subtype["bicycle_lane"], 14u);
  EXPECT_EQ(per_subtype["crosswalk"], 8u);
  EXPECT_EQ(per_subtype["highway"], 8u);
  // Crosswalk lanelets are map.crosswalks, every other lanelet a lane of map.lanelets.
  EXPECT_EQ(f.map.lanelets.size() + f.map.crosswalks.size(), f.lanelet_subtype.size());
  EXPECT_EQ(f.map.crosswalks.size(), 8u);
  EXPECT_FALSE(f.used_local_xy);
  // Lanelet2's validator reports no issue on this map, so every lanelet is well oriented after
  // alignment.
  EXPECT_TRUE(orientationProblems(f.map).empty());

  Lanelet2ReadOptions roads_only;
  roads_only.subtypes = {"road"};
  const LaneMap roads = readLanelet2(kKarlsruhe, 49.0, 8.4, roads_only);
  ASSERT_EQ(roads.lanelets.size(), 337u);
  size_t with_successor = 0;
  for (const auto& ll : roads.lanelets) {
    const auto* left = roads.line(ll.left_id);
    const auto* right = roads.line(ll.right_id);
    ASSERT_TRUE(left && right) << ll.id;
    ASSERT_GE(ll.centre.size(), 2u) << ll.id;
    std::vector<Eigen::Vector2d> ring;
    for (const auto& p : left->points) ring.push_back(p.head<2>());
    for (auto it = right->points.rbegin(); it != right->points.rend(); ++it) ring.push_back(it->head<2>());
    for (const auto& c : ll.centre) {
      // Inside, or within 5 cm of the outline: the first and last centre points lie exactly on
      // the lanelet's start/end edges, and 7-decimal coordinates move points by up to ~1 cm.
      EXPECT_TRUE(inside(ring, c.head<2>()) || distanceToRing(ring, c.head<2>()) < 0.05)
          << "lanelet " << ll.id << " centre point " << c.transpose();
    }
    with_successor += !ll.successors.empty();
  }
  // The map is about 3.4 km x 1 km east/north of the origin (49 N, 8.4 E).
  const auto& p = roads.lanelets.front().centre.front();
  EXPECT_GT(p.x(), 900.0);
  EXPECT_LT(p.x(), 4400.0);
  EXPECT_GT(p.y(), 150.0);
  EXPECT_LT(p.y(), 1300.0);
  // Most road lanelets continue into another one (the rest end at the map's border).
  EXPECT_GT(with_successor, roads.lanelets.size() * 3 / 4);
}

TEST(Lanelet2, KarlsruheSurvivesOurWriterAndReader) {
  Lanelet2ReadOptions roads_only;
  roads_only.subtypes = {"road"};
  const LaneMap first = readLanelet2(kKarlsruhe, 49.0, 8.4, roads_only);
  const std::string path = tempPath("karlsruhe_again.osm");
  writeLanelet2(first, path);
  const LaneMap second = readLanelet2(path, 49.0, 8.4);
  ASSERT_EQ(second.lanelets.size(), first.lanelets.size());
  for (size_t i = 0; i < first.lanelets.size(); ++i) {
    const auto& a = first.lanelets[i];
    const auto& b = second.lanelets[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.successors, b.successors) << a.id;
    EXPECT_EQ(a.left_id, b.left_id);
    EXPECT_EQ(a.right_id, b.right_id);
    EXPECT_LT(maxPointDistance(a.centre, b.centre), 1e-3) << a.id;
  }
}

TEST(Lanelet2, BadFilesThrowWithThePath) {
  const auto expectThrowNaming = [](const std::string& path, const std::string& extra) {
    try {
      readLanelet2(path, 49.0, 8.4);
      FAIL() << "no exception for " << path;
    } catch (const Lanelet2Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(extra), std::string::npos) << e.what();
    }
  };
  expectThrowNaming(tempPath("does_not_exist.osm"), "no such file");

  const std::string truncated = tempPath("truncated.osm");
  writeText(truncated, "<?xml version='1.0'?>\n<osm version='0.6'>\n  <node id='1' lat='49.0' lon='8.4'>\n  <way");
  expectThrowNaming(truncated, "");

  // A coordinate with a huge exponent (the lanelet2 fuzz harness's find: libosmium's parser
  // overflows on it) is refused before libosmium reads it, naming the attribute.
  const std::string exponent = tempPath("exponent.osm");
  writeText(exponent, "<?xml version='1.0'?>\n<osm version='0.6'>\n  <node id='1' lat = '49.00295E11383' lon='8.4'/>\n</osm>\n");
  expectThrowNaming(exponent, "exponent notation, lat=\"49.00295E11383\"");

  const std::string not_xml = tempPath("not_xml.osm");
  writeText(not_xml, "this is not an OSM file\n");
  expectThrowNaming(not_xml, "");

  const std::string missing_way = tempPath("missing_way.osm");
  writeText(missing_way,
            "<?xml version='1.0'?>\n<osm version='0.6'>\n"
            "  <relation id='5'><member type='way' ref='77' role='left'/>"
            "<member type='way' ref='78' role='right'/><tag k='type' v='lanelet'/></relation>\n</osm>\n");
  expectThrowNaming(missing_way, "77");

  // A malformed value in the sidecar: the error names the sidecar and the lanelet.
  const std::string bad_side = tempPath("bad_side.osm");
  writeLanelet2(handMadeMap(), bad_side);
  std::string side = readFile(lanelet2SidecarPath(bad_side));
  const std::string key = "\"road_id\":7";
  ASSERT_NE(side.find(key), std::string::npos);
  side.replace(side.find(key), key.size(), "\"road_id\":\"seven\"");
  writeText(lanelet2SidecarPath(bad_side), side);
  expectThrowNaming(bad_side, "bad_side.lanemap.json");
  expectThrowNaming(bad_side, "lanelet 100");

  // A file of the old format (lanemap:* tags on the lanelets) still reads; a bad tag names its value.
  const std::string bad_tag = tempPath("bad_tag.osm");
  std::string text = toLanelet2Xml(handMadeMap());
  text.replace(text.find("    <tag k=\"type\" v=\"lanelet\"/>"), 0,
               "    <tag k=\"lanemap:road_id\" v=\"seven\"/>\n");
  writeText(bad_tag, text);
  expectThrowNaming(bad_tag, "seven");
}

TEST(Lanelet2, CoordinateConventionRoundTripsExactly) {
  const geo::LocalFrame frame({49.0, 8.4, 250.0});
  const geo::LocalFrame ground({49.0, 8.4, 0.0});
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3000, -2000, 12.5),
                                  Eigen::Vector3d(-150, 800, -3)}) {
    const geo::LatLonAlt g = enuToLatLonEle(frame, p);
    EXPECT_NEAR(g.alt, 250.0 + p.z(), 1e-9);
    // Back in the same frame: the same point (tolerance: floating point, micrometres).
    EXPECT_LT((latLonEleToEnu(frame, g.lat, g.lon, g.alt) - p).norm(), 1e-6);
    // In a frame at the same lat/lon but altitude 0: the same x/y, z shifted by 250 m.
    EXPECT_LT((latLonEleToEnu(ground, g.lat, g.lon, g.alt) - (p + Eigen::Vector3d(0, 0, 250))).norm(), 1e-6);
  }
}

// Every tag key and value the writer uses is one Lanelet2's validator knows (its lists in
// lanelet2_validation/src/validators/CheckTags.cpp, v1.2.3): no unknown_tags/unknown_tag_value.
struct AllTags : osmium::handler::Handler {
  std::map<std::string, std::set<std::string>> nodes, ways, relations;  // key -> values
  static void add(const osmium::TagList& t, std::map<std::string, std::set<std::string>>& out) {
    for (const auto& tag : t) out[tag.key()].insert(tag.value());
  }
  void node(const osmium::Node& n) { add(n.tags(), nodes); }
  void way(const osmium::Way& w) { add(w.tags(), ways); }
  void relation(const osmium::Relation& r) { add(r.tags(), relations); }
};

AllTags tagsOf(const std::string& path) {
  AllTags t;
  osmium::io::Reader reader{osmium::io::File{path, "osm"}};
  osmium::apply(reader, t);
  reader.close();
  return t;
}

TEST(Lanelet2, WritesOnlyTagsLanelet2Knows) {
  const std::string path = tempPath("known_tags.osm");
  writeLanelet2(handMadeMap(), path);
  const AllTags t = tagsOf(path);
  const std::set<std::string> point_keys{"ele", "type", "subtype"};
  const std::set<std::string> line_keys{"type", "subtype", "lane_change", "width", "height", "temporary", "color"};
  const std::set<std::string> lanelet_keys{"type", "subtype", "one_way", "name", "region", "speed_limit",
                                           "location", "participant"};
  for (const auto& [k, v] : t.nodes) EXPECT_TRUE(point_keys.count(k)) << "node tag " << k;
  for (const auto& [k, v] : t.ways) EXPECT_TRUE(line_keys.count(k)) << "way tag " << k;
  for (const auto& [k, v] : t.relations) EXPECT_TRUE(lanelet_keys.count(k)) << "relation tag " << k;
  const std::set<std::string> line_types{"curbstone", "line_thin", "stop_line", "virtual"};
  for (const auto& v : t.ways.at("type")) EXPECT_TRUE(line_types.count(v)) << "line type " << v;
  EXPECT_EQ(t.ways.at("type").count("centerline"), 0u);
  EXPECT_EQ(t.relations.at("subtype"), (std::set<std::string>{"road"}));
  EXPECT_EQ(t.relations.at("type"), (std::set<std::string>{"lanelet"}));
  EXPECT_EQ(t.relations.at("location"), std::set<std::string>{"urban"});
  EXPECT_EQ(t.relations.at("one_way"), std::set<std::string>{"yes"});
  EXPECT_EQ(t.nodes.count("local_x"), 0u);
  // On request Autoware's local_x/local_y are there (and read back).
  Lanelet2WriteOptions autoware;
  autoware.local_xy_tags = true;
  autoware.write_sidecar = false;
  const std::string with_xy = tempPath("xy/known_tags.osm");
  std::filesystem::create_directories(tempPath("xy"));
  writeLanelet2(handMadeMap(), with_xy, autoware);
  EXPECT_EQ(tagsOf(with_xy).nodes.count("local_x"), 1u);
  EXPECT_FALSE(std::filesystem::exists(lanelet2SidecarPath(with_xy)));
  const Lanelet2File f = readLanelet2File(with_xy, 49.0, 8.4);
  EXPECT_TRUE(f.used_local_xy);
  EXPECT_TRUE(f.sidecar.empty());
  EXPECT_EQ(f.map.lanelet(100)->road_id, -1);  // no sidecar: lanemap's attributes are unknown
}

TEST(Lanelet2, SidecarHoldsMetadataFollowsACopyAndIsIgnoredWhenStale) {
  const LaneMap m = handMadeMap();
  const std::string dir = tempPath("side");
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/map.osm";
  writeLanelet2(m, path);
  EXPECT_EQ(lanelet2SidecarPath(path), dir + "/map.lanemap.json");
  EXPECT_EQ(lanelet2SidecarPath("/x/y.xml"), "/x/y.xml.lanemap.json");
  ASSERT_TRUE(std::filesystem::exists(dir + "/map.lanemap.json"));
  const auto side = nlohmann::json::parse(readFile(dir + "/map.lanemap.json"));
  EXPECT_EQ(side["lanelets"]["101"]["road_id"].get<int64_t>(), 7);
  EXPECT_EQ(side["lanelets"]["101"]["stop_line"].get<int64_t>(), 6);
  EXPECT_EQ(side["lanelets"]["102"]["kind"].get<std::string>(), "intersection");
  const auto origin = lanelet2WriterOrigin(path);
  ASSERT_TRUE(origin.has_value());
  EXPECT_DOUBLE_EQ(origin->lat, 49.0);
  EXPECT_DOUBLE_EQ(origin->alt, 112.5);

  // A copy under another name in the same folder finds the sidecar by the hash of its bytes.
  std::filesystem::copy_file(path, dir + "/copy.osm");
  const Lanelet2File copy = readLanelet2File(dir + "/copy.osm", 49.0, 8.4);
  EXPECT_EQ(copy.sidecar, dir + "/map.lanemap.json");
  EXPECT_EQ(copy.map.lanelet(100)->road_id, 7);
  EXPECT_EQ(copy.map.lanelet(102)->turn, TurnDirection::kStraight);
  ASSERT_TRUE(copy.map.lanelet(101)->stop_line_id.has_value());

  // Read in another frame (origin 300 m away): still mm-precise, converted from the writer's frame.
  const geo::LocalFrame writer({49.0, 8.4, 0.0});
  const geo::LatLonAlt other = writer.toWgs84(Eigen::Vector3d(300, -200, 0));
  const Lanelet2File moved = readLanelet2File(path, other.lat, other.lon);
  EXPECT_TRUE(moved.used_local_xy);
  const geo::LocalFrame reader({other.lat, other.lon, 0.0});
  for (const auto& l : m.lines) {
    for (size_t i = 0; i < l.points.size(); ++i) {
      const geo::LatLonAlt g = enuToLatLonEle(geo::LocalFrame({49.0, 8.4, 112.5}), l.points[i]);
      const Eigen::Vector3d want = latLonEleToEnu(reader, g.lat, g.lon, g.alt);
      EXPECT_LT((moved.map.line(l.id)->points[i] - want).norm(), 1e-3) << l.id << " " << i;
    }
  }

  // The map replaced by another one but not its sidecar (a crash between the two writes): the
  // sidecar no longer matches and is ignored.
  LaneMap changed = m;
  changed.lines[0].points[0].x() += 1.0;
  std::filesystem::remove(dir + "/copy.osm");
  writeText(path, toLanelet2Xml(changed));
  const Lanelet2File stale = readLanelet2File(path, 49.0, 8.4);
  EXPECT_TRUE(stale.stale_sidecar);
  EXPECT_TRUE(stale.sidecar.empty());
  EXPECT_EQ(stale.map.lanelet(100)->road_id, -1);
  EXPECT_FALSE(lanelet2WriterOrigin(path).has_value());
  // Written without a sidecar, the map leaves no old one behind.
  Lanelet2WriteOptions no_side;
  no_side.write_sidecar = false;
  writeLanelet2(m, path, no_side);
  EXPECT_FALSE(std::filesystem::exists(dir + "/map.lanemap.json"));
}

TEST(Lanelet2, AutowareTagsLaneChangeSpeedLimitTurnDirection) {
  LaneMap m = handMadeMap();
  m.lines[0].type = LineType::kSolid;
  // A left turn at the end of lanelet 101 with no turn of its own: the writer derives it.
  m.lines.push_back(line(7, LineType::kVirtual, {{50, 0, 0.5}, {55, 1, 0.5}, {58, 5, 0.5}, {59, 10, 0.5}}));
  m.lines.push_back(line(8, LineType::kVirtual, {{50, -3.5, 0.5}, {58, -2, 0.5}, {62, 4, 0.5}, {62.5, 10, 0.5}}));
  map::Lanelet turn;
  turn.id = 103;
  turn.kind = LaneletKind::kIntersection;
  turn.left_id = 7;
  turn.right_id = 8;
  for (size_t i = 0; i < 4; ++i) turn.centre.push_back(0.5 * (m.lines[6].points[i] + m.lines[7].points[i]));
  m.lanelets.push_back(turn);
  Lanelet2WriteOptions o;
  o.speed_limit_kmh_by_road = {{7, 30.0}};
  const std::string dir = tempPath("autoware");
  writeAutowareMapFolder(m, dir, o);
  const std::string path = dir + "/lanelet2_map.osm";
  ASSERT_TRUE(std::filesystem::exists(path));
  const FileStats s = statsOf(path);
  std::map<int64_t, std::map<std::string, std::string>> way_tags;
  struct WayTags : osmium::handler::Handler {
    std::map<int64_t, std::map<std::string, std::string>>* out;
    void way(const osmium::Way& w) {
      for (const auto& t : w.tags()) (*out)[w.id()][t.key()] = t.value();
    }
  } h;
  h.out = &way_tags;
  osmium::io::Reader reader{osmium::io::File{path, "osm"}};
  osmium::apply(reader, h);
  reader.close();
  EXPECT_EQ(way_tags.at(2).at("lane_change"), "yes");   // dashed, between lanelets 100 and 101
  EXPECT_EQ(way_tags.at(1).count("lane_change"), 0u);   // a road edge: one lanelet only
  EXPECT_EQ(way_tags.at(3).count("lane_change"), 0u);
  EXPECT_EQ(s.relation_tags.at(100).at("speed_limit"), "30");
  EXPECT_EQ(s.relation_tags.at(102).at("speed_limit"), "30");  // follows lanelet 100 of road 7
  EXPECT_EQ(s.relation_tags.at(103).at("speed_limit"), "40");  // no road of known speed: default
  EXPECT_EQ(s.relation_tags.at(102).at("turn_direction"), "straight");
  EXPECT_EQ(s.relation_tags.at(103).at("turn_direction"), "left");
  EXPECT_EQ(s.relation_tags.at(100).count("turn_direction"), 0u);
  // Lanelet 101 ends at stop line 6: it references Autoware's road_marking that refers to it.
  const int64_t reg = s.relation_members.at(101).at("regulatory_element");
  EXPECT_EQ(s.relation_tags.at(reg).at("type"), "regulatory_element");
  EXPECT_EQ(s.relation_tags.at(reg).at("subtype"), "road_marking");
  EXPECT_EQ(s.relation_members.at(reg).at("refers"), 6);
  EXPECT_EQ(s.relation_members.at(100).count("regulatory_element"), 0u);
  // The model's turn comes back, not the derived one.
  const LaneMap back = readLanelet2(path, 49.0, 8.4);
  EXPECT_EQ(back.lanelet(103)->turn, TurnDirection::kNone);
  EXPECT_EQ(back.lanelet(102)->turn, TurnDirection::kStraight);

  // A solid line between the two lanes forbids the change.
  m.lines[1].type = LineType::kSolid;
  writeLanelet2(m, dir + "/solid.osm");
  way_tags.clear();
  osmium::io::Reader r2{osmium::io::File{dir + "/solid.osm", "osm"}};
  osmium::apply(r2, h);
  r2.close();
  EXPECT_EQ(way_tags.at(2).at("lane_change"), "no");

  const std::string info = readFile(dir + "/map_projector_info.yaml");
  EXPECT_NE(info.find("projector_type: LocalCartesian\n"), std::string::npos) << info;
  EXPECT_NE(info.find("vertical_datum: WGS84\n"), std::string::npos) << info;
  EXPECT_NE(info.find("  latitude: 49.0000000000\n"), std::string::npos) << info;
  EXPECT_NE(info.find("  longitude: 8.4000000000\n"), std::string::npos) << info;
  EXPECT_NE(info.find("  altitude: 112.5000\n"), std::string::npos) << info;
}

// handMadeMap with one regulatory element of `kind` at stop line 6 (end of lanelet 101; give way:
// lanelet 100 has priority) and crosswalk 300 across both lanes (x = 20..23, walking north).
LaneMap withRules(map::RegulatoryKind kind, bool priority = true) {
  LaneMap m = handMadeMap();
  map::RegulatoryElement r;
  r.id = 200;
  r.kind = kind;
  r.stop_line_id = 6;
  r.lanelets = {101};
  if (kind == map::RegulatoryKind::kGiveWay && priority) r.priority = {100};
  if (kind == map::RegulatoryKind::kTrafficLight) {
    r.light = {{50.0, -1.95, 5.5}, {50.0, -1.55, 5.5}};
    r.light_height_m = 1.2;
    r.light_estimated = true;
  }
  r.osm_node = 4242;
  m.regulatory_elements.push_back(r);
  map::Crosswalk c;
  c.id = 300;
  c.left = {{20.0, -3.5, 0.2}, {20.0, 3.5, 0.2}};  // walking north: x = 20 is on the left
  c.right = {{23.0, -3.5, 0.23}, {23.0, 3.5, 0.23}};
  c.crossing = {100, 101};
  c.road_id = 7;
  m.crosswalks.push_back(c);
  return m;
}

TEST(Lanelet2, RegulatoryElementsAndCrosswalksRoundTrip) {
  using map::RegulatoryKind;
  struct Case {
    RegulatoryKind kind;
    bool priority;
    const char* subtype;
    const char* sign_type;  // nullptr: none
  };
  for (const Case& k : {Case{RegulatoryKind::kStopSign, false, "traffic_sign", "stop_sign"},
                        Case{RegulatoryKind::kGiveWay, true, "right_of_way", nullptr},
                        Case{RegulatoryKind::kGiveWay, false, "traffic_sign", "give_way"},
                        Case{RegulatoryKind::kTrafficLight, false, "traffic_light", nullptr}}) {
    SCOPED_TRACE(std::string(k.subtype) + (k.priority ? " with priority" : ""));
    const LaneMap m = withRules(k.kind, k.priority);
    const std::string path = tempPath(std::string("rules_") + k.subtype + (k.priority ? "_p" : "") + ".osm");
    writeLanelet2(m, path);
    const FileStats s = statsOf(path);
    ASSERT_TRUE(s.relation_tags.count(200));
    const auto& tags = s.relation_tags.at(200);
    EXPECT_EQ(tags.at("type"), "regulatory_element");
    EXPECT_EQ(tags.at("subtype"), k.subtype);
    if (k.sign_type) EXPECT_EQ(tags.at("sign_type"), k.sign_type);
    else EXPECT_EQ(tags.count("sign_type"), 0u);
    EXPECT_EQ(s.relation_members.at(200).at("ref_line"), 6);
    EXPECT_EQ(s.relation_members.at(101).at("regulatory_element"), 200);
    if (k.priority) {
      EXPECT_EQ(s.relation_members.at(200).at("right_of_way"), 100);
      EXPECT_EQ(s.relation_members.at(200).at("yield"), 101);
      EXPECT_EQ(s.relation_members.at(100).at("regulatory_element"), 200);
    } else {
      EXPECT_EQ(s.relation_members.at(100).count("regulatory_element"), 0u);
    }
    if (k.kind == RegulatoryKind::kTrafficLight) {
      const int64_t light = s.relation_members.at(200).at("refers");
      EXPECT_EQ(s.way_nodes.at(light).size(), 2u);
    }
    // The crosswalk lanelet, with the tags Lanelet2 knows; its edges are ways of their own.
    const auto& cw = s.relation_tags.at(300);
    EXPECT_EQ(cw.at("type"), "lanelet");
    EXPECT_EQ(cw.at("subtype"), "crosswalk");
    EXPECT_EQ(cw.at("one_way"), "no");
    EXPECT_EQ(cw.at("location"), "urban");
    EXPECT_EQ(s.relation_members.at(100).count("crosswalk"), 0u);

    // Read back (with the sidecar): everything as written.
    Lanelet2ReadOptions ro;
    ro.origin_alt = m.origin_alt;
    const Lanelet2File f = readLanelet2File(path, 49.0, 8.4, ro);
    ASSERT_EQ(f.map.lanelets.size(), 3u);  // the crosswalk is not a lane
    ASSERT_EQ(f.map.regulatory_elements.size(), 1u);
    const auto& r = f.map.regulatory_elements[0];
    EXPECT_EQ(r.id, 200);
    EXPECT_EQ(r.kind, k.kind);
    EXPECT_EQ(r.stop_line_id, 6);
    EXPECT_EQ(r.lanelets, (std::vector<int64_t>{101}));
    EXPECT_EQ(r.priority, k.priority ? std::vector<int64_t>{100} : std::vector<int64_t>{});
    EXPECT_EQ(r.osm_node, 4242);
    ASSERT_TRUE(f.map.line(6));
    EXPECT_EQ(f.map.line(6)->type, LineType::kStopLine);
    EXPECT_EQ(f.map.lanelet(101)->stop_line_id.value_or(-1), 6);
    EXPECT_FALSE(f.map.lanelet(100)->stop_line_id.has_value());
    if (k.kind == RegulatoryKind::kTrafficLight) {
      EXPECT_TRUE(r.light_estimated);
      EXPECT_NEAR(r.light_height_m, 1.2, 1e-9);
      EXPECT_LT(maxPointDistance(r.light, m.regulatory_elements[0].light), 1e-3);
    }
    ASSERT_EQ(f.map.crosswalks.size(), 1u);
    const auto& c = f.map.crosswalks[0];
    EXPECT_EQ(c.id, 300);
    EXPECT_EQ(c.crossing, (std::vector<int64_t>{100, 101}));
    EXPECT_EQ(c.road_id, 7);
    // The left edge starts 1.6 cm from a node of curb 3 (x = 20): one node (points < 5 cm merge).
    EXPECT_LT(maxPointDistance(c.left, m.crosswalks[0].left), 0.02);
    EXPECT_LT(maxPointDistance(c.right, m.crosswalks[0].right), 1e-3);
    // No line of the map came from the crosswalk's edges or the light.
    EXPECT_EQ(f.map.lines.size(), m.lines.size());

    // Without the sidecar (a foreign reader's view): the rule from the OSM tags alone.
    std::filesystem::remove(lanelet2SidecarPath(path));
    const LaneMap bare = readLanelet2(path, 49.0, 8.4, ro);
    ASSERT_EQ(bare.regulatory_elements.size(), 1u);
    EXPECT_EQ(bare.regulatory_elements[0].kind, k.kind);
    EXPECT_EQ(bare.regulatory_elements[0].lanelets, (std::vector<int64_t>{101}));
    EXPECT_FALSE(bare.regulatory_elements[0].light_estimated);  // nothing says so
    ASSERT_EQ(bare.crosswalks.size(), 1u);
    EXPECT_TRUE(bare.crosswalks[0].crossing.empty());  // plain Lanelet2 links them by geometry
    EXPECT_LT(maxPointDistance(bare.crosswalks[0].left, m.crosswalks[0].left), 0.02);
  }
}

TEST(Lanelet2, AutowareLayoutLinksCrosswalksAndRulesToTheirLanelets) {
  const LaneMap m = withRules(map::RegulatoryKind::kStopSign);
  const std::string dir = tempPath("autoware_rules");
  writeAutowareMapFolder(m, dir);
  const std::string path = dir + "/lanelet2_map.osm";
  const FileStats s = statsOf(path);
  // Stop line 6 has a stop sign: no road_marking of its own.
  for (const auto& [id, tags] : s.relation_tags) EXPECT_NE(tags.count("subtype") ? tags.at("subtype") : "", "road_marking") << id;
  // Autoware's crosswalk element: refers = the crosswalk lanelet, crosswalk_polygon = a closed way.
  int64_t element = 0;
  for (const auto& [id, tags] : s.relation_tags) {
    if (tags.count("type") && tags.at("type") == "regulatory_element" && tags.at("subtype") == "crosswalk") element = id;
  }
  ASSERT_NE(element, 0);
  EXPECT_EQ(s.relation_members.at(element).at("refers"), 300);
  const auto& ring = s.way_nodes.at(s.relation_members.at(element).at("crosswalk_polygon"));
  EXPECT_EQ(ring.size(), 5u);
  EXPECT_EQ(ring.front(), ring.back());
  // Lanelet 100 references the crosswalk element; 101 both it and the stop sign (the map's
  // relation_members keeps one per role: the last, the crosswalk's).
  EXPECT_EQ(s.relation_members.at(100).at("regulatory_element"), element);
  std::filesystem::remove(lanelet2SidecarPath(path));
  const LaneMap back = readLanelet2(path, 49.0, 8.4);
  ASSERT_EQ(back.crosswalks.size(), 1u);
  EXPECT_EQ(back.crosswalks[0].crossing, (std::vector<int64_t>{100, 101}));  // from the element
  ASSERT_EQ(back.regulatory_elements.size(), 1u);
  EXPECT_EQ(back.regulatory_elements[0].kind, map::RegulatoryKind::kStopSign);
}

TEST(Lanelet2, MalformedRulesInTheSidecarThrowWithItsPath) {
  const std::string path = tempPath("rules_bad_sidecar.osm");
  writeLanelet2(withRules(map::RegulatoryKind::kTrafficLight), path);
  const std::string side = lanelet2SidecarPath(path);
  std::string text = readFile(side);
  const auto at = text.find("\"osm_node\":4242");
  ASSERT_NE(at, std::string::npos) << text.substr(0, 400);
  text.replace(at, std::string("\"osm_node\":4242").size(), "\"osm_node\":\"x\"");
  writeText(side, text);
  try {
    readLanelet2(path, 49.0, 8.4);
    FAIL() << "no throw";
  } catch (const Lanelet2Error& e) {
    EXPECT_NE(std::string(e.what()).find(side), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("regulatory element 200"), std::string::npos) << e.what();
  }
}

TEST(Lanelet2, WriterRejectsBrokenRules) {
  LaneMap m = withRules(map::RegulatoryKind::kTrafficLight);
  m.regulatory_elements[0].stop_line_id = 99;
  EXPECT_THROW(toLanelet2Xml(m), Lanelet2Error);
  m = withRules(map::RegulatoryKind::kTrafficLight);
  m.regulatory_elements[0].light.clear();
  EXPECT_THROW(toLanelet2Xml(m), Lanelet2Error);
  m = withRules(map::RegulatoryKind::kStopSign);
  m.regulatory_elements[0].lanelets = {555};
  EXPECT_THROW(toLanelet2Xml(m), Lanelet2Error);
  m = withRules(map::RegulatoryKind::kStopSign);
  m.crosswalks[0].left.pop_back();
  EXPECT_THROW(toLanelet2Xml(m), Lanelet2Error);
  m = withRules(map::RegulatoryKind::kStopSign);
  m.crosswalks[0].id = 200;  // the regulatory element's id
  EXPECT_THROW(toLanelet2Xml(m), Lanelet2Error);
}

TEST(Lanelet2, PointsCloserThan5cmAreOneNode) {
  LaneMap m = handMadeMap();
  // Line 1 gets a point 2 cm after its first; line 4 starts 3 cm off line 1's end.
  m.lines[0].points.insert(m.lines[0].points.begin() + 1, m.lines[0].points[0] + Eigen::Vector3d(0.02, 0, 0));
  m.lines[3].points[0] += Eigen::Vector3d(0.0, 0.03, 0.0);
  // A line shorter than 5 cm keeps its 2 nodes.
  m.lines.push_back(line(9, LineType::kSolid, {{100, 100, 0}, {100.03, 100, 0}}));
  // A line whose first point lies 5.005 cm from line 9's last: one node (merged under 5.01 cm:
  // lanelet2_validate measures in UTM, scale 0.9996, where 5.000-5.002 cm here are under 5 cm).
  m.lines.push_back(line(19, LineType::kSolid, {{100.08005, 100, 0}, {110, 100, 0}}));
  const std::string path = tempPath("close.osm");
  writeLanelet2(m, path);
  const FileStats s = statsOf(path);
  EXPECT_EQ(s.way_nodes.at(1).size(), 6u);
  EXPECT_EQ(s.way_nodes.at(1).back(), s.way_nodes.at(4).front());
  EXPECT_EQ(s.way_nodes.at(9).size(), 2u);
  EXPECT_EQ(s.way_nodes.at(19).front(), s.way_nodes.at(9).back());
  // No two nodes of the file (but line 9's) closer than 5.01 cm.
  const LaneMap back = readLanelet2(path, 49.0, 8.4);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& l : back.lines) {
    if (l.id != 9) pts.insert(pts.end(), l.points.begin(), l.points.end());
  }
  for (size_t i = 0; i < pts.size(); ++i) {
    for (size_t j = 0; j < pts.size(); ++j) {
      const double d = (pts[i] - pts[j]).norm();
      EXPECT_TRUE(d == 0.0 || d >= 0.0501) << i << " " << j << " " << d;
    }
  }
}

// The node table grows far past its first size (thousands of cells, negative coordinates too) and
// still finds every point within 5.01 cm of a node, in any of the 3x3 cells around it.
TEST(Lanelet2, ManyPointsStillMergeAfterTheNodeTableGrows) {
  LaneMap m = handMadeMap();
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d p(-150.0 + 0.1 * i, -40.0 + 0.013 * i, 0.0);  // 10 cm apart: all distinct
    a.push_back(p);
    // 3 cm off a's point, the offset's direction turning: the neighbour cell differs from point to point.
    const double angle = 0.37 * i;
    b.push_back(p + 0.03 * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0));
  }
  m.lines.push_back(line(31, LineType::kSolid, a));
  m.lines.push_back(line(32, LineType::kSolid, b));
  const std::string path = tempPath("many.osm");
  writeLanelet2(m, path);
  const FileStats s = statsOf(path);
  ASSERT_EQ(s.way_nodes.at(31).size(), 3000u);
  EXPECT_EQ(std::set<int64_t>(s.way_nodes.at(31).begin(), s.way_nodes.at(31).end()).size(), 3000u);
  EXPECT_EQ(s.way_nodes.at(32), s.way_nodes.at(31));  // every point of b is a's node
  // The read-back points are a's, to the written precision.
  Lanelet2ReadOptions same_origin;
  same_origin.origin_alt = m.origin_alt;
  const LaneMap back = readLanelet2(path, m.origin_lat, m.origin_lon, same_origin);
  ASSERT_NE(back.line(32), nullptr);
  EXPECT_LT(maxPointDistance(back.line(32)->points, a), 1e-3);
}

TEST(Lanelet2, ParsesOsmMaxspeed) {
  EXPECT_DOUBLE_EQ(*parseMaxspeedKmh("50"), 50.0);
  EXPECT_DOUBLE_EQ(*parseMaxspeedKmh("50 km/h"), 50.0);
  EXPECT_NEAR(*parseMaxspeedKmh("25 mph"), 40.2336, 1e-4);
  EXPECT_NEAR(*parseMaxspeedKmh("10 knots"), 18.52, 1e-9);
  EXPECT_FALSE(parseMaxspeedKmh("none").has_value());
  EXPECT_FALSE(parseMaxspeedKmh("DE:urban").has_value());
  EXPECT_FALSE(parseMaxspeedKmh("0").has_value());
  EXPECT_FALSE(parseMaxspeedKmh("").has_value());
}

}  // namespace
}  // namespace lanemap::io
