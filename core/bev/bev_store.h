// The map store's BEV part: a closed road's grid goes to <store>/bev/road_<id>.bev (BevGrid::save,
// written atomically), so a crash loses nothing and the lane mapper reads it when BEV_ROAD says so.
// A road driven again is merged into its stored grid (counts add up, frames too): more passes,
// more evidence.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/bev/road_bev.h"

#include <Eigen/Core>

#include <string>

namespace lanemap::bev {

// Adds every count of `src` to `dst` (same resolution and tile size, else BevError).
void mergeGrid(const BevGrid& src, BevGrid& dst);

struct StoredRoad {
  std::string path;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // ENU corner of the grid's min cell
  double resolution = 0.0;
  int width = 0, height = 0;  // cells (BevGrid::cellBounds())
  int frames = 0;
};

std::string roadGridPath(const std::string& store, int64_t road_id);
// Writes (or merges into) the road's file; throws BevError / std::runtime_error on failure.
StoredRoad storeRoad(const std::string& store, const RoadBev& road);

}  // namespace lanemap::bev
