// Each drive's offset estimated jointly over the roads drives share (core/bev/drive_offsets.h):
// synthetic roads (tests/bev/synthetic_road.h) seen by drives whose poses carry known offsets.
#include "core/bev/drive_offsets.h"

#include "tests/bev/synthetic_road.h"

#include <gtest/gtest.h>

#include <map>

namespace lanemap::bev {
namespace {

using testing::solidLine;
using testing::traversal;

// Road k: the synthetic road over east k*100 .. k*100+60 m (the same lines, another place).
BevGrid road(int k, const Eigen::Vector2d& offset, uint32_t seed) { return traversal(offset, seed, true, 100.0 * k, 100.0 * k + 60.0); }

TEST(DriveOffsets, OffsetsOfDrivesLinkedByTheirRoadsComeOutAroundTheirMean) {
  // Drives 0-3 carry these offsets. Roads: 0 by drives 0 and 1, 1 by drives 1 and 2, 2 by drives
  // 2 and 3 and 0 (a chain closed by road 2). Drive 4 shares no road with any: it stays as it is.
  const std::vector<Eigen::Vector2d> truth = {{0.6, -0.4}, {-0.3, 0.5}, {0.2, 0.3}, {-0.5, -0.6}, {0.7, 0.7}};
  const std::map<int, std::vector<size_t>> roads = {{0, {0, 1}}, {1, {1, 2}}, {2, {2, 3, 0}}, {3, {4}}};
  DriveOffsetSolver solver(truth.size());
  uint32_t seed = 1;
  for (const auto& [k, drives] : roads) {
    std::vector<BevGrid> grids;
    for (size_t d : drives) grids.push_back(road(k, truth[d], seed++));
    std::vector<std::pair<size_t, const BevGrid*>> in;
    for (size_t i = 0; i < drives.size(); ++i) in.push_back({drives[i], &grids[i]});
    EXPECT_EQ(solver.addRoad(in), static_cast<int>(drives.size() * (drives.size() - 1) / 2)) << "road " << k;
  }
  const DriveOffsets o = solver.solve();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (size_t d = 0; d < 4; ++d) mean += truth[d] / 4.0;
  for (size_t d = 0; d < 4; ++d) {
    // Each offset relative to the linked drives' mean, to a cell or so (the shifts are whole cells).
    EXPECT_NEAR(o.offset_m[d].x(), truth[d].x() - mean.x(), 0.08) << "drive " << d;
    EXPECT_NEAR(o.offset_m[d].y(), truth[d].y() - mean.y(), 0.08) << "drive " << d;
    EXPECT_GT(o.measurements[d], 0);
    EXPECT_EQ(o.component[d], o.component[0]);
  }
  EXPECT_EQ(o.measurements[4], 0);
  EXPECT_NE(o.component[4], o.component[0]);
  EXPECT_EQ(o.offset_m[4], Eigen::Vector2d::Zero());

  // A road only drive 0 saw, moved by drive 0's correction: its solid line (truly at north 0) lies
  // where the linked drives' mean puts it, to a cell, where uncorrected it lay 0.4 m off.
  const BevGrid alone = road(5, truth[0], 99);
  const BevGrid corrected = shiftedGrid(alone, correctionCells(o.offset_m[0], alone.resolution()));
  const auto line = [](const BevGrid& g) {  // the solid line at north 0 of road 5 (east 500..560)
    double w = 0, m = 0;
    for (double x = 510; x < 550; x += g.resolution()) {
      for (double y = -1.2; y < 1.2; y += g.resolution()) {
        const auto c = g.cellOf(Eigen::Vector2d(x, y));
        w += g.count(c, Layer::kSolidLine);
        m += g.count(c, Layer::kSolidLine) * g.cellCentre(c).y();
      }
    }
    return m / w;
  };
  EXPECT_NEAR(line(alone), truth[0].y(), 0.06);
  EXPECT_NEAR(line(corrected), mean.y(), 0.11);
}

TEST(DriveOffsets, NoSharedRoadNoMeasurementNoOffset) {
  DriveOffsetSolver solver(3);
  const BevGrid a = road(0, {0.4, 0.4}, 1), b = road(1, {-0.4, 0.2}, 2);
  // Two drives on roads that do not overlap: no trusted pair.
  EXPECT_EQ(solver.addRoad({{0, &a}, {1, &b}}), 0);
  const DriveOffsets o = solver.solve();
  for (size_t d = 0; d < 3; ++d) {
    EXPECT_EQ(o.offset_m[d], Eigen::Vector2d::Zero());
    EXPECT_EQ(o.measurements[d], 0);
    EXPECT_EQ(correctionCells(o.offset_m[d], 0.1), Eigen::Vector2i::Zero());
  }
  EXPECT_THROW(solver.addRoad({{0, &a}, {0, &b}}), std::invalid_argument);
  EXPECT_THROW(solver.addRoad({{0, &a}, {3, &b}}), std::invalid_argument);
}

}  // namespace
}  // namespace lanemap::bev
