// The map store aligns a road driven again before merging it (core/bev/bev_store.h storeRoad):
// three traversals of a synthetic road, each with its own pose offset, stored one after another.
#include "core/bev/bev_store.h"

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

}  // namespace
}  // namespace lanemap::bev
