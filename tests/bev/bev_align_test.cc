// Traversal alignment before a merge (core/bev/bev_align.h): a synthetic two-lane road seen by
// traversals whose poses carry known offsets.
#include "core/bev/bev_align.h"

#include "tests/bev/synthetic_road.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lanemap::bev {
namespace {

using testing::solidLine;
using testing::traversal;

TEST(BevAlign, FindsTheOffsetBetweenTwoTraversals) {
  const BevGrid ref = traversal({0.0, 0.0}, 1);
  for (const Eigen::Vector2d& off : {Eigen::Vector2d(0.4, -0.3), Eigen::Vector2d(-0.9, 0.6), Eigen::Vector2d(1.2, 1.1)}) {
    const BevGrid t = traversal(off, 2);
    const Alignment a = estimateShift(ref, t);
    ASSERT_TRUE(a.ok) << a.why;
    // The shift undoes the offset, to a cell (0.1 m) across the road; along it the dashes decide.
    EXPECT_NEAR(a.shift_m.y(), -off.y(), 0.101) << off.transpose();
    EXPECT_NEAR(a.shift_m.x(), -off.x(), 0.101) << off.transpose();
    EXPECT_GT(a.correlation, 0.5);
    EXPECT_GT(a.overlap_cells, 60000);
    // Shifted by it, the traversal's solid line is where the reference's is.
    EXPECT_NEAR(solidLine(shiftedGrid(t, a.shift_cells)).first, solidLine(ref).first, 0.051);
  }
}

TEST(BevAlign, OffsetsBeyondTheSearchAreNotFoundAndNothingIsMadeUp) {
  const BevGrid ref = traversal({0.0, 0.0}, 1);
  AlignOptions o;
  o.search_m = 0.5;
  // 1.75 m across: half a lane; the best match within 0.5 m is no match of the lines.
  const Alignment a = estimateShift(ref, traversal({0.0, 1.75}, 2), o);
  EXPECT_LE(a.shift_cells.cwiseAbs().maxCoeff(), 5);  // it cannot reach it
  if (a.ok) {
    EXPECT_LT(a.correlation, 0.5) << a.shift_m.transpose();
  }
  // No overlap at all.
  const Alignment far = estimateShift(ref, traversal({0.0, 0.0}, 3, true, 200, 260));
  EXPECT_FALSE(far.ok);
  EXPECT_NE(far.why.find("overlap"), std::string::npos) << far.why;
  // A road without lines: nothing to register on.
  const Alignment blank = estimateShift(ref, traversal({0.3, 0.3}, 4, false));
  EXPECT_FALSE(blank.ok);
  EXPECT_FALSE(blank.why.empty());
}

TEST(BevAlign, TraversalsFuseOnTheirMeanAndTheLinesStaySharp) {
  const std::vector<Eigen::Vector2d> offsets = {{0.5, -0.4}, {-0.3, 0.5}, {0.1, 0.2}, {-0.6, -0.6}};
  BevGrid aligned, blurred;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < offsets.size(); ++i) {
    const BevGrid t = traversal(offsets[i], 10 + static_cast<uint32_t>(i));
    const Alignment a = mergeAligned(t, aligned, true);  // every traversal has 30 frames: equal weights
    mergeAligned(t, blurred, false);
    if (i > 0) {
      EXPECT_TRUE(a.ok) << i << ": " << a.why;
    }
    mean += offsets[i] / static_cast<double>(offsets.size());
  }
  EXPECT_EQ(aligned.frames(), 4 * 30);
  // Three merges, each counted by its correlation (traversals of one road agree: above 0.5 each);
  // merged unaligned, how well they agree is not known: no agreement.
  EXPECT_EQ(aligned.merges(), 3);
  EXPECT_GT(aligned.agreement(), 3 * 0.5);
  EXPECT_LE(aligned.agreement(), 3.0);
  EXPECT_EQ(blurred.merges(), 3);
  EXPECT_EQ(blurred.agreement(), 0.0);
  const auto [at_aligned, spread_aligned] = solidLine(aligned);
  const auto [at_blurred, spread_blurred] = solidLine(blurred);
  const double spread_one = solidLine(traversal({0, 0}, 99)).second;
  // The fused line is at the mean of the four offsets (every drive counts the same), to a cell and
  // a rounding, not at the first drive's -0.4 m.
  EXPECT_NEAR(at_aligned, mean.y(), 0.11);
  // Aligned, it is as sharp as one traversal's; merged as they came, it is spread over the offsets.
  EXPECT_LT(spread_aligned, spread_one + 0.05);
  EXPECT_GT(spread_blurred, 2.5 * spread_aligned);
}

TEST(BevAlign, ATraversalWeighsByItsFrames) {
  BevGrid fused = traversal({0.0, 0.0}, 20);                                   // 30 frames at 0
  const Alignment a = mergeAligned(traversal({0.0, 0.8}, 21, true, 0, 60, 90), fused, true);  // 90 at +0.8 m
  ASSERT_TRUE(a.ok) << a.why;
  EXPECT_NEAR(a.shift_m.y(), -0.8, 0.101);
  EXPECT_EQ(fused.frames(), 120);
  EXPECT_NEAR(solidLine(fused).first, 0.6, 0.11);  // (30 x 0 + 90 x 0.8) / 120
}

TEST(BevAlign, TheFirstTraversalIsTakenAsItIs) {
  BevGrid fused;
  const BevGrid t = traversal({0.7, 0.7}, 5);
  const Alignment a = mergeAligned(t, fused, true);
  EXPECT_FALSE(a.ok);
  EXPECT_EQ(fused.frames(), t.frames());
  EXPECT_EQ(fused.merges(), 0) << "the first traversal is no merge";
  EXPECT_NEAR(solidLine(fused).first, 0.7, 0.051);
}

}  // namespace
}  // namespace lanemap::bev
