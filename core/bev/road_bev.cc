#include "core/bev/road_bev.h"

#include <algorithm>
#include <cmath>

namespace lanemap::bev {

namespace {

double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

}  // namespace

Corridor::Corridor(const std::vector<Eigen::Vector2d>& polyline, const std::vector<std::vector<Eigen::Vector2d>>& rois,
                   const CorridorOptions& options)
    : options_(options) {
  if (!(options_.mask_cell_m > 0.0) || options_.half_width_m < 0.0) throw BevError("Corridor: bad options");
  for (const auto& p : polyline) {
    bounds_.extend(p - Eigen::Vector2d::Constant(options_.half_width_m));
    bounds_.extend(p + Eigen::Vector2d::Constant(options_.half_width_m));
  }
  for (const auto& roi : rois) {
    for (const auto& p : roi) bounds_.extend(p);
  }
  if (bounds_.isEmpty()) return;
  nx_ = static_cast<int>(std::ceil(bounds_.sizes().x() / options_.mask_cell_m)) + 1;
  ny_ = static_cast<int>(std::ceil(bounds_.sizes().y() / options_.mask_cell_m)) + 1;
  mask_.assign(static_cast<size_t>(nx_) * ny_, 0);
  markPolyline(polyline, options_.half_width_m);
  for (const auto& roi : rois) markPolygon(roi);
}

Corridor Corridor::forRoad(const skeleton::Skeleton& sk, const skeleton::AtomicRoad& road, const CorridorOptions& o) {
  std::vector<std::vector<Eigen::Vector2d>> rois;
  if (o.include_rois) {
    for (int64_t id : {road.from, road.to}) {
      if (const auto* in = sk.intersection(id); in && in->roi.size() >= 3) rois.push_back(in->roi);
    }
  }
  return Corridor(road.polyline, rois, o);
}

Eigen::Vector2d Corridor::centreOf(int x, int y) const {
  return bounds_.min() + Eigen::Vector2d((x + 0.5) * options_.mask_cell_m, (y + 0.5) * options_.mask_cell_m);
}

void Corridor::markPolyline(const std::vector<Eigen::Vector2d>& line, double hw) {
  const double cs = options_.mask_cell_m;
  for (size_t i = 0; i < line.size(); ++i) {
    const Eigen::Vector2d& a = line[i];
    const Eigen::Vector2d& b = line[std::min(i + 1, line.size() - 1)];
    const Eigen::Vector2d lo = a.cwiseMin(b).array() - hw, hi = a.cwiseMax(b).array() + hw;
    const int x0 = std::max(0, static_cast<int>((lo.x() - bounds_.min().x()) / cs));
    const int y0 = std::max(0, static_cast<int>((lo.y() - bounds_.min().y()) / cs));
    const int x1 = std::min(nx_ - 1, static_cast<int>((hi.x() - bounds_.min().x()) / cs));
    const int y1 = std::min(ny_ - 1, static_cast<int>((hi.y() - bounds_.min().y()) / cs));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        uint8_t& m = mask_[static_cast<size_t>(y) * nx_ + x];
        if (!m && segmentDistance(centreOf(x, y), a, b) <= hw) m = 1;
      }
    }
  }
}

void Corridor::markPolygon(const std::vector<Eigen::Vector2d>& poly) {
  if (poly.size() < 3) return;
  Eigen::AlignedBox2d box;
  for (const auto& p : poly) box.extend(p);
  const double cs = options_.mask_cell_m;
  const int x0 = std::max(0, static_cast<int>((box.min().x() - bounds_.min().x()) / cs));
  const int y0 = std::max(0, static_cast<int>((box.min().y() - bounds_.min().y()) / cs));
  const int x1 = std::min(nx_ - 1, static_cast<int>((box.max().x() - bounds_.min().x()) / cs));
  const int y1 = std::min(ny_ - 1, static_cast<int>((box.max().y() - bounds_.min().y()) / cs));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (skeleton::pointInPolygon(poly, centreOf(x, y))) mask_[static_cast<size_t>(y) * nx_ + x] = 1;
    }
  }
}

bool Corridor::contains(const Eigen::Vector2d& p) const {
  if (mask_.empty()) return false;
  const Eigen::Vector2d q = (p - bounds_.min()) / options_.mask_cell_m;
  const int x = static_cast<int>(std::floor(q.x())), y = static_cast<int>(std::floor(q.y()));
  if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return false;
  return mask_[static_cast<size_t>(y) * nx_ + x] != 0;
}

size_t Corridor::cellCount() const { return static_cast<size_t>(std::count(mask_.begin(), mask_.end(), 1)); }

void RoadBev::add(const FrameSplat& splat) {
  bool any = false;
  for (const auto& c : splat.cells) {
    const BevGrid::Cell cell(c.x, c.y);
    if (!corridor->contains(grid.cellCentre(cell))) {
      ++cells_outside;
      continue;
    }
    any = true;
    ++cells_added;
    for (int l = 0; l < kNumLayers; ++l) {
      if (c.layers & (1u << l)) grid.add(cell, static_cast<Layer>(l));
    }
  }
  if (any) grid.addFrame();
}

RoadBevAccumulator::RoadBevAccumulator(const skeleton::Skeleton& skeleton, AccumulatorOptions options)
    : skeleton_(skeleton), options_(options) {}

bool RoadBevAccumulator::open(int64_t road_id, int64_t utime, std::optional<int64_t> newest_frame_utime) {
  const auto* road = skeleton_.road(road_id);
  if (!road || active_.count(road_id)) return false;
  RoadBev r{road_id, road->from, road->to, utime, 0,
            std::make_shared<const Corridor>(Corridor::forRoad(skeleton_, *road, options_.corridor)),
            BevGrid(options_.grid)};
  for (const auto& s : history_) {
    // The same test as add()'s pruning, from the newest frame time.
    if (newest_frame_utime && static_cast<double>(*newest_frame_utime - s->utime) > options_.history_s * 1e6) continue;
    r.add(*s);
  }
  active_.emplace(road_id, std::move(r));
  return true;
}

bool RoadBevAccumulator::restore(int64_t road_id, BevGrid grid, int64_t utime) {
  const auto* road = skeleton_.road(road_id);
  if (!road || active_.count(road_id)) return false;
  if (grid.resolution() != options_.grid.resolution_m || grid.options().tile_cells != options_.grid.tile_cells) return false;
  RoadBev r{road_id, road->from, road->to, utime, 0,
            std::make_shared<const Corridor>(Corridor::forRoad(skeleton_, *road, options_.corridor)), std::move(grid)};
  active_.emplace(road_id, std::move(r));
  return true;
}

std::optional<RoadBev> RoadBevAccumulator::close(int64_t road_id, int64_t utime) {
  auto it = active_.find(road_id);
  if (it == active_.end()) return std::nullopt;
  RoadBev r = std::move(it->second);
  active_.erase(it);
  r.closed_utime = utime;
  return r;
}

bool RoadBevAccumulator::discard(int64_t road_id) { return active_.erase(road_id) > 0; }

void RoadBevAccumulator::add(const FrameSplat& splat) {
  for (auto& [id, r] : active_) r.add(splat);
  if (options_.history_s <= 0.0) return;
  history_.push_back(std::make_shared<const FrameSplat>(splat));
  while (!history_.empty() && static_cast<double>(splat.utime - history_.front()->utime) > options_.history_s * 1e6) {
    history_.pop_front();
  }
}

std::vector<int64_t> RoadBevAccumulator::activeRoads() const {
  std::vector<int64_t> ids;
  for (const auto& [id, r] : active_) ids.push_back(id);
  return ids;
}

const RoadBev* RoadBevAccumulator::active(int64_t road_id) const {
  auto it = active_.find(road_id);
  return it == active_.end() ? nullptr : &it->second;
}

size_t RoadBevAccumulator::memoryBytes() const {
  size_t n = 0;
  for (const auto& [id, r] : active_) n += r.grid.memoryBytes();
  for (const auto& s : history_) n += s->cells.size() * sizeof(SplatCell);
  return n;
}

}  // namespace lanemap::bev
