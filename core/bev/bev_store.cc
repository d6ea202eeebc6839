#include "core/bev/bev_store.h"

#include <filesystem>

namespace lanemap::bev {

void mergeGrid(const BevGrid& src, BevGrid& dst) {
  if (src.resolution() != dst.resolution() || src.options().tile_cells != dst.options().tile_cells) {
    throw BevError("cannot merge BEV grids of different resolution or tile size");
  }
  const int t = src.options().tile_cells;
  src.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    for (int l = 0; l < kNumLayers; ++l) {
      for (int r = 0; r < t; ++r) {
        for (int c = 0; c < t; ++c) {
          const uint16_t n = counts[static_cast<size_t>(l) * t * t + static_cast<size_t>(r) * t + c];
          if (n) dst.add(BevGrid::Cell(origin.x() + c, origin.y() + r), static_cast<Layer>(l), n);
        }
      }
    }
  });
  for (int i = 0; i < src.frames(); ++i) dst.addFrame();
}

std::string roadGridPath(const std::string& store, int64_t road_id) {
  return (std::filesystem::path(store) / "bev" / ("road_" + std::to_string(road_id) + ".bev")).string();
}

StoredRoad storeRoad(const std::string& store, const RoadBev& road) {
  StoredRoad s;
  s.path = roadGridPath(store, road.road_id);
  std::filesystem::create_directories(std::filesystem::path(s.path).parent_path());
  BevGrid grid = road.grid;
  if (std::filesystem::exists(s.path)) {
    const BevGrid old = BevGrid::load(s.path);
    mergeGrid(old, grid);
  }
  grid.save(s.path);
  const auto box = grid.cellBounds();
  s.resolution = grid.resolution();
  s.frames = grid.frames();
  if (!box.isEmpty()) {
    s.origin = box.min().cast<double>() * grid.resolution();
    s.width = box.sizes().x();
    s.height = box.sizes().y();
  }
  return s;
}

}  // namespace lanemap::bev
