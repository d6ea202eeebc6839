#include "core/bev/bev_store.h"

#include "core/io/atomic_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>

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

std::map<int64_t, std::string> roadFiles(const std::string& dir, const std::string& extension) {
  std::map<int64_t, std::string> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = "road_";
    if (name.size() <= prefix.size() + extension.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - extension.size(), extension.size(), extension) != 0) {
      continue;
    }
    const char* first = name.data() + prefix.size();
    const char* last = name.data() + name.size() - extension.size();
    int64_t id = 0;
    const auto [end, err] = std::from_chars(first, last, id);
    if (err == std::errc() && end == last) out[id] = entry.path().string();
  }
  return out;
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

namespace {
std::filesystem::path checkpointDir(const std::string& store) { return std::filesystem::path(store) / "bev" / "open"; }
std::filesystem::path checkpointMeta(const std::string& store, int64_t road_id) {
  return checkpointDir(store) / ("road_" + std::to_string(road_id) + ".json");
}
}  // namespace

std::string checkpointPath(const std::string& store, int64_t road_id) {
  return (checkpointDir(store) / ("road_" + std::to_string(road_id) + ".bev")).string();
}

void storeCheckpoint(const std::string& store, const RoadBev& road, int64_t last_frame_utime) {
  std::filesystem::create_directories(checkpointDir(store));
  road.grid.save(checkpointPath(store, road.road_id));
  const nlohmann::json meta{{"road_id", road.road_id}, {"last_frame_utime", last_frame_utime}, {"frames", road.grid.frames()}};
  io::writeFileAtomically(checkpointMeta(store, road.road_id).string(), meta.dump() + "\n");
}

void removeCheckpoint(const std::string& store, int64_t road_id) {
  std::error_code ec;
  std::filesystem::remove(checkpointPath(store, road_id), ec);
  std::filesystem::remove(checkpointMeta(store, road_id), ec);
}

std::vector<Checkpoint> loadCheckpoints(const std::string& store, std::vector<std::string>* errors) {
  std::vector<Checkpoint> out;  // by road id, as roadFiles gives them
  for (const auto& [road_id, path] : roadFiles(checkpointDir(store).string(), ".bev")) {
    try {
      Checkpoint c;
      c.road_id = road_id;
      c.path = path;
      c.grid = BevGrid::load(c.path);
      std::ifstream meta(checkpointMeta(store, c.road_id));
      if (meta) {
        const auto j = nlohmann::json::parse(meta, nullptr, false);
        if (j.is_object() && j.value("road_id", int64_t{-1}) == c.road_id) c.last_frame_utime = j.value("last_frame_utime", int64_t{0});
      }
      out.push_back(std::move(c));
    } catch (const std::exception& e) {
      if (errors) errors->push_back(path + ": " + e.what());
    }
  }
  return out;
}

}  // namespace lanemap::bev
