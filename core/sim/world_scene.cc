// SimWorld's queries: sample() and height() from lazily rasterised tiles (OpenCV fillPoly into a
// surface raster, a lanelet-id raster and a height grid) kept in a bounded LRU cache; obstacles
// through a grid; laneOffset from the lanelets' lateral slots.
#include "core/sim/world_scene.h"

#include "core/sim/world_geometry.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace lanemap::sim {

using detail::Tile;
using Eigen::Vector2d;

namespace {

std::atomic<uint64_t> g_next_uid{1};

// Per-thread memo of the last tiles used, so that the hot path takes no lock.
struct TlsTile {
  uint64_t uid = 0;
  int64_t key = 0;
  int level = 0;
  std::shared_ptr<const Tile> tile;
};
constexpr int kTlsSlots = 4;
thread_local TlsTile t_tiles[kTlsSlots];
thread_local unsigned t_next = 0;

// The tile this thread was given last and the box of points that certainly fall in it (its square
// shrunk by a billionth of its side, so that floor(east / tile_size) cannot round to a neighbour
// inside the box): most queries (the steps of one ray) land in the same tile as the one before,
// and then need neither the key's divisions nor the slot search. The tile is held by a slot.
struct TlsLast {
  uint64_t uid = 0;
  double xlo = 1.0, xhi = 0.0, ylo = 1.0, yhi = 0.0;  // empty
  int view = 0;         // the level it was asked for ...
  bool any_view = false;  // ... or any: the tile has fills of one level only
  const Tile* tile = nullptr;
};
thread_local TlsLast t_last;

uint64_t hashPixel(int64_t x, int64_t y) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^ (static_cast<uint64_t>(y) + 0x632BE59BD9B4E019ULL);
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 29;
  return h;
}

}  // namespace

double detail::Terrain::at(double east, double north) const {
  double h = 0.0;
  for (const auto& w : waves) h += w.amplitude * std::sin(w.k.x() * east + w.k.y() * north + w.phase);
  return h;
}

size_t Tile::bytes() const {
  return surface.total() * surface.elemSize() + lane.total() * lane.elemSize() +
         height.total() * height.elemSize() + lanelet_ids.size() * sizeof(int64_t);
}

int64_t SimWorld::Impl::tileKeyAt(double east, double north, int64_t* ix, int64_t* iy) const {
  const int64_t x = static_cast<int64_t>(std::floor(east / options.tile_size_m));
  const int64_t y = static_cast<int64_t>(std::floor(north / options.tile_size_m));
  if (ix) *ix = x;
  if (iy) *iy = y;
  return tileKey(x, y);
}

int SimWorld::Impl::tileLevel(int64_t key, int view) const {
  const auto it = levels_by_tile.find(key);
  if (it == levels_by_tile.end() || view >= it->second.back()) return kAllLevels;
  int level = it->second.front();
  for (int l : it->second) {
    if (l <= view) level = l;
  }
  return level;
}

const Tile& SimWorld::Impl::tileAt(double east, double north, int view) const {
  const TlsLast& last = t_last;
  if (last.uid == uid && (last.any_view || last.view == view) && east >= last.xlo && east < last.xhi && north >= last.ylo && north < last.yhi) {
    return *last.tile;
  }
  int64_t ix = 0, iy = 0;
  const int64_t key = tileKeyAt(east, north, &ix, &iy);
  const int level = levels_by_tile.empty() ? kAllLevels : tileLevel(key, view);
  const Tile* found = nullptr;
  for (auto& t : t_tiles) {
    if (t.uid == uid && t.key == key && t.level == level && t.tile) {
      found = t.tile.get();
      break;
    }
  }
  if (!found) {
    auto tile = fetchTile(key, ix, iy, level);
    TlsTile& slot = t_tiles[t_next++ % kTlsSlots];
    slot.uid = uid;
    slot.key = key;
    slot.level = level;
    slot.tile = std::move(tile);
    found = slot.tile.get();
  }
  const double size = options.tile_size_m, margin = 1e-9 * size;
  t_last = TlsLast{uid, ix * size + margin, (ix + 1) * size - margin, iy * size + margin, (iy + 1) * size - margin, view,
                   levels_by_tile.count(key) == 0, found};
  return *found;
}

std::shared_ptr<const Tile> SimWorld::Impl::fetchTile(int64_t xy, int64_t ix, int64_t iy, int level) const {
  const CacheKey key{xy, level};
  std::shared_future<std::shared_ptr<const Tile>> future;
  std::promise<std::shared_ptr<const Tile>> promise;
  bool build = false;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(key);
    if (it != cache.end()) {
      it->second.last_use = ++clock;
      future = it->second.tile;
    } else {
      future = promise.get_future().share();
      cache[key] = Entry{future, ++clock};
      build = true;
      // Bounded cache: drop the least recently used finished tiles (holders keep theirs alive).
      while (cache.size() > static_cast<size_t>(options.tile_cache_size)) {
        auto victim = cache.end();
        for (auto c = cache.begin(); c != cache.end(); ++c) {
          if (c->first == key) continue;
          if (c->second.tile.wait_for(std::chrono::seconds(0)) != std::future_status::ready) continue;
          if (victim == cache.end() || c->second.last_use < victim->second.last_use) victim = c;
        }
        if (victim == cache.end()) break;
        cache.erase(victim);
      }
    }
  }
  if (build) {
    try {
      promise.set_value(buildTile(ix, iy, level));
    } catch (...) {
      promise.set_exception(std::current_exception());
      std::lock_guard<std::mutex> lock(mutex);
      cache.erase(key);
    }
  }
  return future.get();
}

std::shared_ptr<const Tile> SimWorld::Impl::buildTile(int64_t ix, int64_t iy, int level) const {
  auto tile = std::make_shared<Tile>();
  const double size = options.tile_size_m;
  const double res = options.tile_resolution_m;
  tile->x0 = ix * size;
  tile->y0 = iy * size;
  tile->n = static_cast<int>(std::lround(size / res));
  tile->hn = std::max(1, static_cast<int>(std::lround(size / options.height_resolution_m)));
  tile->surface = cv::Mat(tile->n, tile->n, CV_8U, cv::Scalar(static_cast<int>(Surface::kOffRoad)));
  tile->lane = cv::Mat(tile->n, tile->n, CV_16U, cv::Scalar(0));
  tile->lanelet_ids.push_back(-1);
  const double x0 = tile->x0, y0 = tile->y0, x1 = x0 + size, y1 = y0 + size;
  const int64_t key = tileKey(ix, iy);

  // 1. Surface and lanelet id: polygons in draw order. Pixel (c, r) covers
  //    [x0 + c res, x0 + (c+1) res) x [y0 + r res, ...); OpenCV puts pixel centres at integers.
  constexpr int kShift = 8;
  const double scale = 1 << kShift;
  std::unordered_map<int64_t, uint16_t> local_ids;
  cv::Mat scratch;
  if (auto it = fills_by_tile.find(key); it != fills_by_tile.end()) {
    for (uint32_t idx : it->second) {
      const auto& f = fills[idx];
      if (f.level > level) continue;  // above the viewer (a bridge over the road it drives)
      std::vector<cv::Point> pts;
      pts.reserve(f.polygon.size());
      for (const auto& p : f.polygon) {
        pts.emplace_back(static_cast<int>(std::lround(((p.x() - x0) / res - 0.5) * scale)),
                         static_cast<int>(std::lround(((p.y() - y0) / res - 0.5) * scale)));
      }
      const cv::Point* ptr = pts.data();
      const int npts = static_cast<int>(pts.size());
      if (npts < 3) continue;
      if (f.faded) {
        // Worn paint: rasterise into a scratch mask, keep ~40 % of the pixels (seeded by position).
        const cv::Rect r = cv::boundingRect(pts);
        cv::Rect px(static_cast<int>(std::floor(r.x / scale)) - 1, static_cast<int>(std::floor(r.y / scale)) - 1,
                    static_cast<int>(std::ceil(r.width / scale)) + 3, static_cast<int>(std::ceil(r.height / scale)) + 3);
        px &= cv::Rect(0, 0, tile->n, tile->n);
        if (px.empty()) continue;
        if (scratch.empty()) scratch = cv::Mat(tile->n, tile->n, CV_8U, cv::Scalar(0));
        cv::fillPoly(scratch, &ptr, &npts, 1, cv::Scalar(1), cv::LINE_8, kShift);
        const int64_t gx0 = static_cast<int64_t>(std::llround(x0 / res));
        const int64_t gy0 = static_cast<int64_t>(std::llround(y0 / res));
        for (int r2 = px.y; r2 < px.y + px.height; ++r2) {
          uint8_t* m = scratch.ptr<uint8_t>(r2);
          uint8_t* s = tile->surface.ptr<uint8_t>(r2);
          for (int c = px.x; c < px.x + px.width; ++c) {
            if (!m[c]) continue;
            m[c] = 0;
            if (hashPixel(gx0 + c, gy0 + r2) % 100 < 40) s[c] = static_cast<uint8_t>(f.surface);
          }
        }
        continue;
      }
      cv::fillPoly(tile->surface, &ptr, &npts, 1, cv::Scalar(static_cast<int>(f.surface)), cv::LINE_8, kShift);
      if (f.layer == detail::kLayerLane && f.lanelet >= 0) {
        auto [lit, inserted] = local_ids.emplace(f.lanelet, 0);
        if (inserted) {
          if (tile->lanelet_ids.size() >= 65535) continue;  // cannot happen for a 64 m tile
          lit->second = static_cast<uint16_t>(tile->lanelet_ids.size());
          tile->lanelet_ids.push_back(f.lanelet);
        }
        cv::fillPoly(tile->lane, &ptr, &npts, 1, cv::Scalar(lit->second), cv::LINE_8, kShift);
      }
    }
  }

  // 2. Height grid: terrain + bumps, then the road profile (crown, curbs) inside road quads,
  //    then flat intersections.
  if (options.flat) {
    tile->height = cv::Mat(2, 2, CV_32F, cv::Scalar(0.0f));
    tile->hn = 1;
  }
  tile->hres = size / tile->hn;
  int exponent = 0;
  if (std::frexp(tile->hres, &exponent) == 0.5) tile->inv_hres = std::ldexp(1.0, 1 - exponent);
  if (options.flat) return tile;
  const int hn = tile->hn;
  const double hres = size / hn;
  cv::Mat profile(hn + 1, hn + 1, CV_32F, cv::Scalar(0.0f));
  const double slope = options.crown_slope, curb = options.curb_height_m;
  if (auto it = quads_by_tile.find(key); it != quads_by_tile.end()) {
    // Rasterise the quads' footprints into a label image of the height nodes (scanline fill, so
    // only covered nodes are visited; adjacent quads share edges, so there are no gaps), then
    // evaluate each covered node's lateral offset on its quad.
    // Carriageways (curb to curb) are filled after all sidewalks, so where two roads overlap a
    // road surface is never lifted to a sidewalk.
    cv::Mat label(hn + 1, hn + 1, CV_32S, cv::Scalar(0));
    const auto& list = it->second;
    for (int pass = 0; pass < 2; ++pass) {
      for (size_t li = 0; li < list.size(); ++li) {
        const auto& q = quads[list[li]];
        const double* lo = pass == 0 ? q.left_outer : q.left_curb;
        const double* ro = pass == 0 ? q.right_outer : q.right_curb;
        const Vector2d corners[4] = {q.a + q.na * lo[0], q.b + q.nb * lo[1], q.b + q.nb * ro[1], q.a + q.na * ro[0]};
        cv::Point pts[4];
        for (int i = 0; i < 4; ++i) {
          pts[i] = cv::Point(static_cast<int>(std::lround((corners[i].x() - x0) / hres * scale)),
                             static_cast<int>(std::lround((corners[i].y() - y0) / hres * scale)));
        }
        const cv::Point* ptr = pts;
        const int npts = 4;
        cv::fillPoly(label, &ptr, &npts, 1, cv::Scalar(static_cast<int>(li) + 1), cv::LINE_8, kShift);
      }
    }
    for (int r = 0; r <= hn; ++r) {
      float* row = profile.ptr<float>(r);
      const int32_t* lab = label.ptr<int32_t>(r);
      for (int c = 0; c <= hn; ++c) {
        if (!lab[c]) continue;
        const auto& q = quads[list[lab[c] - 1]];
        const Vector2d p(x0 + c * hres, y0 + r * hres);
        const Vector2d ab = q.b - q.a;
        const double l2 = std::max(ab.squaredNorm(), 1e-12);
        const Vector2d n = Vector2d(-ab.y(), ab.x()) / std::sqrt(l2);
        const double u = std::clamp((p - q.a).dot(ab) / l2, 0.0, 1.0);
        const double d = (p - q.a).dot(n);
        const double lc = q.left_curb[0] + u * (q.left_curb[1] - q.left_curb[0]);
        const double rc = q.right_curb[0] + u * (q.right_curb[1] - q.right_curb[0]);
        const double fade = q.fade[0] + u * (q.fade[1] - q.fade[0]);
        double v;
        if (d <= lc && d >= rc) {
          v = -slope * std::abs(d) * fade;
        } else {
          const double edge = d > lc ? lc : rc;
          v = -slope * std::abs(edge) * fade + curb;
        }
        row[c] = static_cast<float>(v);
      }
    }
  }
  if (auto it = flat_by_tile.find(key); it != flat_by_tile.end()) {
    for (uint32_t idx : it->second) {
      const auto& poly = flat_polygons[idx];
      Eigen::AlignedBox2d box;
      for (const auto& p : poly) box.extend(p);
      const int c0 = std::max(0, static_cast<int>(std::floor((box.min().x() - x0) / hres)));
      const int c1 = std::min(hn, static_cast<int>(std::ceil((box.max().x() - x0) / hres)));
      const int r0 = std::max(0, static_cast<int>(std::floor((box.min().y() - y0) / hres)));
      const int r1 = std::min(hn, static_cast<int>(std::ceil((box.max().y() - y0) / hres)));
      for (int r = r0; r <= r1; ++r) {
        for (int c = c0; c <= c1; ++c) {
          if (geom::pointInPolygon(Vector2d(x0 + c * hres, y0 + r * hres), poly)) profile.at<float>(r, c) = 0.0f;
        }
      }
    }
  }
  // Terrain on the node grid, separably: sin(a + b) = sin a cos b + cos a sin b with a the
  // column's and b the row's share of each wave's phase.
  cv::Mat ground(hn + 1, hn + 1, CV_64F, cv::Scalar(0.0));
  std::vector<double> sa(hn + 1), ca(hn + 1), sb(hn + 1), cb(hn + 1);
  for (const auto& wv : terrain.waves) {
    for (int i = 0; i <= hn; ++i) {
      const double a = wv.k.x() * (x0 + i * hres) + wv.phase;
      const double b = wv.k.y() * (y0 + i * hres);
      sa[i] = std::sin(a);
      ca[i] = std::cos(a);
      sb[i] = std::sin(b);
      cb[i] = std::cos(b);
    }
    for (int r = 0; r <= hn; ++r) {
      double* g = ground.ptr<double>(r);
      const double s_b = wv.amplitude * sb[r], c_b = wv.amplitude * cb[r];
      for (int c = 0; c <= hn; ++c) g[c] += sa[c] * c_b + ca[c] * s_b;
    }
  }
  tile->height = cv::Mat(hn + 1, hn + 1, CV_32F);
  for (int r = 0; r <= hn; ++r) {
    float* row = tile->height.ptr<float>(r);
    const float* pr = profile.ptr<float>(r);
    const double* g = ground.ptr<double>(r);
    for (int c = 0; c <= hn; ++c) row[c] = static_cast<float>(g[c] + pr[c]);
  }
  (void)x1;
  (void)y1;
  return tile;
}

void SimWorld::Impl::finalize() {
  uid = g_next_uid.fetch_add(1);
  std::stable_sort(fills.begin(), fills.end(),
                   [](const detail::FillPrimitive& a, const detail::FillPrimitive& b) {
                     return a.level != b.level ? a.level < b.level : a.layer < b.layer;
                   });
  const double size = options.tile_size_m;
  auto index = [&](const Eigen::AlignedBox2d& box, uint32_t idx, std::unordered_map<int64_t, std::vector<uint32_t>>& m) {
    if (box.isEmpty()) return;
    const int64_t ix0 = static_cast<int64_t>(std::floor(box.min().x() / size));
    const int64_t ix1 = static_cast<int64_t>(std::floor(box.max().x() / size));
    const int64_t iy0 = static_cast<int64_t>(std::floor(box.min().y() / size));
    const int64_t iy1 = static_cast<int64_t>(std::floor(box.max().y() / size));
    for (int64_t x = ix0; x <= ix1; ++x) {
      for (int64_t y = iy0; y <= iy1; ++y) m[tileKey(x, y)].push_back(idx);
    }
  };
  for (uint32_t i = 0; i < fills.size(); ++i) {
    auto& f = fills[i];
    f.box = Eigen::AlignedBox2d();
    for (const auto& p : f.polygon) f.box.extend(p);
    index(f.box, i, fills_by_tile);
  }
  levels_by_tile.clear();
  for (const auto& [key, list] : fills_by_tile) {
    std::vector<int> levels;
    for (uint32_t i : list) levels.push_back(fills[i].level);
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    if (levels.size() > 1) levels_by_tile[key] = std::move(levels);
  }
  for (uint32_t i = 0; i < quads.size(); ++i) {
    auto& q = quads[i];
    q.box = Eigen::AlignedBox2d();
    for (int e = 0; e < 2; ++e) {
      const Vector2d& c = e == 0 ? q.a : q.b;
      const Vector2d& n = e == 0 ? q.na : q.nb;
      q.box.extend(c + n * q.left_outer[e]);
      q.box.extend(c + n * q.right_outer[e]);
    }
    index(q.box, i, quads_by_tile);
  }
  for (uint32_t i = 0; i < flat_polygons.size(); ++i) {
    Eigen::AlignedBox2d box;
    for (const auto& p : flat_polygons[i]) box.extend(p);
    index(box, i, flat_by_tile);
  }
  for (size_t i = 0; i < truth.lanelets.size(); ++i) lanelet_index[truth.lanelets[i].id] = i;
  for (size_t i = 0; i < truth.lines.size(); ++i) line_index[truth.lines[i].id] = i;
  for (const auto& l : truth.lanelets) {
    predecessors[l.id];
    for (int64_t s : l.successors) predecessors[s].push_back(l.id);
  }
  max_obstacle_radius = 0.0;
  for (uint32_t i = 0; i < obstacles.size(); ++i) {
    const auto& o = obstacles[i];
    max_obstacle_radius = std::max(max_obstacle_radius, o.half_extent.head<2>().norm());
    const int64_t cx = static_cast<int64_t>(std::floor(o.centre.x() / obstacle_cell));
    const int64_t cy = static_cast<int64_t>(std::floor(o.centre.y() / obstacle_cell));
    obstacle_grid[tileKey(cx, cy)].push_back(i);
  }
}

// ---- SimWorld ----

SimWorld::SimWorld(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SimWorld::~SimWorld() = default;

double SimWorld::height(double east, double north) const {
  if (impl_->options.flat) return 0.0;
  const Tile& t = impl_->tileAt(east, north);
  const double hn = static_cast<double>(t.hn);
  const double gx = std::clamp(t.inv_hres > 0.0 ? (east - t.x0) * t.inv_hres : (east - t.x0) / t.hres, 0.0, hn);
  const double gy = std::clamp(t.inv_hres > 0.0 ? (north - t.y0) * t.inv_hres : (north - t.y0) / t.hres, 0.0, hn);
  const int c = std::min(static_cast<int>(gx), t.hn - 1);
  const int r = std::min(static_cast<int>(gy), t.hn - 1);
  const double u = gx - c, v = gy - r;
  const float* r0 = t.height.ptr<float>(r);
  const float* r1 = t.height.ptr<float>(r + 1);
  return (1 - v) * ((1 - u) * r0[c] + u * r0[c + 1]) + v * ((1 - u) * r1[c] + u * r1[c + 1]);
}

GroundSample SimWorld::sample(double east, double north) const { return sampleSeenFrom(east, north, Impl::kAllLevels); }

int SimWorld::levelOf(int64_t lanelet_id) const {
  const map::Lanelet* l = lanelet(lanelet_id);
  if (!l) return Impl::kAllLevels;
  if (l->road_id >= 0) {
    const auto it = impl_->road_level.find(l->road_id);
    return it == impl_->road_level.end() ? 0 : it->second;
  }
  const auto it = impl_->node_level.find(l->intersection_id);
  return it == impl_->node_level.end() ? 0 : it->second;
}

GroundSample SimWorld::sampleSeenFrom(double east, double north, int level) const {
  const Tile& t = impl_->tileAt(east, north, level);
  const double res = impl_->options.tile_resolution_m;
  const int c = std::clamp(static_cast<int>(std::floor((east - t.x0) / res)), 0, t.n - 1);
  const int r = std::clamp(static_cast<int>(std::floor((north - t.y0) / res)), 0, t.n - 1);
  GroundSample g;
  g.surface = static_cast<Surface>(t.surface.at<uint8_t>(r, c));
  g.lanelet = t.lanelet_ids[t.lane.at<uint16_t>(r, c)];
  return g;
}

void SimWorld::obstaclesNear(const Eigen::Vector2d& p, double radius, std::vector<const Obstacle*>* out) const {
  const Impl& m = *impl_;
  if (!out || m.obstacles.empty()) return;
  const double r = std::max(0.0, radius) + m.max_obstacle_radius;
  const int64_t cx0 = static_cast<int64_t>(std::floor((p.x() - r) / m.obstacle_cell));
  const int64_t cx1 = static_cast<int64_t>(std::floor((p.x() + r) / m.obstacle_cell));
  const int64_t cy0 = static_cast<int64_t>(std::floor((p.y() - r) / m.obstacle_cell));
  const int64_t cy1 = static_cast<int64_t>(std::floor((p.y() + r) / m.obstacle_cell));
  for (int64_t x = cx0; x <= cx1; ++x) {
    for (int64_t y = cy0; y <= cy1; ++y) {
      auto it = m.obstacle_grid.find(m.tileKey(x, y));
      if (it == m.obstacle_grid.end()) continue;
      for (uint32_t i : it->second) {
        const Obstacle& o = m.obstacles[i];
        if ((o.centre.head<2>() - p).norm() <= radius + o.half_extent.head<2>().norm()) out->push_back(&o);
      }
    }
  }
}

std::optional<int> SimWorld::laneOffset(int64_t ego, int64_t other) const {
  const auto a = impl_->slots.find(ego);
  const auto b = impl_->slots.find(other);
  if (a == impl_->slots.end() || b == impl_->slots.end()) return std::nullopt;
  const detail::LaneSlot& e = a->second;
  const detail::LaneSlot& o = b->second;
  if (e.cross_section != o.cross_section) return std::nullopt;
  const int hand = impl_->right_hand ? 1 : -1;  // which side the curb of a direction is on
  if (e.dir == o.dir) return hand * (e.rank_curb - o.rank_curb);
  return -hand * (e.rank_centre + 1 + o.rank_centre);
}

const map::LaneMap& SimWorld::truth() const { return impl_->truth; }
const std::vector<Obstacle>& SimWorld::obstacles() const { return impl_->obstacles; }

const map::Lanelet* SimWorld::lanelet(int64_t id) const {
  auto it = impl_->lanelet_index.find(id);
  return it == impl_->lanelet_index.end() ? nullptr : &impl_->truth.lanelets[it->second];
}

const map::LineString* SimWorld::line(int64_t id) const {
  auto it = impl_->line_index.find(id);
  return it == impl_->line_index.end() ? nullptr : &impl_->truth.lines[it->second];
}

const std::vector<int64_t>& SimWorld::predecessors(int64_t lanelet_id) const {
  static const std::vector<int64_t> kNone;
  auto it = impl_->predecessors.find(lanelet_id);
  return it == impl_->predecessors.end() ? kNone : it->second;
}

const map::Lanelet* SimWorld::laneletAt(double east, double north) const {
  const GroundSample g = sample(east, north);
  return g.lanelet >= 0 ? lanelet(g.lanelet) : nullptr;
}

double SimWorld::terrainHeight(double east, double north) const {
  return impl_->options.flat ? 0.0 : impl_->terrain.at(east, north);
}

const std::vector<MarkingGap>& SimWorld::markingGaps() const { return impl_->gaps; }
const WorldOptions& SimWorld::options() const { return impl_->options; }
const WorldStats& SimWorld::stats() const { return impl_->stats; }

size_t SimWorld::cachedTiles() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->cache.size();
}

}  // namespace lanemap::sim
