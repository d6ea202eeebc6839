// "One semantic map per atomic road" (METHOD.md section 3): a BevGrid per active road E_ij,
// restricted to the road's corridor, handed over (moved out) when the road closes, so memory stays
// flat however long the drive.
//
// - Corridor: the road's skeleton polyline +- half_width_m, plus the ROI polygons of I_i and I_j
//   (the lane explorer starts in I_i's ROI and stops in I_j's), rasterised once into a bitmap of
//   mask_cell_m cells, so a splat cell is accepted with one lookup. The skeleton polyline is the
//   OSM way, i.e. the middle of the whole street; both directions share it, so half_width_m must
//   cover the whole street (all lanes, parking, sidewalk): 15 m by default.
// - RoadBevAccumulator: the active roads (normally one; a closing one may overlap the next for a
//   moment), each frame added to all of them (each keeps its corridor's cells). It also keeps the
//   splats of the last history_s seconds: a road that opens gets them replayed, because the camera
//   saw the start of E_jk while the car was still on E_ij and in I_j (and the first ~4 m past the
//   ROI are never in view once the car is on E_jk: the camera looks 4.4 m ahead of the rear axle).
//   The history is bounded by time, so memory stays flat.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/bev/projector.h"
#include "core/skeleton/skeleton.h"

#include <Eigen/Core>

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <vector>

namespace lanemap::bev {

struct CorridorOptions {
  double half_width_m = 15.0;  // either side of the skeleton polyline
  double mask_cell_m = 0.5;    // raster of the corridor mask
  bool include_rois = true;    // add the ROI polygons of both end intersections
};

class Corridor {
 public:
  Corridor(const std::vector<Eigen::Vector2d>& polyline, const std::vector<std::vector<Eigen::Vector2d>>& rois,
           const CorridorOptions& options = {});
  // For an atomic road of a skeleton (its polyline and its two intersections' ROIs).
  static Corridor forRoad(const skeleton::Skeleton& skeleton, const skeleton::AtomicRoad& road,
                          const CorridorOptions& options = {});

  bool contains(const Eigen::Vector2d& p) const;
  const Eigen::AlignedBox2d& bounds() const { return bounds_; }
  size_t cellCount() const;  // mask cells inside

 private:
  void markPolyline(const std::vector<Eigen::Vector2d>& polyline, double half_width);
  void markPolygon(const std::vector<Eigen::Vector2d>& polygon);
  Eigen::Vector2d centreOf(int x, int y) const;

  CorridorOptions options_;
  Eigen::AlignedBox2d bounds_;
  int nx_ = 0, ny_ = 0;
  std::vector<uint8_t> mask_;
};

struct RoadBev {
  int64_t road_id = -1;
  int64_t from_node = -1, to_node = -1;
  int64_t opened_utime = 0, closed_utime = 0;
  std::shared_ptr<const Corridor> corridor;
  BevGrid grid;
  int64_t cells_added = 0;  // splat cells that fell inside the corridor
  int64_t cells_outside = 0;
  // Adds the splat's cells inside the corridor; counts the frame when any was.
  void add(const FrameSplat& splat);
};

struct AccumulatorOptions {
  BevGridOptions grid;
  CorridorOptions corridor;
  double history_s = 3.0;  // splats replayed into a road that opens
};

class RoadBevAccumulator {
 public:
  explicit RoadBevAccumulator(const skeleton::Skeleton& skeleton, AccumulatorOptions options = {});

  // Starts a road (replaying the history into it). Returns false for an unknown road or one already
  // active.
  // newest_frame_utime: the replayed splats are those within history_s of this frame time
  // (default: of the newest splat added; a caller that has decided on frames it has not added
  // yet passes the newest of those, so that the replay is the same as if they had been added).
  bool open(int64_t road_id, int64_t utime, std::optional<int64_t> newest_frame_utime = std::nullopt);
  // Makes a road active again with the grid it had (a checkpoint read after a restart); false for
  // an unknown road, one already active, or a grid of another resolution or tile size.
  bool restore(int64_t road_id, BevGrid grid, int64_t utime);
  // Ends a road and hands its grid over; nullopt when it is not active.
  std::optional<RoadBev> close(int64_t road_id, int64_t utime);
  // Ends a road without handing it over (it was never completed); false when not active.
  bool discard(int64_t road_id);
  // Adds a frame to every active road and to the history.
  void add(const FrameSplat& splat);

  std::vector<int64_t> activeRoads() const;
  const RoadBev* active(int64_t road_id) const;
  size_t memoryBytes() const;  // active grids + history
  size_t historyFrames() const { return history_.size(); }

 private:
  const skeleton::Skeleton& skeleton_;
  AccumulatorOptions options_;
  std::map<int64_t, RoadBev> active_;
  std::deque<std::shared_ptr<const FrameSplat>> history_;
};

}  // namespace lanemap::bev
