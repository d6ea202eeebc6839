// Each drive's own pose offset, estimated jointly from every road two drives share (issue 14: "align
// all traversals of a road to their common estimate rather than to the first one").
//
// bev::mergeAligned moves a road's traversals onto their mean, road by road. A road driven once
// keeps its drive's offset (decimetres: a drive's GNSS/INS error stays for the whole drive), and the
// same drive's other roads, shared with other drives, say what that offset is. Here every pair of
// drives that both saw a road gives one measurement of the difference of their offsets
// (estimateShift of one's grid onto the other's: o_i - o_j = shift of j onto i); the offsets are the
// least-squares solution, weighted by each shift's correlation, with the mean offset of the drives
// linked by shared roads set to zero (the common estimate; nothing says where the truth is). A
// drive linked to no other keeps a zero offset. Its evidence is then moved by -offset (whole cells)
// before any merge, so a road driven once lands where the drives agree the world is.
#pragma once

#include "core/bev/bev_align.h"
#include "core/bev/bev_grid.h"

#include <Eigen/Core>

#include <cstdint>
#include <set>
#include <utility>
#include <vector>

namespace lanemap::bev {

struct DriveOffsets {
  std::vector<Eigen::Vector2d> offset_m;  // per drive: where its evidence lands off the common estimate
  std::vector<int> measurements;          // per drive: pairwise shifts it took part in (0: offset 0)
  std::vector<int> component;             // per drive: drives linked by shared roads share a number
};

// The whole cells that move a drive's evidence onto the common estimate: -offset, rounded.
Eigen::Vector2i correctionCells(const Eigen::Vector2d& offset_m, double resolution_m);

class DriveOffsetSolver {
 public:
  explicit DriveOffsetSolver(size_t drives, AlignOptions options = {}) : drives_(drives), options_(options) {}
  // One road's evidence per drive that saw it (drive index, its grid of the road: all of that
  // drive's traversals of it merged); every pair of them is registered. Returns the pairs trusted.
  int addRoad(const std::vector<std::pair<size_t, const BevGrid*>>& grids);
  DriveOffsets solve() const;

 private:
  struct Pair {
    size_t i, j;
    Eigen::Vector2d shift_m;  // o_i - o_j
    double weight;
  };
  size_t drives_;
  AlignOptions options_;
  std::vector<Pair> pairs_;
};

// The same offset learned while a drive goes on (the live BEV builder storing into a map store other
// drives filled): every road of this drive merged onto stored evidence with a trusted alignment
// measures the drive's correction (the shift already applied to its grid plus the alignment's
// residual). Once min_roads of them agree (each within max_spread_m of their frame-weighted mean),
// that mean, in whole cells, is the correction applied to the drive's later roads before they are
// stored: a road this drive alone saw lands where the store's drives put the world, instead of off
// by this drive's GNSS/INS offset. Until then, or while the measurements disagree (a wrong
// alignment), the correction is zero. Only the roads stored after the estimate holds are moved.
struct DriveOffsetOptions {
  bool enabled = true;
  int min_roads = 2;            // trusted alignments needed before any correction
  double max_spread_m = 0.3;    // each measurement within this of the mean, else none is applied
};

class LiveDriveOffset {
 public:
  explicit LiveDriveOffset(DriveOffsetOptions options = {}, double resolution_m = 0.1)
      : options_(options), resolution_m_(resolution_m) {}
  // The correction (cells) to apply to the next road's grid before storing it.
  Eigen::Vector2i correction() const { return correction_; }
  // A road stored with `applied` cells of correction and merged onto stored evidence with alignment
  // `a` (its traversal's `frames` weigh it). An untrusted alignment (or a first traversal) is no
  // measurement.
  void addMerge(const Eigen::Vector2i& applied, const Alignment& a, int frames);
  // Every road this drive stores, merged or not: a merge onto a road this drive stored before is
  // onto its own evidence and measures nothing; any other merge is addMerge.
  void addStored(int64_t road_id, bool merged, const Eigen::Vector2i& applied, const Alignment& a, int frames);
  int measurements() const { return static_cast<int>(measured_.size()); }
  bool consistent() const { return consistent_; }

 private:
  DriveOffsetOptions options_;
  double resolution_m_;
  std::vector<std::pair<Eigen::Vector2d, double>> measured_;  // correction (cells), weight
  std::set<int64_t> stored_;                                   // roads this drive stored
  Eigen::Vector2i correction_ = Eigen::Vector2i::Zero();
  bool consistent_ = true;
};

}  // namespace lanemap::bev
