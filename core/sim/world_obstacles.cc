// The world's obstacles: parked cars (parking lanes, bus bays) and buildings, kept clear of the
// roads. Part of buildWorld (core/sim/world_build.h).
#include "core/sim/world_build.h"

namespace lanemap::sim::world_build {

void Builder::indexZones() {
  for (const auto& xs : xss_) {
    const auto samples = xs.line.samplesBetween(xs.sb, xs.se);
    for (size_t i = 0; i + 1 < samples.size(); ++i) {
      ZoneSeg z;
      z.a = xs.line.pointAt(samples[i]);
      z.b = xs.line.pointAt(samples[i + 1]);
      z.left = std::max(0.0, xs.left_extent);
      z.right = std::max(0.0, -xs.right_extent);
      z.xs = xs.key;
      const double ext = std::max(z.left, z.right) + 1.0;
      Eigen::AlignedBox2d box;
      box.extend(z.a);
      box.extend(z.b);
      const uint32_t idx = static_cast<uint32_t>(zones_.size());
      zones_.push_back(z);
      forCells(box.min() - Vector2d(ext, ext), box.max() + Vector2d(ext, ext), [&](int64_t key) { zone_grid_[key].push_back(idx); });
    }
  }
}

bool Builder::clearOfRoads(const geom::Rect& r, int64_t skip_xs, double margin) const {
  const bool clear_of_roads = noneBlocks(zone_grid_, r, [&](uint32_t idx) {
    const ZoneSeg& z = zones_[idx];
    if (z.xs == skip_xs) return false;
    const double side = geom::cross(z.b - z.a, r.c - z.a);
    const double need = (side > 0 ? z.left : z.right) + margin;
    return geom::rectSegmentDistance(r, z.a, z.b) < need;
  });
  if (!clear_of_roads) return false;
  const auto k = r.corners();
  return noneBlocks(circle_grid_, r, [&](uint32_t idx) {
    const Circle& c = zones_circles_[idx];
    double d = r.contains(c.c) ? 0.0 : 1e300;
    for (int i = 0; i < 4; ++i) d = std::min(d, geom::pointSegmentDistance(c.c, k[i], k[(i + 1) % 4]));
    return d < c.r + margin;
  });
}

bool Builder::clearOfBuildings(const geom::Rect& r) const {
  return noneBlocks(building_grid_, r, [&](uint32_t idx) { return geom::rectsOverlap(building_rects_[idx], r); });
}

void Builder::addBuildingRect(const geom::Rect& r) {
  Eigen::AlignedBox2d box;
  for (const auto& c : r.corners()) box.extend(c);
  const uint32_t idx = static_cast<uint32_t>(building_rects_.size());
  building_rects_.push_back(r);
  forCells(box.min(), box.max(), [&](int64_t key) { building_grid_[key].push_back(idx); });
}

Eigen::Vector3f Builder::randomColour(std::mt19937_64& r, bool car) {
  if (car) {
    static const float palette[][3] = {{0.8f, 0.1f, 0.1f}, {0.1f, 0.2f, 0.7f}, {0.9f, 0.9f, 0.9f},
                                       {0.1f, 0.1f, 0.1f}, {0.5f, 0.5f, 0.55f}, {0.2f, 0.5f, 0.2f}};
    const auto& c = palette[std::uniform_int_distribution<int>(0, 5)(r)];
    return Eigen::Vector3f(c[0], c[1], c[2]);
  }
  const float g = static_cast<float>(uni(r, 0.45, 0.85));
  return Eigen::Vector3f(g, static_cast<float>(g * uni(r, 0.85, 1.0)), static_cast<float>(g * uni(r, 0.75, 1.0)));
}

void Builder::placeObstacles() {
  indexZones();
  for (uint32_t i = 0; i < zones_circles_.size(); ++i) {
    const Circle& c = zones_circles_[i];
    const Vector2d e(c.r + 1.0, c.r + 1.0);
    forCells(c.c - e, c.c + e, [&](int64_t key) { circle_grid_[key].push_back(i); });
  }
  for (const auto& xs : xss_) {
    auto r = rngFor(o_.seed, xs.ref->id, 6);
    placeParkedCars(xs, r);
    placeBuildings(xs, r);
  }
}

void Builder::addCar(const CrossSection& xs, std::mt19937_64& r, const geom::Rect& rect, double s, double dcan) {
  Obstacle o;
  o.kind = Obstacle::Kind::kParkedCar;
  const double ground = terrainAt(rect.c) + profileAt(xs, s, m_ * dcan, 1e9, -1e9);
  o.centre = Vector3d(rect.c.x(), rect.c.y(), ground + 0.75);
  o.yaw = std::atan2(rect.axis.y(), rect.axis.x());
  o.half_extent = Vector3d(rect.hl, rect.hw, 0.75);
  o.colour = randomColour(r, true);
  impl_->obstacles.push_back(o);
  ++impl_->stats.parked_cars;
}

std::pair<int, int> Builder::edgeStripColumns(const Section& sec, int k, const Side& sd) const {
  int edge_col = -1, lane_col = -1;
  for (int c = 0; c < static_cast<int>(sec.cols.size()); ++c) {
    if (sec.cols[c].side != k) continue;
    if (sec.cols[c].kind == ColKind::kEdgeOuter) edge_col = c;
    if (sec.cols[c].kind == ColKind::kLaneOuter && sec.cols[c].lane + 1 == static_cast<int>(sd.lane_w.size())) lane_col = c;
  }
  return {edge_col, lane_col};
}

void Builder::placeBayCar(const CrossSection& xs, int k, std::mt19937_64& r) {
  const Side& sd = xs.side[k];
  if (!sd.bay || !chance(r, 0.5)) return;
  const double mid = (sd.bay_s0 + sd.bay_s1) / 2.0;
  const Section* sec = sectionContaining(xs, sd.bay_s0, sd.bay_s1);
  if (!sec) return;
  const auto v = columnValues(xs, *sec, mid);
  const auto [edge_col, lane_col] = edgeStripColumns(*sec, k, sd);
  if (edge_col < 0 || lane_col < 0) return;
  const double len = 4.6;
  if (xs.line.tangentAt(mid - len).dot(xs.line.tangentAt(mid + len)) < std::cos(5.0 * kPi / 180.0)) return;
  const double dmid = (v[edge_col] + v[lane_col]) / 2.0;
  geom::Rect rect;
  rect.c = at(xs, mid, dmid);
  rect.axis = xs.line.tangentAt(mid) * static_cast<double>(sd.dir);
  rect.hl = len / 2.0;
  rect.hw = 0.9;
  if (clearOfRoads(rect, xs.key, 0.2)) addCar(xs, r, rect, mid, dmid);
}

void Builder::placeParkedCars(const CrossSection& xs, std::mt19937_64& r) {
  for (int k = 0; k < 2; ++k) placeBayCar(xs, k, r);
  for (int k = 0; k < 2; ++k) {
    const Side& sd = xs.side[k];
    if (sd.edge != Edge::kParking) continue;
    const double lo = xs.sb + 6.0, hi = xs.se - 6.0;
    double s = lo + uni(r, 0.0, 3.0);
    while (true) {
      const double len = uni(r, 4.2, 4.9);
      if (s + len > hi) break;
      const double mid = s + len / 2.0;
      const Section* sec = sectionContaining(xs, s, s + len);
      // A straight car fits a curved strip only where the road bends little (< 5 deg over it).
      const bool straight = xs.line.tangentAt(s).dot(xs.line.tangentAt(s + len)) > std::cos(5.0 * kPi / 180.0);
      if (sec && straight && chance(r, o_.parked_car_occupancy)) {
        const auto v = columnValues(xs, *sec, mid);
        const auto [edge_col, lane_col] = edgeStripColumns(*sec, k, sd);
        // Nor where the strip shifts sideways (a turn pocket's taper).
        const auto va = columnValues(xs, *sec, s), vb = columnValues(xs, *sec, s + len);
        const bool steady = edge_col >= 0 && lane_col >= 0 &&
                            std::abs(va[edge_col] + va[lane_col] - v[edge_col] - v[lane_col]) < 0.1 &&
                            std::abs(vb[edge_col] + vb[lane_col] - v[edge_col] - v[lane_col]) < 0.1;
        if (steady) {
          const double dmid = (v[edge_col] + v[lane_col]) / 2.0;
          geom::Rect rect;
          rect.c = at(xs, mid, dmid);
          rect.axis = xs.line.tangentAt(mid) * static_cast<double>(sd.dir == 0 ? 1 : sd.dir);
          rect.hl = len / 2.0;
          rect.hw = 0.9;
          if (clearOfRoads(rect, xs.key, 0.2)) addCar(xs, r, rect, mid, dmid);
        }
      }
      s += len + uni(r, 0.8, 3.0);
    }
  }
}

void Builder::placeBuildings(const CrossSection& xs, std::mt19937_64& r) {
  const double L = xs.se - xs.sb;
  if (L < 12.0) return;
  for (int k = 0; k < 2; ++k) {
    // Actual side: +1 left of the reference line, -1 right.
    const double side = (k == 1 ? 1.0 : -1.0) * m_;
    const double extent = side > 0 ? xs.left_extent : -xs.right_extent;
    double s = xs.sb + 3.0 + uni(r, 0.0, 4.0);
    while (true) {
      const double len = uni(r, 8.0, 20.0);
      if (s + len > xs.se - 3.0) break;
      const double depth = uni(r, 8.0, 14.0);
      const double setback = uni(r, 1.5, 5.0);
      const double height = uni(r, 4.0, 18.0);
      if (chance(r, o_.p_building)) {
        const double mid = s + len / 2.0;
        const Vector2d t = xs.line.tangentAt(mid);
        geom::Rect rect;
        rect.axis = t;
        rect.hl = len / 2.0;
        rect.hw = depth / 2.0;
        rect.c = xs.line.offsetPoint(mid, side * (extent + setback + depth / 2.0));
        if (clearOfRoads(rect, -1, 0.5) && clearOfBuildings(rect)) {
          double ground = 1e300;
          for (const auto& c : rect.corners()) ground = std::min(ground, terrainAt(c));
          Obstacle o;
          o.kind = Obstacle::Kind::kBuilding;
          o.centre = Vector3d(rect.c.x(), rect.c.y(), ground + height / 2.0 - 0.5);
          o.yaw = std::atan2(t.y(), t.x());
          o.half_extent = Vector3d(rect.hl, rect.hw, height / 2.0 + 0.5);  // sunk 0.5 m on slopes
          o.colour = randomColour(r, false);
          impl_->obstacles.push_back(o);
          addBuildingRect(rect);
          ++impl_->stats.buildings;
        }
      }
      s += len + uni(r, 2.0, 8.0);
    }
  }
}

}  // namespace lanemap::sim::world_build
