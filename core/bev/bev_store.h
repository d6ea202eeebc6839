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
//
// Partial roads (issue 14): the road the car is on when a drive ends never closes. Its grid goes
// to <store>/bev/partial/road_<id>.bev with road_<id>.json beside it (the station reached along
// the road, the road's length, the grid's hash): storePartialRoad. Two drives ending on one road
// merge there (aligned, the further station kept). A later drive that closes the road completes
// it: storeRoad merges the partial evidence into the road's grid (aligned) and removes the
// partial files. Before the road's grid is saved the partial's JSON names the hash of the grid
// that will hold it ("completed_into"), so a crash between saving and removing is recognised
// (the stored grid has that hash) and the partial is not merged a second time.
#pragma once

#include "core/bev/bev_align.h"
#include "core/bev/bev_grid.h"
#include "core/bev/road_bev.h"

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::bev {

// Adds every count of `src` to `dst`, each cell moved by `move` (same resolution and tile size,
// else BevError); dst gets src's frames too.
void mergeGrid(const BevGrid& src, BevGrid& dst, const CellMove& move);
inline void mergeGrid(const BevGrid& src, BevGrid& dst, const Eigen::Vector2i& shift = Eigen::Vector2i::Zero()) {
  mergeGrid(src, dst, CellMove{shift});
}

struct StoredRoad {
  std::string path;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // ENU corner of the grid's min cell
  double resolution = 0.0;
  int width = 0, height = 0;  // cells (BevGrid::cellBounds())
  int frames = 0;
  bool merged = false;   // the road was stored before: this traversal was merged into it
  Alignment alignment;   // the merge's (bev_align.h); !ok: merged unshifted, alignment.why says why
  // storePartialRoad: the road is stored partial (path: its partial grid), driven to station_m of
  // road_length_m. False when the road was complete already (the traversal joined its grid).
  bool partial = false;
  double station_m = 0.0, road_length_m = 0.0;
  // storeRoad: a partial of the road (an earlier drive ended on it) was merged in and removed.
  bool completed_partial = false;
  Alignment partial_alignment;  // that merge's
};

// A partial road of the store: its grid and how far it was driven.
struct PartialRoadInfo {
  int64_t road_id = -1;
  std::string path;  // the grid
  double station_m = 0.0, road_length_m = 0.0;
  int frames = 0;
};

std::string roadGridPath(const std::string& store, int64_t road_id);
// The files road_<id><extension> of a folder of the map store (bev/, bev/open/, lanes/), by road
// id; none when the folder is missing. Other names are ignored.
std::map<int64_t, std::string> roadFiles(const std::string& dir, const std::string& extension);
// Writes (or merges into) the road's file; throws BevError / std::runtime_error on failure. A road
// already stored gets the new traversal aligned to it first (bev::mergeAligned: both onto the
// frame-weighted mean), unless `align` is false.
// A partial of the road (storePartialRoad) is merged in as well (aligned when `align`) and
// removed: the road is complete now. `correction` (cells) moves the traversal first (this drive's
// offset onto the store's drives, bev::LiveDriveOffset).
StoredRoad storeRoad(const std::string& store, const RoadBev& road, bool align = true,
                     const Eigen::Vector2i& correction = Eigen::Vector2i::Zero());

std::string partialGridPath(const std::string& store, int64_t road_id);
// Stores the road a drive ended on, driven to station_m (arc length along the road) of
// road_length_m: into its partial grid (merged, aligned, into one already there; the station is the
// further one). A road already complete in the store gets the traversal merged into its grid as
// storeRoad does (the result is not partial). `correction` as for storeRoad. Throws like storeRoad.
StoredRoad storePartialRoad(const std::string& store, const RoadBev& road, double station_m, double road_length_m,
                            bool align = true, const Eigen::Vector2i& correction = Eigen::Vector2i::Zero());
// The road's partial (nullopt: none, or one already merged into the road's grid by a storeRoad a
// crash cut short, which is removed now). A grid without its JSON (a crash between the two) is no
// partial: its station is unknown.
std::optional<PartialRoadInfo> partialRoad(const std::string& store, int64_t road_id);
// Every partial road of the store, by road id.
std::map<int64_t, PartialRoadInfo> partialRoads(const std::string& store);

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
