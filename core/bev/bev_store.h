// The map store's BEV part: a closed road's grid goes to <store>/bev/road_<id>.bev (BevGrid::save,
// written atomically), so a crash loses nothing and the lane mapper reads it when BEV_ROAD says so.
// A road driven again is merged into its stored grid (counts add up, frames too): more passes,
// more evidence; the new pass is aligned to the stored evidence first (core/bev/bev_align.h), as
// another drive's poses carry another offset.
//
// Checkpoints (crash recovery): the grid of a road still being driven goes to
// <store>/bev/open/road_<id>.bev every few seconds (lanemap-bev-builder, `checkpoint` in its
// config), with road_<id>.json beside it (the newest frame's time and the frame count); a BEV
// builder that restarts mid-road carries on from it, and the checkpoint is removed when the road is
// stored or given up. Each file is written atomically and durably (io::writeFileAtomically); a
// crash or power loss at any moment leaves each file at its old or its new content, and
// loadCheckpoints sorts out a pair caught between two steps (see storeCheckpoint).
#pragma once

#include "core/bev/bev_align.h"
#include "core/bev/bev_grid.h"
#include "core/bev/road_bev.h"

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace lanemap::bev {

// Adds every count of `src` to `dst`, each `shift` cells away (same resolution and tile size, else
// BevError); dst gets src's frames too.
void mergeGrid(const BevGrid& src, BevGrid& dst, const Eigen::Vector2i& shift = Eigen::Vector2i::Zero());

struct StoredRoad {
  std::string path;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // ENU corner of the grid's min cell
  double resolution = 0.0;
  int width = 0, height = 0;  // cells (BevGrid::cellBounds())
  int frames = 0;
  bool merged = false;   // the road was stored before: this traversal was merged into it
  Alignment alignment;   // the merge's (bev_align.h); !ok: merged unshifted, alignment.why says why
};

std::string roadGridPath(const std::string& store, int64_t road_id);
// The files road_<id><extension> of a folder of the map store (bev/, bev/open/, lanes/), by road
// id; none when the folder is missing. Other names are ignored.
std::map<int64_t, std::string> roadFiles(const std::string& dir, const std::string& extension);
// Writes (or merges into) the road's file; throws BevError / std::runtime_error on failure. A road
// already stored gets the new traversal aligned to it first (bev::mergeAligned: both onto the
// frame-weighted mean), unless `align` is false.
StoredRoad storeRoad(const std::string& store, const RoadBev& road, bool align = true);

struct Checkpoint {
  int64_t road_id = -1;
  int64_t last_frame_utime = 0;  // newest frame in the grid (0: unknown)
  BevGrid grid;
  std::string path;
};
std::string checkpointPath(const std::string& store, int64_t road_id);
// Writes the road's checkpoint (grid, then its JSON); throws on failure. last_frame_utime: the
// newest frame projected into it.
void storeCheckpoint(const std::string& store, const RoadBev& road, int64_t last_frame_utime);
// Removes a road's checkpoint files, durably (none: nothing happens); false when a file could not
// be removed.
bool removeCheckpoint(const std::string& store, int64_t road_id);
// Every readable checkpoint in the store, by road id; one that does not load is named in *errors
// (with why) and left on disk for a person to look at. A checkpoint whose road was stored after it
// (a crash between storeRoad and removeCheckpoint: the stored grid has more frames than when the
// checkpoint was written) is removed and its road id put in *already_stored instead.
std::vector<Checkpoint> loadCheckpoints(const std::string& store, std::vector<std::string>* errors = nullptr,
                                        std::vector<int64_t>* already_stored = nullptr);
// A hash of a grid's content (cells, counts, frames, resolution), the same whatever order its tiles
// are in: what binds a checkpoint's JSON to its grid.
uint64_t gridHash(const BevGrid& grid);

}  // namespace lanemap::bev
