// Hand-made lane maps for the evaluation tests (see eval_test.cc for the network).
#pragma once

#include "core/eval/geometry.h"
#include "core/intersections/curve.h"
#include "core/map/lane_map.h"

#include <algorithm>
#include <cmath>

namespace lanemap::testing {

using Eigen::Vector2d;
using lanemap::eval::Polyline;
using lanemap::map::LaneMap;

constexpr double kW = 3.5;

inline Polyline straight(Vector2d a, Vector2d b, double step = 2.0) {
  const int n = std::max(2, static_cast<int>(std::ceil((b - a).norm() / step)) + 1);
  Polyline out;
  for (int i = 0; i < n; ++i) out.push_back(a + (b - a) * (static_cast<double>(i) / (n - 1)));
  return out;
}

struct MapBuilder {
  LaneMap m;
  int64_t next = 1;
  // A lanelet along `centre` with bounds offset by +-w/2 (normals from neighbouring points).
  int64_t lane(const Polyline& centre, int64_t road_id, bool intersection = false, double w = kW) {
    lanemap::map::LineString left, right;
    lanemap::map::Lanelet ll;
    left.id = next++;
    right.id = next++;
    ll.id = next++;
    left.type = right.type = intersection ? lanemap::map::LineType::kVirtual : lanemap::map::LineType::kDashed;
    for (size_t i = 0; i < centre.size(); ++i) {
      const size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, centre.size() - 1);
      const Vector2d t = (centre[b] - centre[a]).normalized(), nl(-t.y(), t.x());
      const Vector2d l = centre[i] + w / 2 * nl, r = centre[i] - w / 2 * nl;
      ll.centre.emplace_back(centre[i].x(), centre[i].y(), 0.0);
      left.points.emplace_back(l.x(), l.y(), 0.0);
      right.points.emplace_back(r.x(), r.y(), 0.0);
    }
    ll.left_id = left.id;
    ll.right_id = right.id;
    ll.kind = intersection ? lanemap::map::LaneletKind::kIntersection : lanemap::map::LaneletKind::kRoad;
    if (!intersection) {
      ll.road_id = road_id;
      ll.from_node = road_id * 10;
      ll.to_node = road_id * 10 + 10;
    } else {
      ll.intersection_id = 20;
    }
    m.lines.push_back(left);
    m.lines.push_back(right);
    m.lanelets.push_back(ll);
    return ll.id;
  }
  void link(int64_t a, int64_t b) {
    for (auto& ll : m.lanelets) {
      if (ll.id == a) ll.successors.push_back(b);
    }
  }
  void connect(int64_t a, int64_t b) {
    const auto* la = m.lanelet(a);
    const auto* lb = m.lanelet(b);
    const Vector2d p0 = la->centre.back().head<2>(), p2 = lb->centre.front().head<2>();
    const Vector2d t0 = (p0 - la->centre[la->centre.size() - 2].head<2>()).normalized();
    const Vector2d t2 = (lb->centre[1].head<2>() - p2).normalized();
    const auto curve = lanemap::intersections::bezierConnection(p0, t0, p2, t2);
    const int64_t ids[4] = {la->left_id, la->right_id, lb->left_id, lb->right_id};
    const int64_t x = lane(curve.sample(0.5), -1, true);  // (la, lb invalid from here)
    // Successors share end points (Lanelet2 finds them so in a file): snap the bounds' ends.
    const auto* lx = m.lanelet(x);
    Eigen::Vector3d ends[4];
    for (int k = 0; k < 4; ++k) ends[k] = k < 2 ? m.line(ids[k])->points.back() : m.line(ids[k])->points.front();
    for (auto& l : m.lines) {
      if (l.id == lx->left_id) {
        l.points.front() = ends[0];
        l.points.back() = ends[2];
      } else if (l.id == lx->right_id) {
        l.points.front() = ends[1];
        l.points.back() = ends[3];
      }
    }
    link(a, x);
    link(x, b);
  }
};

// Options of the test network.
struct Net {
  double a1_shift = 0.0;  // A1 moved to the right by this
  bool drop_b1 = false;
  bool wrong_connection = false;  // A1 -> C0 instead of A1 -> B1
  bool split_b0 = false;          // B0 in three pieces
  bool split_c0 = false;          // C0 in two pieces
};

inline LaneMap network(const Net& o) {
  MapBuilder b;
  const int64_t a0 = b.lane(straight({-100, -1.75}, {-10, -1.75}), 1);
  const int64_t a1 = b.lane(straight({-100, -5.25 - o.a1_shift}, {-10, -5.25 - o.a1_shift}), 1);
  int64_t b0 = -1, b0_first = -1;
  if (o.split_b0) {
    b0_first = b.lane(straight({10, -1.75}, {40, -1.75}), 2);
    const int64_t mid = b.lane(straight({40, -1.75}, {70, -1.75}), 2);
    const int64_t last = b.lane(straight({70, -1.75}, {100, -1.75}), 2);
    b.link(b0_first, mid);
    b.link(mid, last);
    b0 = b0_first;
  } else {
    b0 = b.lane(straight({10, -1.75}, {100, -1.75}), 2);
  }
  const int64_t b1 = o.drop_b1 ? -1 : b.lane(straight({10, -5.25}, {100, -5.25}), 2);
  int64_t c0 = -1;
  if (o.split_c0) {
    c0 = b.lane(straight({1.75, 10}, {1.75, 50}), 3);
    const int64_t c0b = b.lane(straight({1.75, 50}, {1.75, 100}), 3);
    b.link(c0, c0b);
  } else {
    c0 = b.lane(straight({1.75, 10}, {1.75, 100}), 3);
  }
  b.connect(a0, b0);
  if (o.wrong_connection) {
    b.connect(a1, c0);
  } else if (b1 >= 0) {
    b.connect(a1, b1);
  }
  b.connect(a0, c0);
  return b.m;
}

inline Net with(void (*f)(Net&)) {
  Net n;
  f(n);
  return n;
}

}  // namespace lanemap::testing
