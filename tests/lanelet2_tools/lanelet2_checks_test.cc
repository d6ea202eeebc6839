// Lanelet2's own map checks on the maps lanemap writes: the upstream validator `lanelet2_validate`
// (all 8 checks of Lanelet2 1.2.3, errors and warnings) and `route_check` (Lanelet2's loader and
// routing graph), built from ../shared/tools/lanelet2 (see its README). Each map must give no
// issue but a bounded number of curvature_too_big warnings (not yet 0: see kTruthCurvatureMax)
// and route with no load, degenerate or routing error, every lanelet passable and none isolated. Maps: a hand-made one, the simulator's ground truth of a drive, and the map
// lanemap-offline builds from that short drive (whose stop line must be where the truth has it);
// hand-made maps with each kind of regulatory element (stop sign, right of way, give-way sign,
// traffic light) and a crosswalk lanelet.
//
// The tools: $LANELET2_BIN, else ~/.cache/lanelet2-1.2.3/bin; when missing they are built once with
// ../shared/tools/lanelet2/build.sh (about 6 min on 2 cores). Without ../shared (a fresh clone)
// the tests are skipped, saying so.
#include "core/eval/area.h"
#include "core/eval/regulatory.h"
#include "core/io/lanelet2.h"
#include "core/io/map_check.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <map>
#include <sys/file.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
namespace lt = lanemap::testing;

fs::path toolsSource() { return fs::path(LANEMAP_DATA_DIR).parent_path().parent_path() / "shared/tools/lanelet2"; }

fs::path binDir() {
  if (const char* b = std::getenv("LANELET2_BIN"); b && *b) return b;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  const fs::path cache = xdg && *xdg ? fs::path(xdg) : fs::path(home ? home : "/tmp") / ".cache";
  return cache / "lanelet2-1.2.3/bin";
}

bool toolsBuilt() {
  return fs::exists(binDir() / "lanelet2_validate") && fs::exists(binDir() / "route_check");
}

// Empty when the tools are there (built now if need be), else why the test is skipped.
std::string toolsMissing() {
  static const std::string why = [] {
    if (toolsBuilt()) return std::string();
    const fs::path build = toolsSource() / "build.sh";
    if (!fs::exists(build)) {
      return "Lanelet2's checks are not available: no " + (binDir() / "lanelet2_validate").string() + " and no " +
             build.string() + " to build them (../shared is not part of a plain clone)";
    }
    if (std::getenv("LANELET2_BIN")) return "LANELET2_BIN=" + binDir().string() + " holds no lanelet2_validate/route_check";
    // One build at a time across the test processes ctest starts.
    fs::create_directories(binDir().parent_path());
    const int lock = open((binDir().parent_path().string() + ".lock").c_str(), O_CREAT | O_RDWR, 0644);
    if (lock >= 0) flock(lock, LOCK_EX);
    std::string out;
    if (!toolsBuilt()) {
      std::fprintf(stderr, "building Lanelet2's checks once (%s, about 6 min)\n", build.c_str());
      const auto r = lt::runCommand("bash " + build.string());
      if (r.exit_code != 0) out = "FAILED: " + build.string() + " exited " + std::to_string(r.exit_code) + ":\n" + r.output;
    }
    if (lock >= 0) {
      flock(lock, LOCK_UN);
      close(lock);
    }
    return out;
  }();
  return why;
}

#define REQUIRE_TOOLS()                                   \
  do {                                                    \
    const std::string why = toolsMissing();               \
    if (why.rfind("FAILED", 0) == 0) FAIL() << why;       \
    if (!why.empty()) GTEST_SKIP() << why;                \
  } while (0)

struct Checked {
  std::string validate_output;
  int validate_rc = -1;
  nlohmann::json route;  // route_check's JSON line
  std::string route_output;
  int route_rc = -1;
};

// Runs both tools on `map` (origin: the writer's, from the sidecar; else the tools' first node).
Checked check(const std::string& map) {
  Checked c;
  std::string origin;
  if (const auto o = lanemap::io::lanelet2WriterOrigin(map)) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "%.10f %.10f", o->lat, o->lon);
    origin = buf;
  }
  std::istringstream ll(origin);
  std::string lat, lon;
  ll >> lat >> lon;
  const std::string v = (binDir() / "lanelet2_validate").string() +
                        (origin.empty() ? std::string() : " --lat " + lat + " --lon " + lon) + " " + map;
  const auto rv = lt::runCommand(v);
  c.validate_output = rv.output;
  c.validate_rc = rv.exit_code;
  const auto rr = lt::runCommand((binDir() / "route_check").string() + " " + map +
                                 (origin.empty() ? std::string() : " --origin " + origin));
  c.route_output = rr.output;
  c.route_rc = rr.exit_code;
  const auto brace = rr.output.rfind("\n{");
  if (brace != std::string::npos) {
    try {
      c.route = nlohmann::json::parse(rr.output.substr(brace + 1));
    } catch (const std::exception&) {
    }
  }
  return c;
}

std::string lastLine(const std::string& text) {
  std::string t = text;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  const auto nl = t.rfind('\n');
  return nl == std::string::npos ? t : t.substr(nl + 1);
}

// How many of the validator's issues are curvature_too_big warnings.
size_t curvatureWarnings(const std::string& output) {
  size_t n = 0;
  for (size_t p = output.find("[mapping.curvature_too_big]"); p != std::string::npos;
       p = output.find("[mapping.curvature_too_big]", p + 1)) {
    ++n;
  }
  return n;
}

// Lanelets of `m` with no successor, no predecessor and no same-direction neighbour (a shared
// bound, right of one and left of the other): what route_check must call isolated, e.g. the two
// directions of a road mapped without its intersections (Lanelet2's routing graph does not join
// lanes of opposite directions).
size_t unconnected(const lanemap::map::LaneMap& m) {
  std::set<int64_t> connected;
  std::map<int64_t, std::vector<int64_t>> as_left, as_right;
  for (const auto& ll : m.lanelets) {
    as_left[ll.left_id].push_back(ll.id);
    as_right[ll.right_id].push_back(ll.id);
    if (!ll.successors.empty()) connected.insert(ll.id);
    connected.insert(ll.successors.begin(), ll.successors.end());
  }
  for (const auto& ll : m.lanelets) {
    if (as_left.count(ll.right_id) || as_right.count(ll.left_id)) connected.insert(ll.id);
  }
  return m.lanelets.size() - connected.size();
}

// Both tools pass on `map`: Lanelet2 loads all of its lanelets, all passable, and isolates
// exactly those our reader finds unconnected. The validator finds no issue but at most
// `max_curvature` curvature_too_big warnings: bounds of intersection lanelets turning tighter
// than 2 m where the lane ends leave no room for a wider curve (measured figures in the callers).
void expectClean(const std::string& map, size_t max_curvature) {
  const auto o = lanemap::io::lanelet2WriterOrigin(map);
  ASSERT_TRUE(o.has_value()) << map;
  const auto ours = lanemap::io::readLanelet2(map, o->lat, o->lon);
  const size_t lanelets = ours.lanelets.size();
  ASSERT_GT(lanelets, 0u);
  const Checked c = check(map);
  const size_t curvature = curvatureWarnings(c.validate_output);
  EXPECT_EQ(lastLine(c.validate_output), std::to_string(curvature) + " issues found.") << map << ":\n" << c.validate_output;
  EXPECT_LE(curvature, max_curvature) << c.validate_output;
  if (curvature == 0) { EXPECT_EQ(c.validate_rc, 0) << c.validate_output; }
  ASSERT_TRUE(c.route.is_object()) << c.route_output;
  EXPECT_EQ(c.route_rc, 0) << c.route_output;
  EXPECT_EQ(c.route["load_errors"].get<int>(), 0) << c.route_output;
  EXPECT_EQ(c.route["degenerate"].get<int>(), 0) << c.route_output;
  EXPECT_EQ(c.route["routing_errors"].get<int>(), 0) << c.route_output;
  // Crosswalk lanelets load as lanelets too, but no vehicle may pass them.
  EXPECT_EQ(c.route["lanelets"].get<size_t>(), lanelets + ours.crosswalks.size()) << c.route_output;
  EXPECT_EQ(c.route["passable"].get<size_t>(), lanelets) << c.route_output;
  EXPECT_EQ(c.route["regulatory_elements"].get<size_t>(), ours.regulatory_elements.size()) << c.route_output;
  EXPECT_EQ(c.route["isolated"].get<size_t>(), unconnected(ours)) << c.route_output;
  std::printf("%s: %s (%zu curvature); %zu regulatory elements, %zu crosswalks; route_check %s\n",
              fs::path(map).filename().c_str(), lastLine(c.validate_output).c_str(), curvature,
              ours.regulatory_elements.size(), ours.crosswalks.size(), c.route.dump().c_str());
}

// curvature_too_big warnings left (measured on this drive, seed 7): the truth of the whole world
// and the map of the drive. The validator's 7 other checks find nothing.
// Before (the writer and bounds of f197959): 31,772 issues on a truth of this world, 1,651 on a
// map of a 60 s drive, of every check but bool_tags, duplicated_points and graph_is_valid.
constexpr size_t kTruthCurvatureMax = 31;
constexpr size_t kMapCurvatureMax = 0;

// The drive every test of this file shares: the BEV tests' drive (tests/bev/bev_replay.h: 18 s of
// West Oakland, seed 7, 5 Hz camera), so that a test run makes it once for all of them.
std::string drive() { return lt::sharedSimDrive("osm/west-oakland.osm", 18.0, 7, "--camera-hz 5"); }

TEST(Lanelet2Checks, ReferenceMapOfLanelet2IsClean) {
  REQUIRE_TOOLS();
  // The tools themselves: Lanelet2's example map passes (its README's figures).
  const Checked c = check(lt::dataPath("lanelet2/karlsruhe_mapping_example.osm"));
  EXPECT_EQ(lastLine(c.validate_output), "0 issues found.") << c.validate_output;
  ASSERT_TRUE(c.route.is_object()) << c.route_output;
  EXPECT_EQ(c.route["lanelets"].get<int>(), 371);
  EXPECT_EQ(c.route["routing_errors"].get<int>(), 0);
}

TEST(Lanelet2Checks, ToolsSeeADefectiveMap) {
  REQUIRE_TOOLS();
  // The tests can fail: an unknown tag and two points 1 cm apart are found.
  lt::TempDir dir("l2-defect");
  const std::string path = dir.str("bad.osm");
  std::ofstream(path) << R"(<?xml version="1.0"?>
<osm version="0.6">
  <node id="1" lat="49.0" lon="8.4"><tag k="ele" v="0"/></node>
  <node id="2" lat="49.0001" lon="8.4"><tag k="ele" v="0"/></node>
  <node id="3" lat="49.00010009" lon="8.4"><tag k="ele" v="0"/></node>
  <node id="4" lat="49.0" lon="8.40005"><tag k="ele" v="0"/></node>
  <node id="5" lat="49.0001" lon="8.40005"><tag k="ele" v="0"/></node>
  <way id="10"><nd ref="1"/><nd ref="2"/><nd ref="3"/><tag k="type" v="line_thin"/><tag k="subtype" v="solid"/></way>
  <way id="11"><nd ref="4"/><nd ref="5"/><tag k="type" v="line_thin"/><tag k="subtype" v="solid"/></way>
  <relation id="20"><member type="way" ref="10" role="left"/><member type="way" ref="11" role="right"/>
    <tag k="type" v="lanelet"/><tag k="subtype" v="road"/><tag k="location" v="urban"/><tag k="mine" v="x"/></relation>
</osm>
)";
  const Checked c = check(path);
  EXPECT_NE(c.validate_rc, 0);
  EXPECT_NE(c.validate_output.find("attribute mine is not a known lanelet2 tag"), std::string::npos) << c.validate_output;
  EXPECT_NE(c.validate_output.find("Point is very close to point"), std::string::npos) << c.validate_output;
}

// A two-lane road (lanelets 100 left, 101 right, x = 0..60) into intersection lanelets 102/103,
// and road 104 coming from the north to the same junction (the priority of a right of way). Stop
// line 6 ends 100 and 101, crosswalk 300 crosses both lanes; one rule of `kind` at the stop line.
lanemap::map::LaneMap ruledMap(lanemap::map::RegulatoryKind kind, bool priority) {
  using namespace lanemap::map;
  LaneMap m;
  m.origin_lat = 49.0;
  m.origin_lon = 8.4;
  m.origin_alt = 100.0;
  const auto along = [](double x0, double x1, double y) {
    std::vector<Eigen::Vector3d> p;
    for (double x = x0; x <= x1 + 1e-9; x += 10.0) p.emplace_back(x, y, 0.0);
    return p;
  };
  const auto ls = [&](int64_t id, LineType t, std::vector<Eigen::Vector3d> p) {
    LineString l;
    l.id = id;
    l.type = t;
    l.points = std::move(p);
    m.lines.push_back(l);
  };
  ls(1, LineType::kSolid, along(0, 60, 3.5));
  ls(2, LineType::kDashed, along(0, 60, 0.0));
  ls(3, LineType::kCurb, along(0, 60, -3.5));
  ls(4, LineType::kVirtual, along(60, 80, 3.5));
  ls(5, LineType::kVirtual, along(60, 80, 0.0));
  ls(7, LineType::kVirtual, along(60, 80, -3.5));
  ls(6, LineType::kStopLine, {{59.0, 3.5, 0.0}, {59.0, -3.5, 0.0}});
  // Road 104 from the north (x = 70, y = 60 -> 10), ending where the junction begins.
  std::vector<Eigen::Vector3d> l104, r104;
  for (double y = 60.0; y >= 10.0 - 1e-9; y -= 10.0) {
    l104.emplace_back(73.5, y, 0.0);
    r104.emplace_back(66.5, y, 0.0);
  }
  ls(8, LineType::kCurb, l104);
  ls(9, LineType::kCurb, r104);
  const auto lanelet = [&](int64_t id, int64_t l, int64_t r, LaneletKind k) {
    Lanelet ll;
    ll.id = id;
    ll.kind = k;
    ll.left_id = l;
    ll.right_id = r;
    const auto& a = m.line(l)->points;
    const auto& b = m.line(r)->points;
    for (size_t i = 0; i < a.size(); ++i) ll.centre.push_back(0.5 * (a[i] + b[i]));
    m.lanelets.push_back(ll);
  };
  lanelet(100, 1, 2, LaneletKind::kRoad);
  lanelet(101, 2, 3, LaneletKind::kRoad);
  lanelet(102, 4, 5, LaneletKind::kIntersection);
  lanelet(103, 5, 7, LaneletKind::kIntersection);
  lanelet(104, 8, 9, LaneletKind::kRoad);
  m.lanelets[0].successors = {102};
  m.lanelets[1].successors = {103};
  m.lanelets[0].stop_line_id = m.lanelets[1].stop_line_id = 6;
  RegulatoryElement r;
  r.id = 200;
  r.kind = kind;
  r.stop_line_id = 6;
  r.lanelets = {100, 101};
  if (priority) r.priority = {104};
  if (kind == RegulatoryKind::kTrafficLight) r.light = {{59.0, -0.2, 5.0}, {59.0, 0.2, 5.0}};
  m.regulatory_elements.push_back(r);
  Crosswalk c;
  c.id = 300;
  c.left = {{50.0, -3.5, 0.0}, {50.0, 3.5, 0.0}};
  c.right = {{53.0, -3.5, 0.0}, {53.0, 3.5, 0.0}};
  c.crossing = {100, 101};
  m.crosswalks.push_back(c);
  return m;
}

TEST(Lanelet2Checks, RegulatoryElementsAndCrosswalksGiveNoIssue) {
  REQUIRE_TOOLS();
  using lanemap::map::RegulatoryKind;
  lt::TempDir dir("l2-rules");
  int n = 0;
  for (const auto& [kind, priority] : std::vector<std::pair<RegulatoryKind, bool>>{
           {RegulatoryKind::kStopSign, false}, {RegulatoryKind::kGiveWay, true},
           {RegulatoryKind::kGiveWay, false}, {RegulatoryKind::kTrafficLight, false}}) {
    const std::string path = dir.str("rules" + std::to_string(n++) + ".osm");
    lanemap::io::writeLanelet2(ruledMap(kind, priority), path);
    SCOPED_TRACE(path);
    expectClean(path, 0);
    const Checked c = check(path);
    EXPECT_EQ(c.route["regulatory_elements"].get<int>(), 1) << c.route_output;
    EXPECT_EQ(c.route["lanelets"].get<int>(), 6) << c.route_output;  // 5 lanes and the crosswalk
  }
}

TEST(Lanelet2Checks, SimulatedGroundTruthHasNoIssueButBoundedCurvature) {
  REQUIRE_TOOLS();
  const std::string d = drive();
  ASSERT_FALSE(d.empty());
  expectClean(d + "/groundtruth.osm", kTruthCurvatureMax);
  // Autoware's shared borders (lanemap-check): intersection lanelets side by side or opposed along
  // the centre line share their bound (before the world builder shared them: 74 ways on top of
  // another). Its regulatory elements are sound.
  for (const auto& r : lanemap::io::checkLanelet2Map(d + "/groundtruth.osm")) {
    if (r.name == "shared_borders" || r.name == "regulatory_elements") {
      EXPECT_TRUE(r.passed) << r.name << ": " << r.offenders.size() << " offenders";
      EXPECT_TRUE(r.applicable) << r.name;
    }
  }
}

TEST(Lanelet2Checks, MapBuiltFromATestDriveHasNoIssue) {
  REQUIRE_TOOLS();
  const std::string d = drive();
  ASSERT_FALSE(d.empty());
  lt::TempDir out("l2-offline");
  const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --log " + d + "/drive.lcmlog --osm " + d +
                                "/roads.osm --out " + out.str("map"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string map = out.str("map/map.osm");
  expectClean(map, kMapCurvatureMax);
  EXPECT_TRUE(fs::exists(out.str("map/map_projector_info.yaml")));

  // The stop line the BEV saw at the end of the drive's first road is in the map where the truth
  // has it (measured: 0.011 m off), and the rule at it agrees with the truth's (none: OSM has no
  // control on that approach).
  {
    const auto t = lanemap::io::lanelet2WriterOrigin(d + "/groundtruth.osm");
    ASSERT_TRUE(t.has_value());
    const auto truth = lanemap::eval::restrictToRoads(lanemap::io::readLanelet2(d + "/groundtruth.osm", t->lat, t->lon),
                                                      lanemap::eval::drivenRoadsFromScenario(d + "/scenario.json"));
    const auto s = lanemap::eval::scoreRegulatory(truth, lanemap::io::readLanelet2(map, t->lat, t->lon));
    EXPECT_EQ(s.stop_lines.truth, 1u);
    EXPECT_EQ(s.stop_lines.built, 1u);
    EXPECT_EQ(s.stop_lines.matched, 1u);
    EXPECT_LT(s.stop_lines.error_m(), 0.3);
    EXPECT_EQ(s.rules_agreeing, s.rules_compared);
  }

  // Autoware's layout adds turn_direction to the intersection lanelets, a tag plain Lanelet2's
  // validator does not know, and road_marking regulatory elements for stop lines and crosswalk
  // elements, which only Autoware's Lanelet2 extension implements: exactly those issues.
  const auto o = lanemap::io::lanelet2WriterOrigin(map);
  ASSERT_TRUE(o.has_value());
  const auto built = lanemap::io::readLanelet2(map, o->lat, o->lon);
  size_t intersections = 0;
  for (const auto& ll : built.lanelets) intersections += ll.kind == lanemap::map::LaneletKind::kIntersection;
  lanemap::io::writeAutowareMapFolder(built, out.str("autoware"));
  const Checked a = check(out.str("autoware/lanelet2_map.osm"));
  size_t turn_warnings = 0, other = 0;
  std::istringstream lines(a.validate_output);
  for (std::string l; std::getline(lines, l);) {
    if (l.find("attribute turn_direction is not a known lanelet2 tag") != std::string::npos) {
      ++turn_warnings;
    } else if (l.rfind("Warning", 0) == 0 ||
               (l.rfind("Error", 0) == 0 && l.find("road_marking") == std::string::npos &&
                l.find("type crosswalk") == std::string::npos &&
                l.find("Failed to get id") == std::string::npos && l.find("Errors ocurred while parsing") == std::string::npos)) {
      ++other;
    }
  }
  EXPECT_EQ(turn_warnings, intersections) << a.validate_output;
  EXPECT_EQ(other, 0u) << a.validate_output;
  EXPECT_EQ(a.route["routing_errors"].get<int>(), 0) << a.route_output;
}


// Issue 15: the maps lanemap builds from a drive of every OSM extract in data/ (West Oakland,
// Monaco and the twelve hard cases of data/osm/dev: roundabouts, slip lanes, sausage links, a
// SPUI) pass Lanelet2's validator with 0 issues (no curvature warning either), route with no
// error, and pass every requirement of lanemap-check. A 40 s drive each (seed 1, camera only at
// 5 Hz), mapped on the simulator's truth labels. Before the shared borders, the boundary outlier
// rule and the chord for too tight bounds: 12 validator issues on 3 of the 14 maps and
// lanemap-check's shared_borders failed on 6. The drives turn round at dead ends (the default
// since 2026-12-06): on them aurora's map failed shared_borders until the bounds of opposite lanes
// on top of each other were made one line (a link and its reverse, bounded within 0.1 m of each
// other on the OSM line; core/mapping/shared_dividers.h), and seattle's had two curvature warnings
// (ConnectorBordersWithin5cm... below). README, "Lanelet2 and Autoware".
class EveryExtract : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryExtract, MapHasNoIssueAndPassesLanemapCheck) {
  REQUIRE_TOOLS();
  const std::string d = lt::sharedSimDrive(GetParam(), 40.0, 1, "--no-lidar --camera-hz 5");
  ASSERT_FALSE(d.empty());
  lt::TempDir out("l2-extract");
  const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --log " + d +
                                "/drive.lcmlog --osm " + d + "/roads.osm --out " + out.str("map"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string map = out.str("map/map.osm");
  expectClean(map, 0);
  size_t applicable = 0;
  for (const auto& c : lanemap::io::checkLanelet2Map(map)) {
    EXPECT_TRUE(c.passed) << c.name << ": " << c.offenders.size() << " offenders, first "
                          << (c.offenders.empty() ? -1 : c.offenders.front());
    applicable += c.applicable;
  }
  EXPECT_GE(applicable, 5u);  // ele, lanelet tags, bounds apart, centre lines inside, ...
}

const std::vector<const char*> kExtracts = {
    "osm/west-oakland.osm", "osm/monaco.osm.pbf", "osm/dev/arizona_highways.osm", "osm/dev/aurora_sausage_link.osm",
    "osm/dev/borough_sausage_links.osm", "osm/dev/fremantle_placement.osm", "osm/dev/i5_exit_ramp.osm",
    "osm/dev/kingsway_junction.osm", "osm/dev/montlake_roundabout.osm", "osm/dev/neukolln.osm",
    "osm/dev/perth_peanut_roundabout.osm", "osm/dev/roosevelt_cycletrack.osm", "osm/dev/seattle_slip_lane.osm",
    "osm/dev/tiny_roundabout.osm"};

// An extract added to data/osm is checked too: the list above names every one.
TEST(Lanelet2Checks, EveryExtractOfTheDataFolderIsListed) {
  std::set<std::string> listed(kExtracts.begin(), kExtracts.end()), found;
  for (const char* sub : {"osm", "osm/dev"}) {
    for (const auto& e : fs::directory_iterator(lt::dataPath(sub))) {
      const std::string name = e.path().filename().string();
      if (name.size() > 4 && (name.substr(name.size() - 4) == ".osm" || name.substr(name.size() - 4) == ".pbf")) {
        found.insert(std::string(sub) + "/" + name);
      }
    }
  }
  EXPECT_EQ(found, listed);
}

// Two connections side by side whose borders, each shaped by the car's paths, run within 5 cm of
// each other for a stretch without being one line (seattle, the turning-round route of seed 1:
// the two lanes of road 27 into road 6). The writer merged each inner point of the second within
// 5 cm of the first's nodes into them: moved by 2-5 cm between points 0.45 m apart, its left bound
// turned at curvature 0.77 and 0.68 where the connection's own check saw 0.46, and Lanelet2's
// validator warned twice. Such a point is now left out; the map is clean.
TEST(Lanelet2Checks, ConnectorBordersWithin5cmAreNotKinkedByTheWritersNodeMerge) {
  REQUIRE_TOOLS();
  const std::string d = lt::sharedSimDrive("osm/dev/seattle_slip_lane.osm", 40.0, 1, "--no-lidar --camera-hz 5");
  ASSERT_FALSE(d.empty());
  lt::TempDir out("l2-seattle");
  const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --no-lidar --log " + d +
                                "/drive.lcmlog --osm " + d + "/roads.osm --out " + out.str("map"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectClean(out.str("map/map.osm"), 0);
  for (const auto& c : lanemap::io::checkLanelet2Map(out.str("map/map.osm"))) {
    EXPECT_TRUE(c.passed) << c.name << ": " << c.offenders.size() << " offenders";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Lanelet2Checks, EveryExtract,
    ::testing::ValuesIn(kExtracts),
    [](const ::testing::TestParamInfo<const char*>& info) {
      std::string name = std::filesystem::path(info.param).filename().string();
      name = name.substr(0, name.find('.'));
      for (char& c : name) if (c == '-') c = '_';
      return name;
    });

}  // namespace
