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

}  // namespace lanemap::bev
