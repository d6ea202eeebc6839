// lanemap-check's rules (core/io/map_check.h) on small hand-made maps: a map lanemap writes passes
// every rule; each variant below breaks one rule once and must fail exactly that rule, naming the
// offending id. The tool itself: exit status and output.
#include "core/io/lanelet2.h"
#include "core/io/map_check.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

namespace lanemap::io {
namespace {

using lanemap::testing::readFile;
using map::LaneletKind;
using map::LaneMap;
using map::LineType;
namespace lt = lanemap::testing;

map::LineString line(int64_t id, LineType type, std::vector<Eigen::Vector3d> pts) {
  map::LineString l;
  l.id = id;
  l.type = type;
  l.points = std::move(pts);
  return l;
}

std::vector<Eigen::Vector3d> alongX(double x0, double x1, double y, int n) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) pts.emplace_back(x0 + (x1 - x0) * i / (n - 1), y, 0.0);
  return pts;
}

map::Lanelet lanelet(const LaneMap& m, int64_t id, int64_t left, int64_t right) {
  map::Lanelet ll;
  ll.id = id;
  ll.left_id = left;
  ll.right_id = right;
  const auto& l = m.line(left)->points;
  const auto& r = m.line(right)->points;
  for (size_t i = 0; i < l.size(); ++i) ll.centre.push_back(0.5 * (l[i] + r[i]));
  return ll;
}

// An intersection lanelet of intersection 9 between lines left and right.
map::Lanelet intersectionLanelet(const LaneMap& m, int64_t id, int64_t left, int64_t right) {
  map::Lanelet ll = lanelet(m, id, left, right);
  ll.kind = LaneletKind::kIntersection;
  ll.intersection_id = 9;
  return ll;
}

// Two eastbound lanes sharing dashed line 2 (lanelets 100, 101), lanelet 101 ending at stop line 6,
// and intersection lanelet 102 of intersection 9 after lanelet 100. Node ids start at 106 (after
// the 6 lines, 3 lanelets and 3 centre lines; 107 in Autoware's layout, after the road_marking).
LaneMap goodMap() {
  LaneMap m;
  m.origin_lat = 37.8;
  m.origin_lon = -122.3;
  m.lines.push_back(line(1, LineType::kSolid, alongX(0, 50, 3.5, 6)));
  m.lines.push_back(line(2, LineType::kDashed, alongX(0, 50, 0.0, 6)));
  m.lines.push_back(line(3, LineType::kCurb, alongX(0, 50, -3.5, 6)));
  m.lines.push_back(line(4, LineType::kVirtual, alongX(50, 70, 3.5, 3)));
  m.lines.push_back(line(5, LineType::kVirtual, alongX(50, 70, 0.0, 3)));
  m.lines.push_back(line(6, LineType::kStopLine, {{50, 0, 0}, {50, -3.5, 0}}));
  m.lanelets = {lanelet(m, 100, 1, 2), lanelet(m, 101, 2, 3), intersectionLanelet(m, 102, 4, 5)};
  m.lanelets[0].successors = {102};
  m.lanelets[1].stop_line_id = 6;
  m.lanelets[2].turn = map::TurnDirection::kStraight;
  return m;
}

void replaceOnce(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// The rules that failed, with their offenders.
std::map<std::string, std::vector<int64_t>> failures(const std::string& path, bool autoware = false) {
  MapCheckOptions o;
  o.autoware = autoware;
  std::map<std::string, std::vector<int64_t>> out;
  for (const auto& r : checkLanelet2Map(path, o)) {
    if (!r.passed) out[r.name] = r.offenders;
  }
  return out;
}

using Failures = std::map<std::string, std::vector<int64_t>>;

TEST(MapCheck, MapsLanemapWritesPassEveryRule) {
  lt::TempDir dir("check-good");
  writeLanelet2(goodMap(), dir.str("map.osm"));
  EXPECT_EQ(failures(dir.str("map.osm")), Failures{});
  size_t applicable = 0;
  for (const auto& r : checkLanelet2Map(dir.str("map.osm"))) applicable += r.applicable;
  EXPECT_EQ(applicable, 7u);  // every rule had something to check
  writeAutowareMapFolder(goodMap(), dir.str("aw"));
  EXPECT_EQ(failures(dir.str("aw/lanelet2_map.osm"), true), Failures{});
}

TEST(MapCheck, EachBrokenRuleFailsAlone) {
  lt::TempDir dir("check-bad");
  const std::string good = toLanelet2Xml(goodMap());
  const auto write = [&](const std::string& name, const std::string& text) {
    const std::string p = dir.str(name);
    std::ofstream(p) << text;
    return p;
  };
  {  // a node without ele: the first node
    std::string t = good;
    const auto node = t.find("<node id=\"106\"");
    ASSERT_NE(node, std::string::npos);
    const auto ele = t.find("    <tag k=\"ele\"", node);
    t.erase(ele, t.find('\n', ele) + 1 - ele);
    EXPECT_EQ(failures(write("ele.osm", t)), (Failures{{"ele", {106}}}));
  }
  {  // a lanelet without speed_limit
    std::string t = good;
    replaceOnce(t, "<tag k=\"speed_limit\" v=\"40\"/>", "<tag k=\"name\" v=\"x\"/>");
    EXPECT_EQ(failures(write("speed.osm", t)), (Failures{{"lanelet_tags", {100}}}));
  }
  {  // lane_change=no on the dashed line between lanelets 100 and 101
    std::string t = good;
    replaceOnce(t, "<tag k=\"lane_change\" v=\"yes\"/>", "<tag k=\"lane_change\" v=\"no\"/>");
    EXPECT_EQ(failures(write("lc.osm", t)), (Failures{{"lane_change", {2}}}));
  }
  {  // lanelet 101 on its own copy (line 7) of the dashed line
    LaneMap m = goodMap();
    m.lines.push_back(line(7, LineType::kDashed, alongX(0, 50, 0.0, 11)));
    m.lanelets[1].left_id = 7;
    writeLanelet2(m, dir.str("shared.osm"));
    const auto f = failures(dir.str("shared.osm"));
    // Line 2 is now between no two lanelets, so lane_change does not apply to it.
    EXPECT_EQ(f, (Failures{{"shared_borders", {2, 7}}})) << f.size();
  }
  {  // lanelet 103, 1.5 m long, merging into lanelet 102's end (both end at the same two nodes) on
     // its own copies of 102's bounds: a merge, not two neighbours, so it passes ...
    LaneMap m = goodMap();
    m.lines.push_back(line(10, LineType::kVirtual, alongX(68.5, 70, 3.5, 2)));
    m.lines.push_back(line(11, LineType::kVirtual, alongX(68.5, 70, 0.0, 2)));
    m.lanelets.push_back(intersectionLanelet(m, 103, 10, 11));
    writeLanelet2(m, dir.str("merge.osm"));
    EXPECT_EQ(failures(dir.str("merge.osm")), Failures{});
    // ... but ending 10 cm short of 102's end (no shared node) it lies on 102 as a neighbour would.
    m.lines[6].points.back().x() = 69.9;
    m.lines[7].points.back().x() = 69.9;
    m.lanelets.back() = intersectionLanelet(m, 103, 10, 11);
    writeLanelet2(m, dir.str("merge-short.osm"));
    EXPECT_EQ(failures(dir.str("merge-short.osm")), (Failures{{"shared_borders", {4, 5, 10, 11}}}));
  }
  {  // lanelet 101 narrowing to a point: its bounds share their last node
    LaneMap m = goodMap();
    m.lines[2].points.back() = m.lines[1].points.back();
    m.lines[5].points = {{50, 0, 0}, {50, -0.1, 0}};
    m.lanelets[1] = lanelet(m, 101, 2, 3);
    m.lanelets[1].stop_line_id = 6;
    writeLanelet2(m, dir.str("apart.osm"));
    EXPECT_EQ(failures(dir.str("apart.osm")), (Failures{{"bounds_apart", {101}}}));
  }
  {  // a centre line leaving its lanelet
    LaneMap m = goodMap();
    m.lanelets[0].centre[2].y() += 3.0;
    writeLanelet2(m, dir.str("centre.osm"));
    EXPECT_EQ(failures(dir.str("centre.osm")), (Failures{{"centerline_inside", {100}}}));
  }
  {  // Autoware's layout: a stop line no regulatory element refers to
    writeAutowareMapFolder(goodMap(), dir.str("stop"));
    std::string t = readFile(dir.str("stop/lanelet2_map.osm"));
    replaceOnce(t, "role=\"refers\"", "role=\"other\"");
    std::ofstream(dir.str("stop/edited.osm")) << t;
    EXPECT_EQ(failures(dir.str("stop/edited.osm"), true), (Failures{{"stop_line_refs", {6}}}));
  }
  {  // two intersection lanelets of intersection 9 one after the other
    LaneMap m = goodMap();
    m.lines.push_back(line(8, LineType::kVirtual, alongX(70, 80, 3.5, 2)));
    m.lines.push_back(line(9, LineType::kVirtual, alongX(70, 80, 0.0, 2)));
    m.lanelets.push_back(intersectionLanelet(m, 103, 8, 9));
    m.lanelets[2].successors = {103};
    writeLanelet2(m, dir.str("split.osm"));
    EXPECT_EQ(failures(dir.str("split.osm")), (Failures{{"one_lanelet_per_intersection_path", {102}}}));
  }
  {  // Autoware's layout: a plain map (no turn_direction) fails it on intersection lanelet 102
    // (the sidecar says which lanelets are intersection lanelets) ...
    std::filesystem::create_directories(dir.str("aw"));
    writeLanelet2(goodMap(), dir.str("aw/map.osm"));
    EXPECT_EQ(failures(dir.str("aw/map.osm"), true), (Failures{{"stop_line_refs", {6}}, {"turn_direction", {102}}}));
    // ... and a map with no map_projector_info.yaml beside it fails projector_info.
    Lanelet2WriteOptions o;
    o.write_projector_info = false;
    o.turn_direction_tags = true;
    o.stop_line_road_markings = true;
    std::filesystem::create_directories(dir.str("aw2"));
    writeLanelet2(goodMap(), dir.str("aw2/map.osm"), o);
    EXPECT_EQ(failures(dir.str("aw2/map.osm"), true), (Failures{{"projector_info", {}}}));
  }
}

// goodMap with a traffic light at stop line 6 (element 200, lanelet 101) and crosswalk 300 over
// lanelets 100 and 101.
LaneMap ruledMap() {
  LaneMap m = goodMap();
  map::RegulatoryElement r;
  r.id = 200;
  r.kind = map::RegulatoryKind::kTrafficLight;
  r.stop_line_id = 6;
  r.lanelets = {101};
  r.light = {{50, -1.95, 5}, {50, -1.55, 5}};
  m.regulatory_elements.push_back(r);
  map::Crosswalk c;
  c.id = 300;
  c.left = {{20, -3.5, 0}, {20, 3.5, 0}};
  c.right = {{23, -3.5, 0}, {23, 3.5, 0}};
  c.crossing = {100, 101};
  m.crosswalks.push_back(c);
  return m;
}

TEST(MapCheck, RegulatoryElementsAndCrosswalks) {
  lt::TempDir dir("check-rules");
  writeLanelet2(ruledMap(), dir.str("map.osm"));
  EXPECT_EQ(failures(dir.str("map.osm")), Failures{});
  bool checked = false;
  for (const auto& r : checkLanelet2Map(dir.str("map.osm"))) checked |= r.name == "regulatory_elements" && r.applicable;
  EXPECT_TRUE(checked);
  writeAutowareMapFolder(ruledMap(), dir.str("aw"));
  EXPECT_EQ(failures(dir.str("aw/lanelet2_map.osm"), true), Failures{});

  const std::string good = toLanelet2Xml(ruledMap());
  const auto write = [&](const std::string& name, const std::string& text) {
    const std::string p = dir.str(name);
    std::ofstream(p) << text;
    return p;
  };
  {  // a crosswalk whose edge runs on lanelet 101's curb for 10 m (a crossing of a side street
     // beside the lane): crosswalks lie across lanes by design and are no lane's neighbour
    LaneMap m = ruledMap();
    map::Crosswalk c;
    c.id = 301;
    c.left = alongX(30, 40, -3.5, 3);
    c.right = alongX(30, 40, -6.5, 3);
    m.crosswalks.push_back(c);
    writeLanelet2(m, dir.str("side_crossing.osm"));
    EXPECT_EQ(failures(dir.str("side_crossing.osm")), Failures{});
  }
  {  // the light's ref_line is not a stop line (curb 3 instead of stop line 6)
    std::string t = good;
    replaceOnce(t, "ref=\"6\" role=\"ref_line\"", "ref=\"3\" role=\"ref_line\"");
    EXPECT_EQ(failures(write("ref.osm", t)), (Failures{{"regulatory_elements", {200}}}));
  }
  {  // no lanelet references the element
    std::string t = good;
    replaceOnce(t, "ref=\"200\" role=\"regulatory_element\"", "ref=\"200\" role=\"other\"");
    EXPECT_EQ(failures(write("unused.osm", t)), (Failures{{"regulatory_elements", {200}}}));
  }
  {  // a traffic light without its light
    std::string t = good;
    replaceOnce(t, "role=\"refers\"", "role=\"other\"");
    EXPECT_EQ(failures(write("nolight.osm", t)), (Failures{{"regulatory_elements", {200}}}));
  }
  {  // Autoware's layout: the crosswalk element refers to no crosswalk lanelet
    std::string t = readFile(dir.str("aw/lanelet2_map.osm"));
    replaceOnce(t, "ref=\"300\" role=\"refers\"", "ref=\"300\" role=\"other\"");
    std::ofstream(dir.str("aw/edited.osm")) << t;
    EXPECT_EQ(failures(dir.str("aw/edited.osm"), true), (Failures{{"crosswalk_refs", {300}}}));
  }
}

TEST(MapCheck, ToolPrintsEachRuleAndExitsNonZeroOnFailure) {
  lt::TempDir dir("check-tool");
  writeLanelet2(goodMap(), dir.str("map.osm"));
  const auto ok = lt::runCommand(lt::binPath("lanemap-check") + " " + dir.str("map.osm"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("pass  lane_change"), std::string::npos) << ok.output;
  EXPECT_NE(ok.output.find("0 of 8 requirements failed"), std::string::npos) << ok.output;
  std::string t = toLanelet2Xml(goodMap());
  replaceOnce(t, "<tag k=\"lane_change\" v=\"yes\"/>", "");
  std::ofstream(dir.str("bad.osm")) << t;
  const auto bad = lt::runCommand(lt::binPath("lanemap-check") + " " + dir.str("bad.osm"));
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.output.find("FAIL  lane_change"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find(": 1: 2\n"), std::string::npos) << bad.output;
  const auto missing = lt::runCommand(lt::binPath("lanemap-check") + " " + dir.str("none.osm"));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("no such file"), std::string::npos) << missing.output;
}

}  // namespace
}  // namespace lanemap::io
