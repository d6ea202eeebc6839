// Scores of stop lines, crosswalks, their rules and lane-change permissions (core/eval/regulatory.h)
// on constructed maps: a stop line 0.3 m off is matched with error 0.3, a missing one lowers recall,
// a wrong rule or lane_change lowers accuracy; and evaluate()'s JSON carries them.
#include "core/eval/evaluate.h"
#include "core/eval/regulatory.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lanemap::eval {
namespace {

using map::LineType;

map::LineString line(int64_t id, LineType t, std::vector<Eigen::Vector3d> p) {
  map::LineString l;
  l.id = id;
  l.type = t;
  l.points = std::move(p);
  return l;
}

// Two eastbound lanes from x = 0 to 50 (lanelets 100: lines 1|2, 101: lines 2|3; line 2 dashed),
// two westbound ones beside them (102: 4|5, 103: 5|6; line 5 solid), stop lines 10 (x = 49,
// eastbound) and 11 (x = 1, westbound) with a stop sign at 10 and a light at 11; crosswalks at
// x = 45 and x = 5.
map::LaneMap truthMap() {
  map::LaneMap m;
  const auto east = [](double y) { return std::vector<Eigen::Vector3d>{{0, y, 0}, {25, y, 0}, {50, y, 0}}; };
  const auto west = [](double y) { return std::vector<Eigen::Vector3d>{{50, y, 0}, {25, y, 0}, {0, y, 0}}; };
  m.lines = {line(1, LineType::kSolidSolid, east(0.0)), line(2, LineType::kDashed, east(-3.5)),
             line(3, LineType::kCurb, east(-7.0)),      line(4, LineType::kSolidSolid, west(0.0)),
             line(5, LineType::kSolid, west(3.5)),      line(6, LineType::kCurb, west(7.0)),
             line(10, LineType::kStopLine, {{49, 0, 0}, {49, -7, 0}}),
             line(11, LineType::kStopLine, {{1, 0, 0}, {1, 7, 0}})};
  const auto lanelet = [&](int64_t id, int64_t l, int64_t r) {
    map::Lanelet ll;
    ll.id = id;
    ll.left_id = l;
    ll.right_id = r;
    ll.road_id = id < 102 ? 1 : 2;
    const auto& a = m.line(l)->points;
    const auto& b = m.line(r)->points;
    for (size_t i = 0; i < a.size(); ++i) ll.centre.push_back(0.5 * (a[i] + b[i]));
    return ll;
  };
  m.lanelets = {lanelet(100, 1, 2), lanelet(101, 2, 3), lanelet(102, 4, 5), lanelet(103, 5, 6)};
  m.lanelets[0].stop_line_id = m.lanelets[1].stop_line_id = 10;
  m.lanelets[2].stop_line_id = m.lanelets[3].stop_line_id = 11;
  map::RegulatoryElement stop;
  stop.id = 200;
  stop.kind = map::RegulatoryKind::kStopSign;
  stop.stop_line_id = 10;
  stop.lanelets = {100, 101};
  map::RegulatoryElement light = stop;
  light.id = 201;
  light.kind = map::RegulatoryKind::kTrafficLight;
  light.stop_line_id = 11;
  light.lanelets = {102, 103};
  light.light = {{1, 3.3, 5}, {1, 3.7, 5}};
  m.regulatory_elements = {stop, light};
  for (double x : {45.0, 5.0}) {
    map::Crosswalk c;
    c.id = static_cast<int64_t>(300 + x);
    c.left = {{x, -7, 0}, {x, 7, 0}};
    c.right = {{x + 3, -7, 0}, {x + 3, 7, 0}};
    m.crosswalks.push_back(c);
  }
  return m;
}

void shift(map::LineString& l, double dx) {
  for (auto& p : l.points) p.x() += dx;
}

TEST(RegulatoryScores, IdenticalMapsScorePerfectly) {
  const auto m = truthMap();
  const RegulatoryScores s = scoreRegulatory(m, m);
  EXPECT_EQ(s.stop_lines.matched, 2u);
  EXPECT_DOUBLE_EQ(s.stop_lines.precision(), 1.0);
  EXPECT_DOUBLE_EQ(s.stop_lines.recall(), 1.0);
  EXPECT_DOUBLE_EQ(s.stop_lines.error_m(), 0.0);
  EXPECT_EQ(s.crosswalks.matched, 2u);
  EXPECT_EQ(s.rules_agreeing, 2u);
  EXPECT_EQ(s.lane_change_truth, 2u);  // lines 2 and 5
  EXPECT_EQ(s.lane_change_correct, 2u);
  EXPECT_DOUBLE_EQ(s.laneChangeAccuracy(), 1.0);
}

TEST(RegulatoryScores, StopLineOffByThirtyCentimetresIsMatchedWithThatError) {
  const auto truth = truthMap();
  auto built = truthMap();
  shift(*std::find_if(built.lines.begin(), built.lines.end(), [](const auto& l) { return l.id == 10; }), -0.3);
  const RegulatoryScores s = scoreRegulatory(truth, built);
  EXPECT_EQ(s.stop_lines.matched, 2u);
  EXPECT_NEAR(s.stop_lines.error_m(), 0.15, 1e-9);  // mean of 0.3 and 0
  EXPECT_NEAR(s.stop_lines.error_sum_m, 0.3, 1e-9);
  // 2.5 m off: beyond stop_line_match_m (2 m), no match.
  shift(*std::find_if(built.lines.begin(), built.lines.end(), [](const auto& l) { return l.id == 10; }), -2.2);
  const RegulatoryScores far = scoreRegulatory(truth, built);
  EXPECT_EQ(far.stop_lines.matched, 1u);
  EXPECT_DOUBLE_EQ(far.stop_lines.precision(), 0.5);
  EXPECT_DOUBLE_EQ(far.stop_lines.recall(), 0.5);
}

TEST(RegulatoryScores, MissingStopLineAndCrosswalkLowerRecallOnly) {
  const auto truth = truthMap();
  auto built = truthMap();
  built.lines.erase(std::find_if(built.lines.begin(), built.lines.end(), [](const auto& l) { return l.id == 11; }));
  built.regulatory_elements.pop_back();
  built.crosswalks.pop_back();
  const RegulatoryScores s = scoreRegulatory(truth, built);
  EXPECT_DOUBLE_EQ(s.stop_lines.recall(), 0.5);
  EXPECT_DOUBLE_EQ(s.stop_lines.precision(), 1.0);
  EXPECT_DOUBLE_EQ(s.crosswalks.recall(), 0.5);
  EXPECT_DOUBLE_EQ(s.crosswalks.precision(), 1.0);
  // A crosswalk 1 m off is matched with error 1.
  auto moved = truthMap();
  for (auto* e : {&moved.crosswalks[0].left, &moved.crosswalks[0].right}) {
    for (auto& p : *e) p.x() += 1.0;
  }
  const RegulatoryScores m = scoreRegulatory(truth, moved);
  EXPECT_EQ(m.crosswalks.matched, 2u);
  EXPECT_NEAR(m.crosswalks.error_sum_m, 1.0, 1e-9);
}

TEST(RegulatoryScores, WrongRuleAndWrongLaneChangeLowerAccuracy) {
  const auto truth = truthMap();
  auto built = truthMap();
  built.regulatory_elements[0].kind = map::RegulatoryKind::kGiveWay;  // a stop sign read as give way
  built.lines[1].type = LineType::kSolid;                              // line 2: no instead of yes
  const RegulatoryScores s = scoreRegulatory(truth, built);
  EXPECT_EQ(s.rules_compared, 2u);
  EXPECT_EQ(s.rules_agreeing, 1u);
  EXPECT_DOUBLE_EQ(s.ruleAccuracy(), 0.5);
  EXPECT_EQ(s.lane_change_matched, 2u);
  EXPECT_EQ(s.lane_change_correct, 1u);
  EXPECT_DOUBLE_EQ(s.laneChangeAccuracy(), 0.5);
  // A rule where the truth has none counts as wrong too.
  built = truthMap();
  built.regulatory_elements.erase(built.regulatory_elements.begin());
  EXPECT_EQ(scoreRegulatory(truth, built).rules_agreeing, 1u);
  // A built map without the shared line: nothing to compare for it (coverage drops).
  built = truthMap();
  built.lanelets.pop_back();  // 103 gone: line 5 is no longer shared
  const RegulatoryScores c = scoreRegulatory(truth, built);
  EXPECT_EQ(c.lane_change_matched, 1u);
  EXPECT_DOUBLE_EQ(c.laneChangeCoverage(), 0.5);
}

TEST(RegulatoryScores, EvaluateReportsThemInItsJson) {
  const auto truth = truthMap();
  auto built = truthMap();
  built.crosswalks.clear();
  const EvalReport r = evaluate(truth, built);
  const nlohmann::json j = toJson(r);
  EXPECT_EQ(j["stop_lines"]["matched"].get<size_t>(), 2u);
  EXPECT_DOUBLE_EQ(j["stop_lines"]["recall"].get<double>(), 1.0);
  EXPECT_EQ(j["crosswalks"]["truth"].get<size_t>(), 2u);
  EXPECT_DOUBLE_EQ(j["crosswalks"]["recall"].get<double>(), 0.0);
  EXPECT_TRUE(j["crosswalks"]["precision"].is_null());  // no built crosswalk
  EXPECT_DOUBLE_EQ(j["lane_change"]["accuracy"].get<double>(), 1.0);
  EXPECT_NE(summary(r).find("stop lines:"), std::string::npos);
}

}  // namespace
}  // namespace lanemap::eval
