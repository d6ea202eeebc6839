// Paints a BevGrid from a hand-made lane layout, for the lane-exploration tests: a reference curve
// (straight or a circular arc) with lines, curbs, drivable areas and blocked boxes given as
// functions of arc length s and lateral offset d (left positive). Observed counts ~10 per cell
// with noise; markings are painted 0.15 m wide, dashes 3 m every 9 m as in the simulator.
#pragma once

#include "core/bev/bev_grid.h"

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace lanemap::lanes::testing {

using Fn = std::function<double(double)>;
inline Fn constant(double v) { return [v](double) { return v; }; }
// v0 before s0, v1 after s1, smooth in between.
inline Fn ramp(double s0, double s1, double v0, double v1) {
  return [=](double s) {
    const double t = std::clamp((s - s0) / (s1 - s0), 0.0, 1.0);
    return v0 + (v1 - v0) * t * t * (3 - 2 * t);
  };
}

struct Reference {
  // Straight: from origin along heading. Arc: radius > 0 turns left, < 0 right.
  Eigen::Vector2d origin = Eigen::Vector2d(1000.0, 2000.0);
  double heading = 0.3;
  double radius = 0.0;  // 0 = straight
  double length = 200.0;

  Eigen::Vector2d at(double s, double d) const {
    const Eigen::Vector2d t(std::cos(heading), std::sin(heading)), n(-t.y(), t.x());
    if (radius == 0.0) return origin + s * t + d * n;
    const Eigen::Vector2d c = origin + radius * n;
    const double a = s / radius;
    const Eigen::Vector2d r0 = origin - c;  // from centre to start
    const Eigen::Vector2d ra(std::cos(a) * r0.x() - std::sin(a) * r0.y(), std::sin(a) * r0.x() + std::cos(a) * r0.y());
    return c + ra * (1.0 - d / radius);
  }
  Eigen::Vector2d toSD(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d t(std::cos(heading), std::sin(heading)), n(-t.y(), t.x());
    if (radius == 0.0) return Eigen::Vector2d((p - origin).dot(t), (p - origin).dot(n));
    const Eigen::Vector2d c = origin + radius * n;
    const Eigen::Vector2d r0 = origin - c, rp = p - c;
    const double a = std::atan2(r0.x() * rp.y() - r0.y() * rp.x(), r0.dot(rp));
    return Eigen::Vector2d(a * radius, radius - (radius > 0 ? 1.0 : -1.0) * rp.norm());
  }
  std::vector<Eigen::Vector2d> polyline(double vertex_spacing = 10.0) const {
    std::vector<Eigen::Vector2d> out;
    const int n = std::max(1, static_cast<int>(std::ceil(length / vertex_spacing)));
    for (int i = 0; i <= n; ++i) out.push_back(at(length * i / n, 0.0));
    return out;
  }
};

struct Line {
  Fn d;
  double s0 = -1e9, s1 = 1e9;
  enum Kind { kDashed, kSolid, kCurb, kSeparationOnly } kind = kDashed;
  bool separation = true;  // also a lane separation (between two lanes)
};
struct Area {  // drivable between dlo(s) and dhi(s)
  Fn dlo, dhi;
  double s0 = -1e9, s1 = 1e9;
};
struct Box {  // observed, not drivable (a parked car)
  double s0, s1, d0, d1;
};
struct Speckles {  // cells labelled dashed line at random (a far line smeared by the projection)
  double s0, s1, d0, d1;
  double share;     // of the cells
};

struct FarGround {  // drivable ground seen far off: 2-4 observations per cell, some of them noise
  double s0, s1, d0, d1;
  double dashed_share;      // of the cells: one of the observations labelled dashed line
  double seen_once_share;   // of the cells: a single observation, background (nothing labelled)
};

struct Layout {
  Reference ref;
  std::vector<Line> lines;
  std::vector<Area> areas;
  std::vector<Box> boxes;
  std::vector<Speckles> speckles;
  std::vector<FarGround> far;  // painted instead of everything else where it lies
  double observed_half_width = 14.0;
  double observed_s0 = -1e9;  // nothing observed before this s (a road first seen this far in)
  double drivable_share = 1.0;  // of a drivable cell's observations, the share labelled drivable
                                // (the rest: background, as frames taken inside a junction label it)
  uint64_t seed = 3;
};

inline bev::BevGrid paint(const Layout& L) {
  bev::BevGrid g;
  const double res = g.resolution();
  std::mt19937_64 rng(L.seed);
  std::uniform_int_distribution<int> obsN(8, 12);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  // Bounding box of the corridor.
  Eigen::AlignedBox2d box;
  for (double s = -2; s <= L.ref.length + 2; s += 1.0) {
    box.extend(L.ref.at(s, L.observed_half_width + 1));
    box.extend(L.ref.at(s, -L.observed_half_width - 1));
  }
  const auto c0 = g.cellOf(box.min()), c1 = g.cellOf(box.max());
  for (int i = c0.x(); i <= c1.x(); ++i) {
    for (int j = c0.y(); j <= c1.y(); ++j) {
      const bev::BevGrid::Cell cell(i, j);
      const Eigen::Vector2d sd = L.ref.toSD(g.cellCentre(cell));
      const double s = sd.x(), d = sd.y();
      if (s < 0 || s > L.ref.length || s < L.observed_s0 || std::abs(d) > L.observed_half_width) continue;
      const FarGround* far = nullptr;
      for (const FarGround& f : L.far) {
        if (s >= f.s0 && s <= f.s1 && d >= f.d0 && d <= f.d1) far = &f;
      }
      if (far) {
        if (U(rng) < far->seen_once_share) {
          g.add(cell, bev::Layer::kObserved, 1);
          continue;
        }
        const int n = 2 + static_cast<int>(U(rng) * 3);
        const bool dash = U(rng) < far->dashed_share;
        g.add(cell, bev::Layer::kObserved, n);
        g.add(cell, bev::Layer::kDrivable, n - dash);
        if (dash) g.add(cell, bev::Layer::kDashedLine, 1);
        continue;
      }
      const int obs = obsN(rng);
      g.add(cell, bev::Layer::kObserved, obs);
      bool blocked = false;
      for (const Box& b : L.boxes) blocked |= s >= b.s0 && s <= b.s1 && d >= b.d0 && d <= b.d1;
      if (blocked) continue;
      bool marked = false;
      for (const Line& ln : L.lines) {
        if (s < ln.s0 || s > ln.s1) continue;
        const double e = std::abs(d - ln.d(s));
        if (ln.separation && e <= res * 0.75) g.add(cell, bev::Layer::kLaneSeparation, obs - (U(rng) < 0.2));
        if (ln.kind == Line::kCurb && e <= 0.15) {
          g.add(cell, bev::Layer::kCurb, obs);
          marked = true;
        } else if (ln.kind == Line::kSolid && e <= 0.075 + res / 2) {
          g.add(cell, bev::Layer::kSolidLine, obs - (U(rng) < 0.3));
          marked = true;
        } else if (ln.kind == Line::kDashed && e <= 0.075 + res / 2 && std::fmod(s - ln.s0, 9.0) < 3.0) {
          g.add(cell, bev::Layer::kDashedLine, obs - (U(rng) < 0.3));
          marked = true;
        }
      }
      for (const Speckles& sp : L.speckles) {
        if (s >= sp.s0 && s <= sp.s1 && d >= sp.d0 && d <= sp.d1 && U(rng) < sp.share) {
          g.add(cell, bev::Layer::kDashedLine, obs);
          marked = true;
        }
      }
      if (marked) continue;
      bool drivable = false;
      for (const Area& a : L.areas) drivable |= s >= a.s0 && s <= a.s1 && d >= a.dlo(s) && d <= a.dhi(s);
      if (drivable) {
        const int seen = static_cast<int>(std::lround(obs * L.drivable_share));
        g.add(cell, bev::Layer::kDrivable, std::max(0, seen - static_cast<int>(U(rng) * 3)));  // a few misses
      }
      // Segmentation noise: a rare spurious marking count, well below the thresholds.
      if (U(rng) < 0.02) g.add(cell, bev::Layer::kDashedLine, 1);
    }
  }
  return g;
}

}  // namespace lanemap::lanes::testing
