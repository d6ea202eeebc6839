#include "core/bev/bev_store.h"

#include "core/io/atomic_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace lanemap::bev {

void mergeGrid(const BevGrid& src, BevGrid& dst, const CellMove& move) {
  if (src.resolution() != dst.resolution() || src.options().tile_cells != dst.options().tile_cells) {
    throw BevError("cannot merge BEV grids of different resolution or tile size");
  }
  const int t = src.options().tile_cells;
  const size_t plane = static_cast<size_t>(t) * t;
  const Eigen::Vector2d shears = move.shears();
  src.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    for (int r = 0; r < t; ++r) {
      for (int c = 0; c < t; ++c) {
        const size_t i = static_cast<size_t>(r) * t + c;
        bool any = false;
        for (int l = 0; l < kNumLayers && !any; ++l) any = counts[static_cast<size_t>(l) * plane + i] != 0;
        if (!any) continue;
        const BevGrid::Cell to = move.apply(BevGrid::Cell(origin.x() + c, origin.y() + r), shears);
        for (int l = 0; l < kNumLayers; ++l) {
          const uint16_t n = counts[static_cast<size_t>(l) * plane + i];
          if (n) dst.add(to, static_cast<Layer>(l), n);
        }
      }
    }
  });
  const int traversals = dst.traversals() + src.traversals();
  for (int i = 0; i < src.frames(); ++i) dst.addFrame();
  dst.setTraversals(traversals);
  dst.addMerges(src.merges(), src.agreement());
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

namespace {
std::filesystem::path partialDir(const std::string& store) { return std::filesystem::path(store) / "bev" / "partial"; }
std::filesystem::path partialMeta(const std::string& store, int64_t road_id) {
  return partialDir(store) / ("road_" + std::to_string(road_id) + ".json");
}
nlohmann::json readJson(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) return nullptr;
  return nlohmann::json::parse(f, nullptr, false);
}
// The grid first (a JSON without its grid is dropped by partialRoad), then the JSON.
void removePartial(const std::string& store, int64_t road_id) {
  for (const std::string& path : {partialGridPath(store, road_id), partialMeta(store, road_id).string()}) {
    try {
      io::removeFileDurably(path);
    } catch (const io::IoError&) {
    }
  }
}
void fillBox(StoredRoad& s, const BevGrid& grid) {
  const auto box = grid.cellBounds();
  s.resolution = grid.resolution();
  s.frames = grid.frames();
  if (!box.isEmpty()) {
    s.origin = box.min().cast<double>() * grid.resolution();
    s.width = box.sizes().x();
    s.height = box.sizes().y();
  }
}
}  // namespace

std::string partialGridPath(const std::string& store, int64_t road_id) {
  return (partialDir(store) / ("road_" + std::to_string(road_id) + ".bev")).string();
}

std::optional<PartialRoadInfo> partialRoad(const std::string& store, int64_t road_id) {
  std::error_code ec;
  const std::string grid = partialGridPath(store, road_id);
  const auto meta_path = partialMeta(store, road_id);
  if (!std::filesystem::exists(grid, ec)) {
    if (std::filesystem::exists(meta_path, ec)) removePartial(store, road_id);  // a crash while removing it
    return std::nullopt;
  }
  const nlohmann::json j = readJson(meta_path);
  if (!j.is_object() || !j.contains("station_m") || !j["station_m"].is_number()) return std::nullopt;  // station unknown
  if (j.contains("completed_into")) {
    // storeRoad was merging it: when the road's grid is the one it was merged into, it is done.
    const std::string road_grid = roadGridPath(store, road_id);
    if (std::filesystem::exists(road_grid, ec) &&
        std::to_string(gridHash(BevGrid::load(road_grid))) == j.value("completed_into", std::string())) {
      removePartial(store, road_id);
      return std::nullopt;
    }
  }
  PartialRoadInfo p;
  p.road_id = road_id;
  p.path = grid;
  p.station_m = j["station_m"].get<double>();
  p.road_length_m = j.value("road_length_m", 0.0);
  p.frames = j.value("frames", 0);
  return p;
}

std::map<int64_t, PartialRoadInfo> partialRoads(const std::string& store) {
  std::map<int64_t, PartialRoadInfo> out;
  for (const auto& [id, path] : roadFiles(partialDir(store).string(), ".bev")) {
    if (auto p = partialRoad(store, id)) out[id] = std::move(*p);
  }
  return out;
}

StoredRoad storeRoad(const std::string& store, const RoadBev& road, bool align, const Eigen::Vector2i& correction) {
  StoredRoad s;
  s.path = roadGridPath(store, road.road_id);
  io::createDirectories(std::filesystem::path(s.path).parent_path().string());
  const auto partial = partialRoad(store, road.road_id);  // before the road's grid changes
  const BevGrid traversal = correction == Eigen::Vector2i::Zero() ? road.grid : shiftedGrid(road.grid, correction);
  BevGrid grid = traversal;
  if (std::filesystem::exists(s.path)) {
    grid = BevGrid::load(s.path);
    s.alignment = mergeAligned(traversal, grid, align);
    s.merged = true;
  }
  if (partial) {
    // An earlier drive ended on this road: its evidence completes the road now.
    s.partial_alignment = mergeAligned(BevGrid::load(partial->path), grid, align);
    s.completed_partial = true;
    nlohmann::json j = readJson(partialMeta(store, road.road_id));
    j["completed_into"] = std::to_string(gridHash(grid));
    io::writeFileAtomically(partialMeta(store, road.road_id).string(), j.dump() + "\n");
  }
  grid.save(s.path);
  if (partial) removePartial(store, road.road_id);
  fillBox(s, grid);
  return s;
}

StoredRoad storePartialRoad(const std::string& store, const RoadBev& road, double station_m, double road_length_m,
                            bool align, const Eigen::Vector2i& correction) {
  if (std::filesystem::exists(roadGridPath(store, road.road_id))) return storeRoad(store, road, align, correction);  // complete already
  StoredRoad s;
  s.path = partialGridPath(store, road.road_id);
  s.partial = true;
  s.station_m = station_m;
  s.road_length_m = road_length_m;
  io::createDirectories(partialDir(store).string());
  const BevGrid traversal = correction == Eigen::Vector2i::Zero() ? road.grid : shiftedGrid(road.grid, correction);
  BevGrid grid = traversal;
  if (const auto earlier = partialRoad(store, road.road_id)) {  // another drive ended on it too
    grid = BevGrid::load(earlier->path);
    s.alignment = mergeAligned(traversal, grid, align);
    s.merged = true;
    s.station_m = std::max(s.station_m, earlier->station_m);
  }
  grid.save(s.path);
  const nlohmann::json meta{{"road_id", road.road_id}, {"station_m", s.station_m}, {"road_length_m", road_length_m},
                            {"frames", grid.frames()}};
  io::writeFileAtomically(partialMeta(store, road.road_id).string(), meta.dump() + "\n");
  fillBox(s, grid);
  return s;
}

namespace {
std::filesystem::path checkpointDir(const std::string& store) { return std::filesystem::path(store) / "bev" / "open"; }
std::filesystem::path checkpointMeta(const std::string& store, int64_t road_id) {
  return checkpointDir(store) / ("road_" + std::to_string(road_id) + ".json");
}

// The frame count in the header of a stored grid file (BevGrid::readHeader): 0 when there is
// none, -1 when it cannot be read.
int64_t storedFrames(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return 0;
  try {
    return BevGrid::readHeader(path).frames;
  } catch (const BevError&) {
    return -1;
  }
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
