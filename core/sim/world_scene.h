// Inside of SimWorld (world_builder.h): the scene the builder produces (filled polygons per
// surface layer, road-surface quads for the height profile, obstacles, lane slots for laneOffset)
// and the lazily rasterised tiles behind sample() and height(), held in a bounded cache.
// Only world_builder.cc, world_scene.cc and lanelet2_world.cc (the world from a Lanelet2 map)
// include this.
#pragma once

#include "core/sim/world_builder.h"

#include <opencv2/core.hpp>

#include <atomic>
#include <future>
#include <limits>
#include <mutex>
#include <unordered_map>

namespace lanemap::sim {

namespace detail {

using Eigen::Vector2d;

// Draw order of the surface raster: a higher layer paints over a lower one.
enum Layer : uint8_t {
  kLayerSidewalk = 0,
  kLayerIntersection,
  kLayerShoulder,  // parking, bike lanes, bus bays
  kLayerLane,      // driving lanes (also writes the lanelet id)
  kLayerCurb,
  kLayerLinePaint,
  kLayerCrosswalk,
  kLayerStopLine,
};

struct FillPrimitive {
  Surface surface = Surface::kOffRoad;
  int level = 0;             // the OSM level of its road (WorldOptions::osm_layers): drawn before `layer`
  Layer layer = kLayerSidewalk;
  bool faded = false;        // worn paint: only part of its pixels are painted
  int64_t lanelet = -1;      // driving lanes: the lanelet id written to the id raster
  std::vector<Vector2d> polygon;
  Eigen::AlignedBox2d box;
};

// One reference-line segment of a road cross-section and its lateral profile at both ends
// (offsets along the left normal, metres): the crown between the curbs, curb steps up to the
// sidewalk's outer edge.
struct CrownQuad {
  Vector2d a = Vector2d::Zero(), b = Vector2d::Zero();
  Vector2d na = Vector2d::UnitY(), nb = Vector2d::UnitY();  // left normals at a and b
  double left_curb[2] = {0, 0}, right_curb[2] = {0, 0};     // carriageway edges
  double left_outer[2] = {0, 0}, right_outer[2] = {0, 0};   // sidewalk outer edges
  double fade[2] = {1, 1};                                   // crown fades out at the road ends
  Eigen::AlignedBox2d box;
};

// Smooth seeded terrain (sum of long waves, slope bounded by max_grade) plus short bumps.
struct Terrain {
  struct Wave {
    Vector2d k = Vector2d::Zero();
    double amplitude = 0.0;
    double phase = 0.0;
  };
  std::vector<Wave> waves;
  double at(double east, double north) const;
};

struct Tile {
  double x0 = 0.0, y0 = 0.0;    // south-west corner (ENU)
  int n = 0;                    // surface pixels per side
  int hn = 0;                   // height cells per side (hn + 1 nodes)
  cv::Mat surface;              // CV_8U, Surface, row = north
  cv::Mat lane;                 // CV_16U, index into lanelet_ids (0: none)
  std::vector<int64_t> lanelet_ids;
  cv::Mat height;               // CV_32F, (hn + 1) x (hn + 1) nodes
  double hres = 1.0;            // height cell size: tile_size_m / hn
  double inv_hres = 0.0;        // 1 / hres when hres is a power of two (then x * inv_hres is x / hres
                                // to the bit), else 0: divide
  size_t bytes() const;
};

// Lateral slot of a road lanelet inside its cross-section (for laneOffset).
struct LaneSlot {
  int64_t cross_section = -1;
  int dir = 1;           // +1 along the cross-section's reference direction, -1 against
  int rank_curb = 0;     // 0 = next to its curb side
  int rank_centre = 0;   // 0 = next to the centre line / the inner edge
};

}  // namespace detail

struct SimWorld::Impl {
  WorldOptions options;
  map::LaneMap truth;
  std::unordered_map<int64_t, size_t> lanelet_index, line_index;
  std::unordered_map<int64_t, std::vector<int64_t>> predecessors;
  std::unordered_map<int64_t, detail::LaneSlot> slots;
  std::vector<Obstacle> obstacles;
  double obstacle_cell = 20.0, max_obstacle_radius = 0.0;
  std::unordered_map<int64_t, std::vector<uint32_t>> obstacle_grid;
  std::vector<MarkingGap> gaps;
  WorldStats stats;
  detail::Terrain terrain;
  bool right_hand = true;

  std::vector<detail::FillPrimitive> fills;  // in draw order (sorted by layer)
  std::vector<detail::CrownQuad> quads;
  std::vector<std::vector<Eigen::Vector2d>> flat_polygons;  // intersections: no crown, no curb
  std::unordered_map<int64_t, std::vector<uint32_t>> fills_by_tile, quads_by_tile, flat_by_tile;
  // OSM levels (WorldOptions::osm_layers): the distinct levels of each tile's fills (ascending;
  // tiles of one level are not listed), and each road's and intersection's level.
  std::unordered_map<int64_t, std::vector<int>> levels_by_tile;
  std::unordered_map<int64_t, int> road_level, node_level;
  static constexpr int kAllLevels = std::numeric_limits<int>::max();  // seen from above: every level
  // The level a tile is drawn for when seen from `view`: kAllLevels for a tile of one level or
  // seen from its top level or above, else the highest of its levels at or under `view` (its
  // lowest when none is).
  int tileLevel(int64_t key, int view) const;

  // Tile cache.
  struct Entry {
    std::shared_future<std::shared_ptr<const detail::Tile>> tile;
    uint64_t last_use = 0;
  };
  struct CacheKey {
    int64_t xy = 0;
    int level = kAllLevels;
    bool operator==(const CacheKey& o) const { return xy == o.xy && level == o.level; }
  };
  struct CacheKeyHash {
    size_t operator()(const CacheKey& k) const {
      return std::hash<int64_t>()(k.xy) ^ (std::hash<int>()(k.level) * 0x9E3779B97F4A7C15ULL);
    }
  };
  mutable std::mutex mutex;
  mutable std::unordered_map<CacheKey, Entry, CacheKeyHash> cache;
  mutable uint64_t clock = 0;
  uint64_t uid = 0;

  int64_t tileKey(int64_t ix, int64_t iy) const { return (ix << 32) ^ (iy & 0xffffffffLL); }
  int64_t tileKeyAt(double east, double north, int64_t* ix = nullptr, int64_t* iy = nullptr) const;
  // The tile at a point as seen from level `view` (tileLevel); thread-safe.
  const detail::Tile& tileAt(double east, double north, int view = kAllLevels) const;
  std::shared_ptr<const detail::Tile> fetchTile(int64_t key, int64_t ix, int64_t iy, int level) const;
  // Fills of a level above `level` are left out (kAllLevels: none).
  std::shared_ptr<const detail::Tile> buildTile(int64_t ix, int64_t iy, int level) const;
  // Indexes the scene by tile and builds the lookup tables; call once after building.
  void finalize();
};

}  // namespace lanemap::sim
