#include "core/bev/bev_store.h"

#include "core/io/atomic_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace lanemap::bev {

void mergeGrid(const BevGrid& src, BevGrid& dst, const Eigen::Vector2i& shift) {
  if (src.resolution() != dst.resolution() || src.options().tile_cells != dst.options().tile_cells) {
    throw BevError("cannot merge BEV grids of different resolution or tile size");
  }
  const int t = src.options().tile_cells;
  src.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    for (int l = 0; l < kNumLayers; ++l) {
      for (int r = 0; r < t; ++r) {
        for (int c = 0; c < t; ++c) {
          const uint16_t n = counts[static_cast<size_t>(l) * t * t + static_cast<size_t>(r) * t + c];
          if (n) dst.add(BevGrid::Cell(origin.x() + c + shift.x(), origin.y() + r + shift.y()), static_cast<Layer>(l), n);
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

StoredRoad storeRoad(const std::string& store, const RoadBev& road, bool align) {
  StoredRoad s;
  s.path = roadGridPath(store, road.road_id);
  io::createDirectories(std::filesystem::path(s.path).parent_path().string());
  BevGrid grid = road.grid;
  if (std::filesystem::exists(s.path)) {
    grid = BevGrid::load(s.path);
    s.alignment = mergeAligned(road.grid, grid, align);
    s.merged = true;
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

// The frame count in the header of a stored grid file (BevGrid::save: magic, resolution, tile
// size, layers, frames): 0 when there is none, -1 when it cannot be read.
int64_t storedFrames(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return 0;
  std::ifstream f(path, std::ios::binary);
  char header[28];
  if (!f.read(header, sizeof(header)) || std::memcmp(header, "LMBEV001", 8) != 0) return -1;
  int32_t frames = 0;
  std::memcpy(&frames, header + 24, sizeof(frames));
  return frames;
}

}  // namespace

uint64_t gridHash(const BevGrid& grid) {
  constexpr uint64_t kPrime = 1099511628211ull;
  const size_t n = static_cast<size_t>(kNumLayers) * grid.options().tile_cells * grid.options().tile_cells;
  uint64_t sum = 0;  // per-tile hashes summed: the tiles' order does not matter
  grid.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    uint64_t h = 14695981039346656037ull ^ ((static_cast<uint64_t>(static_cast<uint32_t>(origin.x())) << 32) |
                                           static_cast<uint32_t>(origin.y()));
    h *= kPrime;
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
      uint64_t w;
      std::memcpy(&w, counts + i, sizeof(w));
      h = (h ^ w) * kPrime;
    }
    for (; i < n; ++i) h = (h ^ counts[i]) * kPrime;
    sum += h ^ (h >> 29);
  });
  uint64_t r;
  const double res = grid.resolution();
  std::memcpy(&r, &res, sizeof(r));
  return ((sum ^ r) * kPrime ^ static_cast<uint64_t>(grid.frames())) * kPrime ^ grid.tileCount();
}

std::string checkpointPath(const std::string& store, int64_t road_id) {
  return (checkpointDir(store) / ("road_" + std::to_string(road_id) + ".bev")).string();
}

// The checkpoint is two files, the grid and then its JSON. The JSON names the grid it belongs to
// (its hash) and how many frames the road's stored grid had when it was written: a checkpoint
// found after a crash whose road's stored grid has more frames since was stored already (the
// crash came between storeRoad and removeCheckpoint) and is not carried on again, which would
// count its frames twice.
namespace {
// A checkpoint's JSON: its grid (hash), its newest frame, and the road's stored frames then.
void writeCheckpointMeta(const std::string& store, int64_t road_id, const BevGrid& grid, int64_t last_frame_utime,
                         int64_t stored_frames) {
  const nlohmann::json meta{{"road_id", road_id},
                            {"last_frame_utime", last_frame_utime},
                            {"frames", grid.frames()},
                            {"grid_hash", std::to_string(gridHash(grid))},
                            {"stored_frames", stored_frames}};
  io::writeFileAtomically(checkpointMeta(store, road_id).string(), meta.dump() + "\n");
}
}  // namespace

void storeCheckpoint(const std::string& store, const RoadBev& road, int64_t last_frame_utime) {
  io::createDirectories(checkpointDir(store).string());
  const int64_t stored = storedFrames(roadGridPath(store, road.road_id));
  road.grid.save(checkpointPath(store, road.road_id));
  writeCheckpointMeta(store, road.road_id, road.grid, last_frame_utime, stored);
}

bool removeCheckpoint(const std::string& store, int64_t road_id) {
  // The grid first: a crash between leaves a JSON without a grid, which loadCheckpoints ignores
  // (and removes); a JSON of another grid is never taken for its own (the hash).
  bool ok = true;
  for (const std::string& path : {checkpointPath(store, road_id), checkpointMeta(store, road_id).string()}) {
    try {
      io::removeFileDurably(path);
    } catch (const io::IoError&) {
      ok = false;
    }
  }
  return ok;
}

std::vector<Checkpoint> loadCheckpoints(const std::string& store, std::vector<std::string>* errors,
                                        std::vector<int64_t>* already_stored) {
  std::vector<Checkpoint> out;  // by road id, as roadFiles gives them
  const auto grids = roadFiles(checkpointDir(store).string(), ".bev");
  for (const auto& [road_id, path] : grids) {
    try {
      Checkpoint c;
      c.road_id = road_id;
      c.path = path;
      c.grid = BevGrid::load(c.path);
      bool matched = false;
      std::ifstream meta(checkpointMeta(store, c.road_id));
      if (meta) {
        const auto j = nlohmann::json::parse(meta, nullptr, false);
        if (j.is_object() && j.value("road_id", int64_t{-1}) == c.road_id &&
            j.value("grid_hash", std::string()) == std::to_string(gridHash(c.grid))) {
          matched = true;
          c.last_frame_utime = j.value("last_frame_utime", int64_t{0});
          const int64_t stored_then = j.value("stored_frames", int64_t{-1});
          const int64_t stored_now = storedFrames(roadGridPath(store, road_id));
          if (stored_then >= 0 && stored_now > stored_then) {
            removeCheckpoint(store, road_id);
            if (already_stored) already_stored->push_back(road_id);
            continue;
          }
        }
      }
      if (!matched) {
        // No JSON, or one of an older checkpoint (a crash between the grid and its JSON): the grid
        // is newer than anything stored, its newest frame unknown (0). Its JSON is written now, so
        // that a crash after this road is stored and before the checkpoint is removed is still
        // recognised (else the next start would carry the stored frames on a second time).
        writeCheckpointMeta(store, road_id, c.grid, 0, storedFrames(roadGridPath(store, road_id)));
      }
      out.push_back(std::move(c));
    } catch (const std::exception& e) {
      if (errors) errors->push_back(path + ": " + e.what());
    }
  }
  // A JSON left without its grid (a crash while removing the checkpoint) is removed.
  for (const auto& [road_id, path] : roadFiles(checkpointDir(store).string(), ".json")) {
    if (!grids.count(road_id)) removeCheckpoint(store, road_id);
  }
  return out;
}

}  // namespace lanemap::bev
