// Traversal alignment before a merge (core/bev/bev_align.h): a synthetic two-lane road seen by
// traversals whose poses carry known offsets.
#include "core/bev/bev_align.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lanemap::bev {
namespace {

// A 60 m road along east: curbs at north -1.0 and 8.0 m, solid lines at 0 and 7 m, a dashed line
// (3 m dash, 6 m gap) at 3.5 m; observed over north -3..10 m. The traversal's evidence lands
// `offset` away from the truth (its pose error); each line cell is seen with probability 0.8, and
// 2 % of the other cells are false line hits. `lines` false: no line at all (a featureless road).
BevGrid traversal(const Eigen::Vector2d& offset, uint32_t seed, bool lines = true, double x0 = 0, double x1 = 60) {
  BevGrid g;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double res = g.resolution();
  for (double x = x0; x < x1; x += res) {
    for (double y = -3.0; y < 10.0; y += res) {
      const double xc = x + res / 2, yc = y + res / 2;
      const auto cell = g.cellOf(Eigen::Vector2d(xc, yc) + offset);
      const int frames = 3;
      g.add(cell, Layer::kObserved, frames);
      if (yc > 0 && yc < 7) g.add(cell, Layer::kDrivable, frames);
      auto near = [&](double at) { return std::abs(yc - at) < 0.075; };
      Layer line = Layer::kCount;
      if (lines && (near(-1.0) || near(8.0))) line = Layer::kCurb;
      if (lines && (near(0.0) || near(7.0))) line = Layer::kSolidLine;
      if (lines && near(3.5) && std::fmod(xc, 9.0) < 3.0) line = Layer::kDashedLine;
      for (int f = 0; f < frames; ++f) {
        if (line != Layer::kCount && u(rng) < 0.8) g.add(cell, line);
        if (line == Layer::kCount && u(rng) < 0.02) g.add(cell, Layer::kLaneSeparation);
      }
    }
  }
  for (int f = 0; f < 30; ++f) g.addFrame();
  return g;
}

// Where the solid line at north 0 is in `g`, and how spread its evidence is (metres): the mean
// and standard deviation of north over the cells of north -0.8..0.8 weighted by solid-line counts.
std::pair<double, double> solidLine(const BevGrid& g) {
  double w = 0, m = 0, m2 = 0;
  for (double x = 10; x < 50; x += g.resolution()) {
    for (double y = -0.8; y < 0.8; y += g.resolution()) {
      const auto cell = g.cellOf(Eigen::Vector2d(x, y));
      const double n = g.count(cell, Layer::kSolidLine);
      const double yc = g.cellCentre(cell).y();
      w += n;
      m += n * yc;
      m2 += n * yc * yc;
    }
  }
  const double mean = m / w;
  return {mean, std::sqrt(std::max(0.0, m2 / w - mean * mean))};
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
    const Alignment a = mergeAligned(t, aligned, static_cast<int>(i), true);
    mergeAligned(t, blurred, static_cast<int>(i), false);
    if (i > 0) {
      EXPECT_TRUE(a.ok) << i << ": " << a.why;
    }
    mean += offsets[i] / static_cast<double>(offsets.size());
  }
  EXPECT_EQ(aligned.frames(), 4 * 30);
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

TEST(BevAlign, TheFirstTraversalIsTakenAsItIs) {
  BevGrid fused;
  const BevGrid t = traversal({0.7, 0.7}, 5);
  const Alignment a = mergeAligned(t, fused, 0, true);
  EXPECT_FALSE(a.ok);
  EXPECT_EQ(fused.frames(), t.frames());
  EXPECT_NEAR(solidLine(fused).first, 0.7, 0.051);
}

}  // namespace
}  // namespace lanemap::bev
