// The map store aligns a road driven again before merging it (core/bev/bev_store.h storeRoad):
// three traversals of a synthetic road, each with its own pose offset, stored one after another.
#include "core/bev/bev_store.h"
#include "core/bev/drive_offsets.h"

#include "tests/bev/synthetic_road.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

namespace lanemap::bev {
namespace {

using testing::solidLine;
using testing::traversal;

RoadBev pass(const Eigen::Vector2d& offset, uint32_t seed) {
  RoadBev r;
  r.road_id = 7;
  r.grid = traversal(offset, seed);
  return r;
}

TEST(StoreAlign, ARoadDrivenAgainIsAlignedToWhatIsStored) {
  lanemap::testing::TempDir dir("store-align");
  const std::vector<Eigen::Vector2d> offsets = {{0.4, -0.5}, {-0.2, 0.4}, {0.1, 0.4}};
  StoredRoad s = storeRoad(dir.str(), pass(offsets[0], 1));
  EXPECT_FALSE(s.merged);
  s = storeRoad(dir.str(), pass(offsets[1], 2));
  EXPECT_TRUE(s.merged);
  ASSERT_TRUE(s.alignment.ok) << s.alignment.why;
  EXPECT_NEAR(s.alignment.shift_m.y(), offsets[0].y() - offsets[1].y(), 0.101);
  s = storeRoad(dir.str(), pass(offsets[2], 3));
  ASSERT_TRUE(s.alignment.ok) << s.alignment.why;
  EXPECT_EQ(s.frames, 90);
  const BevGrid stored = BevGrid::load(s.path);
  const auto [at, spread] = solidLine(stored);
  EXPECT_NEAR(at, (offsets[0].y() + offsets[1].y() + offsets[2].y()) / 3, 0.11);  // the mean, not the first
  EXPECT_LT(spread, solidLine(traversal({0, 0}, 9)).second + 0.05);

  // Unaligned (align = false), the same passes blur the line.
  lanemap::testing::TempDir raw("store-raw");
  for (size_t i = 0; i < offsets.size(); ++i) s = storeRoad(raw.str(), pass(offsets[i], static_cast<uint32_t>(i + 1)), false);
  EXPECT_FALSE(s.alignment.ok);
  EXPECT_GT(solidLine(BevGrid::load(s.path)).second, 2.0 * spread);
}

// The live store (issue 14): drive 1 stored roads 7 and 8; drive 2, its poses 0.3 m east and
// 0.4 m south of drive 1's, drives them again and then road 9, which no drive saw before. Its two
// merges measure its correction; road 9 is stored with it, where drive 1's frame puts the world.
// Without the correction road 9 keeps drive 2's offset.
RoadBev passOf(int64_t road_id, const Eigen::Vector2d& offset, uint32_t seed) {
  RoadBev r = pass(offset, seed);
  r.road_id = road_id;
  return r;
}

TEST(StoreAlign, ADrivesOffsetLearnedOnRoadsDrivenBeforeMovesTheRoadItAloneDrove) {
  for (const bool learn : {true, false}) {
    lanemap::testing::TempDir dir("store-drive-offset");
    const Eigen::Vector2d drive2(0.3, -0.4);
    storeRoad(dir.str(), passOf(7, {0, 0}, 1));
    storeRoad(dir.str(), passOf(8, {0, 0}, 2));
    DriveOffsetOptions options;
    options.enabled = learn;
    LiveDriveOffset offset(options);
    for (const int64_t id : {7, 8}) {
      const Eigen::Vector2i applied = offset.correction();
      EXPECT_EQ(applied, Eigen::Vector2i::Zero()) << "one measurement is not enough (min_roads 2)";
      const StoredRoad s = storeRoad(dir.str(), passOf(id, drive2, 10 + static_cast<uint32_t>(id)), true, applied);
      ASSERT_TRUE(s.alignment.ok) << s.alignment.why;
      offset.addMerge(applied, s.alignment, 30);
    }
    if (learn) {
      EXPECT_EQ(offset.measurements(), 2);
      EXPECT_EQ(offset.correction(), Eigen::Vector2i(-3, 4));
    } else {
      EXPECT_EQ(offset.correction(), Eigen::Vector2i::Zero());
    }
    const StoredRoad nine = storeRoad(dir.str(), passOf(9, drive2, 20), true, offset.correction());
    EXPECT_FALSE(nine.merged);
    const double line = solidLine(BevGrid::load(nine.path)).first;
    if (learn) {
      EXPECT_NEAR(line, 0.0, 0.06) << "drive 1's frame";
    } else {
      EXPECT_NEAR(line, drive2.y(), 0.06) << "drive 2's own offset";
    }
  }
}

TEST(StoreAlign, MeasurementsThatDisagreeOrAreNotTrustedMoveNothing) {
  Alignment a;
  a.ok = true;
  LiveDriveOffset offset;  // min_roads 2, max_spread_m 0.3
  a.shift_cells = {-3, 4};
  offset.addMerge({0, 0}, a, 30);
  EXPECT_EQ(offset.correction(), Eigen::Vector2i::Zero());
  Alignment untrusted = a;
  untrusted.ok = false;
  offset.addMerge({0, 0}, untrusted, 30);  // not a measurement
  EXPECT_EQ(offset.measurements(), 1);
  a.shift_cells = {-1, 2};  // measured after a correction of (-2, 2) was applied: (-3, 4) again
  offset.addMerge({-2, 2}, a, 30);
  EXPECT_EQ(offset.correction(), Eigen::Vector2i(-3, 4));
  EXPECT_TRUE(offset.consistent());
  // The drive drives a road it stored itself again: merged onto its own evidence, no measurement
  // (counted, the (0, 0) it measures would make the three disagree).
  offset.addStored(42, false, {-3, 4}, Alignment(), 30);
  Alignment self = a;
  self.shift_cells = {3, -4};  // the road was stored before the correction: it is off by it
  offset.addStored(42, true, {-3, 4}, self, 30);
  EXPECT_EQ(offset.measurements(), 2);
  EXPECT_EQ(offset.correction(), Eigen::Vector2i(-3, 4));
  a.shift_cells = {12, -10};  // a wrong alignment 2 m away: the three disagree, nothing is applied
  offset.addMerge({0, 0}, a, 30);
  EXPECT_FALSE(offset.consistent());
  EXPECT_EQ(offset.correction(), Eigen::Vector2i::Zero());
}

}  // namespace
}  // namespace lanemap::bev
