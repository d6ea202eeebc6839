// Traversal alignment before a merge (core/bev/bev_align.h): a synthetic two-lane road seen by
// traversals whose poses carry known offsets.
#include "core/bev/bev_align.h"

#include "tests/bev/synthetic_road.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

namespace lanemap::bev {
namespace {

using testing::solidLine;
using testing::traversal;

constexpr double kDeg = M_PI / 180.0;

AlignOptions withRotation() {
  AlignOptions o;
  o.max_rotation_deg = AlignOptions::kRotationSearchDeg;
  return o;
}

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
    // With the rotation searched: none where there is none, the same shift.
    const Alignment turned = estimateShift(ref, t, withRotation());
    ASSERT_TRUE(turned.ok) << turned.why;
    EXPECT_EQ(turned.rotation_rad, 0.0) << off.transpose();
    EXPECT_EQ(turned.shift_cells, a.shift_cells) << off.transpose();
  }
}

TEST(BevAlign, FindsASmallRotationAndTurnsTheTraversalBack) {
  const BevGrid ref = traversal({0.0, 0.0}, 1);
  for (const double deg : {0.3, -0.4}) {
    const Eigen::Vector2d off(0.3, -0.2);
    const BevGrid t = traversal(off, 2, true, 0, 60, 30, deg * kDeg);
    const Alignment a = estimateShift(ref, t, withRotation());
    ASSERT_TRUE(a.ok) << a.why;
    EXPECT_NEAR(a.rotation_rad, -deg * kDeg, 0.1 * kDeg + 1e-9) << deg;
    // Turned about the middle of the evidence, the shift is the offset there.
    EXPECT_NEAR(a.shift_m.x(), -off.x(), 0.101) << deg;
    EXPECT_NEAR(a.shift_m.y(), -off.y(), 0.101) << deg;
    // Moved back, the solid line lies where the reference's does at both ends of the road (the
    // turn moved it 0.1-0.14 m there, in opposite directions).
    const BevGrid moved = movedGrid(t, a.move());
    for (const auto& [x0, x1] : {std::pair{2.0, 12.0}, std::pair{48.0, 58.0}}) {
      EXPECT_NEAR(solidLine(moved, x0, x1).first, solidLine(ref, x0, x1).first, 0.051) << deg << " at " << x0;
    }
    // Shift only (the default): one end at least stays off.
    const Alignment s = estimateShift(ref, t);
    ASSERT_TRUE(s.ok) << s.why;
    EXPECT_EQ(s.rotation_rad, 0.0);
    const BevGrid shifted = shiftedGrid(t, s.shift_cells);
    EXPECT_GT(std::max(std::abs(solidLine(shifted, 2, 12).first - solidLine(ref, 2, 12).first),
                       std::abs(solidLine(shifted, 48, 58).first - solidLine(ref, 48, 58).first)),
              0.07)
        << deg;
  }
}

TEST(BevAlign, ACellMoveKeepsEveryCount) {
  const BevGrid g = traversal({0.0, 0.0}, 3);
  const CellMove move{{2, -1}, 0.6 * kDeg, {300, 35}};
  // A cell 300 cells east of the pivot moves 300 sin(0.6 deg) = 3.1 -> 3 cells north, then the shift.
  EXPECT_EQ(move.apply({600, 35}), Eigen::Vector2i(602, 37));
  EXPECT_EQ(move.apply({300, 35}), Eigen::Vector2i(302, 34));
  const BevGrid moved = movedGrid(g, move);
  const auto totals = [](const BevGrid& grid) {
    std::array<uint64_t, kNumLayers + 1> sum{};  // per layer, and the cells observed
    const int t = grid.options().tile_cells;
    grid.forEachTile([&](const BevGrid::Cell&, const uint16_t* counts) {
      for (int l = 0; l < kNumLayers; ++l) {
        for (int i = 0; i < t * t; ++i) sum[l] += counts[static_cast<size_t>(l) * t * t + i];
      }
      for (int i = 0; i < t * t; ++i) sum[kNumLayers] += counts[i] > 0;
    });
    return sum;
  };
  // One cell to one cell: every count kept, as many cells observed (no two cells fell on one).
  EXPECT_EQ(totals(moved), totals(g));
  EXPECT_EQ(moved.frames(), g.frames());
}

TEST(BevAlign, TurnedTraversalsFuseOnTheirMean) {
  BevGrid aligned, blurred;
  for (const auto& [deg, seed] : {std::pair{0.2, 30u}, std::pair{-0.2, 31u}}) {
    const BevGrid t = traversal({0.0, 0.0}, seed, true, 0, 60, 30, deg * kDeg);
    mergeAligned(t, aligned, true, withRotation());
    mergeAligned(t, blurred, false);
  }
  const double spread_one = solidLine(traversal({0, 0}, 99), 2, 12).second;
  for (const auto& [x0, x1] : {std::pair{2.0, 12.0}, std::pair{48.0, 58.0}}) {
    // At the mean of the two turns (none), as sharp as one traversal's line; unaligned, the two
    // lines lie 0.2 m apart at each end.
    EXPECT_NEAR(solidLine(aligned, x0, x1).first, 0.0, 0.051) << x0;
    EXPECT_LT(solidLine(aligned, x0, x1).second, spread_one + 0.03) << x0;
    EXPECT_GT(solidLine(blurred, x0, x1).second, spread_one + 0.05) << x0;
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
