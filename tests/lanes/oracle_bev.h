// An "oracle" BEV grid of one atomic road painted from the simulator world's truth, as a perfect
// camera -> segmentation -> BEV chain would accumulate it: every cell centre of the road's corridor
// within `observed_m` of the road's centre line is observed 10 times; lane asphalt (either
// direction) is drivable, paint and curbs go to their layers, and a cell whose lanelet differs
// from a neighbour's in another lane of the cross-section is a lane separation. Parking, bike
// lanes, sidewalks, intersections: observed, not drivable.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/lanes/frenet.h"
#include "core/sim/world.h"
#include "core/skeleton/skeleton.h"

#include <cmath>

namespace lanemap::lanes::testing {

inline bev::BevGrid paintOracle(const sim::World& world, const skeleton::AtomicRoad& road, double observed_m = 25.0) {
  bev::BevGrid g;
  const FrenetFrame frame(road.polyline, 0.5, 0.0);
  Eigen::AlignedBox2d box;
  for (const auto& p : road.polyline) {
    box.extend(p - Eigen::Vector2d::Constant(observed_m + 1));
    box.extend(p + Eigen::Vector2d::Constant(observed_m + 1));
  }
  const auto c0 = g.cellOf(box.min()), c1 = g.cellOf(box.max());
  const int nx = c1.x() - c0.x() + 1, ny = c1.y() - c0.y() + 1;
  // Pass 1: the observed cells (swept in the road's frame), and their truth sample.
  std::vector<sim::GroundSample> gs(static_cast<size_t>(nx) * ny);
  std::vector<uint8_t> seen(gs.size(), 0);
  const double step = 0.4 * g.resolution();
  for (double s = 0.0; s <= frame.length(); s += step) {
    const Eigen::Vector2d p0 = frame.point(s), nrm = frame.normal(s);
    for (double d = -observed_m; d <= observed_m; d += step) {
      const auto c = g.cellOf(p0 + d * nrm);
      const int i = c.x() - c0.x(), j = c.y() - c0.y();
      if (i >= 0 && j >= 0 && i < nx && j < ny) seen[static_cast<size_t>(j) * nx + i] = 1;
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const size_t k = static_cast<size_t>(j) * nx + i;
      if (!seen[k]) continue;
      const Eigen::Vector2d p = g.cellCentre(bev::BevGrid::Cell(c0.x() + i, c0.y() + j));
      gs[k] = world.sample(p.x(), p.y());
    }
  }
  const uint16_t n = 10;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const size_t k = static_cast<size_t>(j) * nx + i;
      if (!seen[k]) continue;
      const bev::BevGrid::Cell cell(c0.x() + i, c0.y() + j);
      g.add(cell, bev::Layer::kObserved, n);
      const sim::GroundSample& s = gs[k];
      switch (s.surface) {
        case sim::Surface::kAsphalt: if (s.lanelet >= 0) g.add(cell, bev::Layer::kDrivable, n); break;
        case sim::Surface::kDashedPaint: g.add(cell, bev::Layer::kDashedLine, n); break;
        case sim::Surface::kSolidPaint: g.add(cell, bev::Layer::kSolidLine, n); break;
        case sim::Surface::kCrosswalkPaint: g.add(cell, bev::Layer::kCrosswalk, n); break;
        case sim::Surface::kStopLinePaint: g.add(cell, bev::Layer::kStopLine, n); break;
        case sim::Surface::kCurb: g.add(cell, bev::Layer::kCurb, n); break;
        default: break;
      }
      if (s.lanelet < 0) continue;
      bool sep = false;
      for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        const int ii = i + di, jj = j + dj;
        if (ii < 0 || jj < 0 || ii >= nx || jj >= ny) continue;
        const size_t q = static_cast<size_t>(jj) * nx + ii;
        if (!seen[q] || gs[q].lanelet < 0 || gs[q].lanelet == s.lanelet) continue;
        const auto off = world.laneOffset(s.lanelet, gs[q].lanelet);
        sep |= off && *off != 0;
      }
      if (sep) g.add(cell, bev::Layer::kLaneSeparation, n);
    }
  }
  return g;
}

}  // namespace lanemap::lanes::testing
