// Lane precision/recall per confidence band (core/eval/confidence.h) on the evaluation's test
// network: two sure lanes right, one middling lane right, two doubtful lanes wrong, one unrated.
#include "core/eval/confidence.h"
#include "core/eval/evaluate.h"
#include "tests/eval/test_maps.h"

#include <gtest/gtest.h>

namespace {

using lanemap::map::LaneletKind;
using lanemap::testing::network;

TEST(ConfidenceBands, HighConfidenceLanesAreRightMoreOftenInTheReport) {
  const auto truth = network({});  // road lanes A0, A1 (road 1), B0, B1 (road 2), C0 (road 3)
  lanemap::testing::MapBuilder b;
  b.next = 1000;
  const auto shifted = [](const lanemap::map::Lanelet& l, double dy) {
    lanemap::eval::Polyline c;
    for (const auto& p : l.centre) c.push_back(p.head<2>() + Eigen::Vector2d(0, dy));
    return c;
  };
  std::vector<std::pair<int64_t, std::optional<double>>> conf;
  int k = 0;
  for (const auto& l : truth.lanelets) {
    if (l.kind != LaneletKind::kRoad) continue;
    // A0 0.9, A1 0.85, B0 0.6: right; B1 3 m off (wrong) 0.4; C0 right but unrated.
    const double dy = k == 3 ? -3.0 : 0.0;
    const std::optional<double> c = k == 0 ? 0.9 : k == 1 ? 0.85 : k == 2 ? 0.6 : k == 3 ? std::optional<double>(0.4) : std::nullopt;
    conf.push_back({b.lane(shifted(l, dy), l.road_id), c});
    ++k;
  }
  conf.push_back({b.lane(lanemap::testing::straight({-100, 12}, {-10, 12}), 1), 0.2});  // a spurious lane
  for (auto& ll : b.m.lanelets) {
    for (const auto& [id, c] : conf) {
      if (ll.id == id) ll.confidence = c;
    }
  }
  const auto report = lanemap::eval::evaluate(truth, b.m);
  ASSERT_EQ(report.built_lanes.size(), 6u);
  ASSERT_EQ(report.truth_lanes.size(), 5u);
  EXPECT_EQ(report.lane_recall.hits, 4u);
  const auto bands = lanemap::eval::confidenceBands(report, b.m);
  ASSERT_EQ(bands.bands.size(), 3u);
  EXPECT_EQ(bands.unrated, 1u);
  const auto& low = bands.bands[0], &mid = bands.bands[1], &high = bands.bands[2];
  EXPECT_DOUBLE_EQ(low.lo, 0.0);
  EXPECT_DOUBLE_EQ(mid.lo, 0.5);
  EXPECT_DOUBLE_EQ(high.lo, 0.8);
  EXPECT_DOUBLE_EQ(high.hi, 1.0);
  EXPECT_EQ(high.precision.total, 2u);
  EXPECT_DOUBLE_EQ(high.precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(high.recall.value(), 2.0 / 5.0);
  EXPECT_EQ(mid.precision.total, 1u);
  EXPECT_DOUBLE_EQ(mid.precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(mid.recall.value(), 1.0 / 5.0);
  EXPECT_EQ(low.precision.total, 2u);
  EXPECT_DOUBLE_EQ(low.precision.value(), 0.0);
  EXPECT_DOUBLE_EQ(low.recall.value(), 0.0);
  const auto j = lanemap::eval::toJson(bands);
  EXPECT_EQ(j["bands"][2]["built"], 2);
  EXPECT_EQ(j["bands"][2]["detected"], 2);
  EXPECT_EQ(j["unrated"], 1);
  EXPECT_NE(lanemap::eval::summary(bands).find("[0.80, 1.00]: 2 built, P 1.000, R 0.400"), std::string::npos)
      << lanemap::eval::summary(bands);
}

}  // namespace
