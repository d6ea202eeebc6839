// Test helper: a synthetic two-lane road's BEV as seen by a traversal whose poses carry a known
// offset (tests/bev/bev_align_test.cc, store_align_test.cc).
#pragma once

#include "core/bev/bev_grid.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

namespace lanemap::bev::testing {

// A 60 m road along east: curbs at north -1.0 and 8.0 m, solid lines at 0 and 7 m, a dashed line
// (3 m dash, 6 m gap) at 3.5 m; observed over north -3..10 m. The traversal's evidence lands
// `offset` away from the truth (its pose error); each line cell is seen with probability 0.8, and
// 2 % of the other cells are false line hits. `lines` false: no line at all (a featureless road).
// `yaw_rad`: the evidence is also turned by it (counter-clockwise) about the road's middle (30, 3.5).
inline BevGrid traversal(const Eigen::Vector2d& offset, uint32_t seed, bool lines = true, double x0 = 0, double x1 = 60,
                  int frames_in_grid = 30, double yaw_rad = 0.0) {
  BevGrid g;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double res = g.resolution();
  for (double x = x0; x < x1; x += res) {
    for (double y = -3.0; y < 10.0; y += res) {
      const double xc = x + res / 2, yc = y + res / 2;
      const Eigen::Vector2d mid(30.0, 3.5);
      const auto cell = g.cellOf(Eigen::Rotation2Dd(yaw_rad) * (Eigen::Vector2d(xc, yc) - mid) + mid + offset);
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
  for (int f = 0; f < frames_in_grid; ++f) g.addFrame();
  return g;
}

// Where the solid line at north 0 is in `g`, and how spread its evidence is (metres): the mean
// and standard deviation of north over the cells of north -0.8..0.8 (east x0..x1) weighted by
// solid-line counts.
inline std::pair<double, double> solidLine(const BevGrid& g, double x0 = 10, double x1 = 50) {
  double w = 0, m = 0, m2 = 0;
  for (double x = x0; x < x1; x += g.resolution()) {
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

}  // namespace lanemap::bev::testing
