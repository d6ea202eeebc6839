// Tests of lanemap-eval (tools/eval.cc) on files: hand-made map pairs written with our Lanelet2
// writer give the JSON keys scripts read with the values evaluate() computes in memory (a missing
// lane: recall 4/5, intersection recall 2/3); lanelet2Origin recovers the writer's origin; the
// simulator's ground truth (West Oakland world, built in-process) scores P = R = 1 against itself;
// a foreign map (Lanelet2's Karlsruhe example) loads and scores against itself and against ours
// without crashing; bad input fails with a message; the broad benchmark's table
// (tools/bench/quality_table.py) counts each miss of lanemap-eval's JSON once, by its kind.
#include "core/eval/evaluate.h"
#include "core/io/lanelet2.h"
#include "core/osm/osm_data.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "tests/common/sim_drive.h"
#include "tests/eval/test_maps.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace {

using lanemap::testing::binPath;
using lanemap::testing::dataPath;
using lanemap::testing::runCommand;
using lanemap::testing::TempDir;

nlohmann::json runEval(const std::string& truth, const std::string& map, const std::string& json,
                       std::string* output = nullptr) {
  const auto r = runCommand(binPath("lanemap-eval") + " --truth " + truth + " --map " + map + " --json " + json);
  if (output) *output = r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  if (!in) return {};
  return nlohmann::json::parse(in);
}

lanemap::map::LaneMap located(lanemap::map::LaneMap m) {
  m.origin_lat = 37.81;
  m.origin_lon = -122.29;
  return m;
}

TEST(EvalTool, JsonKeysAndValuesOnAMissingLane) {
  TempDir dir("eval-tool");
  const auto truth = located(lanemap::testing::network({}));
  const auto built = located(lanemap::testing::network(lanemap::testing::with([](lanemap::testing::Net& n) { n.drop_b1 = true; })));
  lanemap::io::writeLanelet2(truth, dir.str("gt.osm"));
  lanemap::io::writeLanelet2(built, dir.str("built.osm"));
  std::string out;
  const auto j = runEval(dir.str("gt.osm"), dir.str("built.osm"), dir.str("report.json"), &out);
  ASSERT_FALSE(j.is_null());
  const auto mem = lanemap::eval::evaluate(truth, built);
  EXPECT_DOUBLE_EQ(j["lanes"]["recall"].get<double>(), 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(j["lanes"]["recall"].get<double>(), mem.lane_recall.value());
  EXPECT_DOUBLE_EQ(j["lanes"]["precision"].get<double>(), 1.0);
  EXPECT_NEAR(j["lanes"]["rms_m"].get<double>(), 0.0, 1e-3);  // local_x/y: mm precision
  EXPECT_NEAR(j["lanes"]["miou"].get<double>(), 1.0, 1e-3);
  EXPECT_DOUBLE_EQ(j["intersections"]["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["intersections"]["recall"].get<double>(), 2.0 / 3.0);
  EXPECT_NEAR(j["intersections"]["rms_m"].get<double>(), 0.0, 1e-3);
  for (const char* k : {"0.5", "1.0", "1.5"}) {
    ASSERT_TRUE(j["chamfer_ap"].contains(k)) << k;
    EXPECT_NEAR(j["chamfer_ap"][k].get<double>(), mem.chamfer_ap.at(std::stod(k)), 1e-6) << k;
  }
  EXPECT_TRUE(j.contains("lane_graph"));
  ASSERT_EQ(j["roads"].size(), 3u);
  EXPECT_EQ(j["roads"][1]["truth_lanes"].get<int>(), 2);
  EXPECT_EQ(j["roads"][1]["built_lanes"].get<int>(), 1);
  EXPECT_EQ(j["lanes_detail"].size(), 5u);
  // Per built lane: the four built lanes, each detecting the truth lane that names it back.
  ASSERT_EQ(j["built_lanes_detail"].size(), 4u);
  int built_detected = 0;
  for (const auto& b : j["built_lanes_detail"]) {
    if (!b["detected"].get<bool>()) continue;
    ++built_detected;
    bool named_back = false;
    for (const auto& t : j["lanes_detail"]) named_back |= t["lanelets"] == b["truth_lanelets"] && t["built_lanelets"] == b["lanelets"];
    EXPECT_TRUE(named_back) << b.dump();
  }
  EXPECT_EQ(built_detected, 4);
  EXPECT_NE(out.find("recall 0.800"), std::string::npos) << out;
}

// tools/bench/quality_table.py (the broad benchmark's table) over lanemap-eval's JSON of three
// "drives" of one network: where the misses are. Drive 1 lacks lane B1 (a truth lane no built lane
// matched; the pair A1 -> B1 missed for want of it); drive 2 connects A1 to C0 instead of B1 (all
// lanes detected: a truth pair missed and a built pair wrong between detected lanes); drive 3
// has its lane A1 2 m off (whatever lanemap-eval says of it, the table's counts add up to its
// totals). Then --compare lists the one network whose reports differ between two labels.
TEST(EvalTool, TheBenchmarkTableSaysWhereTheMissesAre) {
  TempDir dir("quality-table");
  const auto truth = located(lanemap::testing::network({}));
  const std::vector<lanemap::map::LaneMap> built = {
      located(lanemap::testing::network(lanemap::testing::with([](lanemap::testing::Net& n) { n.drop_b1 = true; }))),
      located(lanemap::testing::network(lanemap::testing::with([](lanemap::testing::Net& n) { n.wrong_connection = true; }))),
      located(lanemap::testing::network(lanemap::testing::with([](lanemap::testing::Net& n) { n.a1_shift = 2.0; })))};
  lanemap::io::writeLanelet2(truth, dir.str("gt.osm"));
  std::vector<nlohmann::json> evals;
  for (size_t k = 0; k < built.size(); ++k) {
    const std::string drive = dir.str("net-s" + std::to_string(k + 1));
    std::filesystem::create_directories(drive + "/drive");
    lanemap::io::writeLanelet2(built[k], drive + "/built.osm");
    evals.push_back(runEval(dir.str("gt.osm"), drive + "/built.osm", drive + "/eval-test.json"));
    ASSERT_FALSE(evals.back().is_null());
  }
  const auto r = runCommand("python3 " + dataPath("../tools/bench/quality_table.py") + " " + dir.str("") + " test");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir.str("quality.json"));
  ASSERT_TRUE(in.good()) << r.output;
  const auto q = nlohmann::json::parse(in)["test"]["pooled"];
  const auto& m = q["misses"];
  // Every miss is counted once, in one of its two kinds.
  size_t truth_lanes = 0, detected = 0, built_lanes = 0, truth_pairs = 0, built_pairs = 0, correct = 0;
  for (const auto& e : evals) {
    truth_lanes += e["lanes"]["truth"].get<size_t>();
    detected += e["lanes"]["detected"].get<size_t>();
    built_lanes += e["lanes"]["built"].get<size_t>();
    truth_pairs += e["intersections"]["truth_pairs"].get<size_t>();
    built_pairs += e["intersections"]["built_pairs"].get<size_t>();
    correct += e["intersections"]["correct_pairs"].get<size_t>();
  }
  EXPECT_EQ(m["lanes_unmatched"].get<size_t>() + m["lanes_not_detected"].get<size_t>(), truth_lanes - detected);
  EXPECT_EQ(m["built_false"].get<size_t>(), built_lanes - detected);
  EXPECT_EQ(m["pairs_missed_lane"].get<size_t>() + m["pairs_missed_both_detected"].get<size_t>(), truth_pairs - correct);
  EXPECT_EQ(m["pairs_wrong_lane"].get<size_t>() + m["pairs_wrong_both_detected"].get<size_t>(), built_pairs - correct);
  // Drives 1 and 2 alone, as reasoned above.
  const auto one = [&](size_t k) {
    std::filesystem::rename(dir.str("net-s" + std::to_string(k) + "/eval-test.json"), dir.str("net-s" + std::to_string(k) + "/eval-one.json"));
    const auto rr = runCommand("python3 " + dataPath("../tools/bench/quality_table.py") + " " + dir.str("") + " one");
    EXPECT_EQ(rr.exit_code, 0) << rr.output;
    std::filesystem::rename(dir.str("net-s" + std::to_string(k) + "/eval-one.json"), dir.str("net-s" + std::to_string(k) + "/eval-test.json"));
    std::ifstream f(dir.str("quality.json"));
    return nlohmann::json::parse(f)["one"]["pooled"]["misses"];
  };
  const auto m1 = one(1);
  EXPECT_EQ(m1["lanes_unmatched"].get<int>(), 1);  // B1
  EXPECT_EQ(m1["lanes_not_detected"].get<int>(), 0);
  EXPECT_EQ(m1["built_false"].get<int>(), 0);
  EXPECT_EQ(m1["pairs_missed_lane"].get<int>(), 1);  // A1 -> B1
  EXPECT_EQ(m1["pairs_missed_both_detected"].get<int>(), 0);
  EXPECT_EQ(m1["pairs_wrong_lane"].get<int>() + m1["pairs_wrong_both_detected"].get<int>(), 0);
  const auto m2 = one(2);
  EXPECT_EQ(m2["lanes_unmatched"].get<int>() + m2["lanes_not_detected"].get<int>(), 0);
  EXPECT_EQ(m2["pairs_missed_both_detected"].get<int>(), 1);  // A1 -> B1
  EXPECT_EQ(m2["pairs_wrong_both_detected"].get<int>(), 1);   // A1 -> C0
  EXPECT_EQ(m2["pairs_missed_lane"].get<int>() + m2["pairs_wrong_lane"].get<int>(), 0);
  EXPECT_NE(r.output.find("misses: truth lanes"), std::string::npos) << r.output;

  // lanemap-check's verdict on each map (quality.sh keeps it as check-LABEL.txt): the table counts
  // the maps whose check failed, as its exit status says, and each failed requirement. Drive 1's
  // map gets a lane drawn twice, the second's left bound its own line 2 cm off the first's
  // (shared_borders fails).
  {
    auto twice = built[0];
    ASSERT_FALSE(twice.lanelets.empty());
    auto lane = twice.lanelets.front();
    auto copy = *std::find_if(twice.lines.begin(), twice.lines.end(), [&](const auto& l) { return l.id == lane.left_id; });
    copy.id = 999999;
    for (auto& p : copy.points) p.y() += 0.02;
    twice.lines.push_back(copy);
    lane.id = 999998;
    lane.left_id = copy.id;
    lane.successors.clear();
    twice.lanelets.push_back(lane);
    lanemap::io::writeLanelet2(twice, dir.str("net-s1/built.osm"));
  }
  int failing = 0;
  for (int k = 1; k <= 3; ++k) {
    const std::string d = dir.str("net-s" + std::to_string(k));
    const auto chk = runCommand(binPath("lanemap-check") + " " + d + "/built.osm > " + d + "/check-test.txt 2>&1");
    failing += chk.exit_code != 0;
  }
  const auto rc = runCommand("python3 " + dataPath("../tools/bench/quality_table.py") + " " + dir.str("") + " test");
  ASSERT_EQ(rc.exit_code, 0) << rc.output;
  std::ifstream qc(dir.str("quality.json"));
  const auto check = nlohmann::json::parse(qc)["test"]["lanemap_check"];
  EXPECT_EQ(check["maps"].get<int>(), 3);
  EXPECT_EQ(check["failing"].get<int>(), failing);
  EXPECT_GE(failing, 1);
  EXPECT_GE(check["requirements"].value("shared_borders", 0), 1) << check.dump();
  EXPECT_NE(rc.output.find("lanemap-check: " + std::to_string(failing) + " of 3 maps fail"), std::string::npos) << rc.output;

  // --compare A B: the networks whose figures differ, A's row above B's. Label "b" is "test" with
  // drive 3's report replaced by drive 1's; a second network ("other") has the same report under
  // both and is not listed.
  namespace fs = std::filesystem;
  for (int k = 1; k <= 3; ++k) {
    const std::string d = dir.str("net-s" + std::to_string(k));
    fs::copy_file(k == 3 ? dir.str("net-s1/eval-test.json") : d + "/eval-test.json", d + "/eval-b.json");
  }
  fs::create_directories(dir.str("other-s1/drive"));
  for (const char* lab : {"test", "b"}) fs::copy_file(dir.str("net-s2/eval-test.json"), dir.str("other-s1/eval-") + lab + ".json");
  const auto c = runCommand("python3 " + dataPath("../tools/bench/quality_table.py") + " " + dir.str("") + " test b --compare test b");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const std::string table = c.output.substr(c.output.find("== test -> b"));
  EXPECT_NE(table.find("1 of 2 networks changed"), std::string::npos) << table;
  size_t rows = 0;
  for (size_t at = table.find("\n   net "); at != std::string::npos; at = table.find("\n   net ", at + 1)) ++rows;
  EXPECT_EQ(rows, 2u) << table;
  EXPECT_EQ(table.find("\n   other "), std::string::npos) << table;
  EXPECT_NE(table.find("POOLED test"), std::string::npos) << table;
  EXPECT_NE(table.find("POOLED b"), std::string::npos) << table;
  // The maps failing lanemap-check under each label (only "test" was checked), by name.
  const size_t verdict = table.find("lanemap-check under test: " + std::to_string(failing) + " of 3 maps fail");
  ASSERT_NE(verdict, std::string::npos) << table;
  EXPECT_NE(table.find("net-s1", verdict), std::string::npos) << table;
  EXPECT_EQ(table.find("lanemap-check under b"), std::string::npos) << table;
  EXPECT_NE(runCommand("python3 " + dataPath("../tools/bench/quality_table.py") + " " + dir.str("") + " test --compare test").exit_code, 0);
}

TEST(EvalTool, OriginOfOurFilesIsTheWritersOrigin) {
  TempDir dir("eval-origin");
  const auto truth = located(lanemap::testing::network({}));
  lanemap::io::writeLanelet2(truth, dir.str("gt.osm"));
  const auto o = lanemap::eval::lanelet2Origin(dir.str("gt.osm"));
  // osmium keeps 1e-7 degrees of the node: the origin comes back to about a centimetre.
  EXPECT_NEAR(o.lat, 37.81, 2e-7);
  EXPECT_NEAR(o.lon, -122.29, 2e-7);
  const auto file = lanemap::io::readLanelet2File(dir.str("gt.osm"), o.lat, o.lon);
  EXPECT_TRUE(file.used_local_xy);
  // Karlsruhe (no local_x/y): the first node.
  const auto k = lanemap::eval::lanelet2Origin(dataPath("lanelet2/karlsruhe_mapping_example.osm"));
  EXPECT_NEAR(k.lat, 49.00345654351, 1e-7);
  EXPECT_NEAR(k.lon, 8.42427590707, 1e-7);
  EXPECT_THROW(lanemap::eval::lanelet2Origin(dir.str("missing.osm")), std::exception);
}

TEST(EvalTool, SimulatorGroundTruthAgainstItselfAndAForeignMap) {
  TempDir dir("eval-sim");
  const auto data = lanemap::osm::readOsm(dataPath("osm/west-oakland.osm"));
  const auto sk = lanemap::skeleton::Skeleton::build(data);
  lanemap::sim::WorldOptions wo;
  wo.seed = 5;
  const auto world = lanemap::sim::buildWorld(sk, wo);
  const std::string gt = dir.str("groundtruth.osm");
  lanemap::io::writeLanelet2(world->truth(), gt);
  const auto self = runEval(gt, gt, dir.str("self.json"));
  ASSERT_FALSE(self.is_null());
  EXPECT_GT(self["lanes"]["truth"].get<int>(), 50);
  EXPECT_DOUBLE_EQ(self["lanes"]["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(self["lanes"]["recall"].get<double>(), 1.0);
  EXPECT_NEAR(self["lanes"]["rms_m"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(self["lanes"]["miou"].get<double>(), 1.0, 1e-6);
  EXPECT_GT(self["intersections"]["truth_pairs"].get<int>(), 50);
  EXPECT_DOUBLE_EQ(self["intersections"]["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(self["intersections"]["recall"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(self["lane_graph"]["recall"].get<double>(), 1.0);
  for (const char* k : {"0.5", "1.0", "1.5"}) EXPECT_DOUBLE_EQ(self["chamfer_ap"][k].get<double>(), 1.0) << k;

  const std::string karlsruhe = dataPath("lanelet2/karlsruhe_mapping_example.osm");
  const auto kk = runEval(karlsruhe, karlsruhe, dir.str("kk.json"));
  ASSERT_FALSE(kk.is_null());
  EXPECT_GT(kk["lanes"]["truth"].get<int>(), 20);
  EXPECT_DOUBLE_EQ(kk["lanes"]["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(kk["lanes"]["recall"].get<double>(), 1.0);
  EXPECT_TRUE(kk["intersections"]["precision"].is_null());  // no intersection lanelets: n/a
  // Two maps 9000 km apart: nothing matches, nothing crashes.
  const auto ko = runEval(karlsruhe, gt, dir.str("ko.json"));
  ASSERT_FALSE(ko.is_null());
  EXPECT_DOUBLE_EQ(ko["lanes"]["precision"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(ko["lanes"]["recall"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(ko["intersections"]["precision"].get<double>(), 0.0);
}

TEST(EvalTool, BadInputFailsWithAMessage) {
  TempDir dir("eval-bad");
  const auto r = runCommand(binPath("lanemap-eval") + " --truth " + dir.str("nope.osm") + " --map " + dir.str("nope.osm"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("nope.osm"), std::string::npos) << r.output;
  std::ofstream(dir.str("bad.osm")) << "<osm><relation id='1'><member type='way' ref='5' role='left'/>"
                                       "<tag k='type' v='lanelet'/></relation></osm>";
  const auto b = runCommand(binPath("lanemap-eval") + " --truth " + dir.str("bad.osm") + " --map " + dir.str("bad.osm"));
  EXPECT_EQ(b.exit_code, 1) << b.output;
  EXPECT_EQ(runCommand(binPath("lanemap-eval") + " --map x.osm").exit_code, 106);  // CLI11: --truth required
}

}  // namespace
