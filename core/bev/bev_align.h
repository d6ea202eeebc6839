// Aligning a traversal's BEV evidence to a road's fused evidence before they are merged (issue 14,
// the city map from many drives).
//
// Every drive carries its own GNSS/INS error: besides the noise, an offset of decimetres that
// stays for the whole drive. Two traversals of one road merged as they are (counts added) blur
// every line by that offset. Here a traversal is registered to what is stored by the one thing
// both see the same way: the road's lines (painted dashed and solid lines, lane separations,
// curbs, stop lines). Each grid becomes a "line image" (the share of observations that saw a
// line, per cell, smoothed by a Gaussian so nearby lines attract), and the integer-cell shift
// that maximises the normalised cross-correlation of the two images inside a search window is the
// traversal's offset. A shift is trusted only with enough overlap and correlation; otherwise the
// traversal is merged unshifted and the reason is given. Along a road whose lines are continuous
// the along-road shift is weakly determined (dashes, stop lines and curb ends fix it): a small
// prior prefers the smaller shift there; the lateral shift, which decides where the lanes are, is
// what the lines pin.
//
// No drive is special: the fused grid stands for the mean of the traversals merged so far (their
// common estimate), each weighted by its frames (the evidence it brought), not for the first one.
// With n frames fused and a traversal of m frames measured s cells away from them, the fused grid
// moves by -s m/(n+m) and the traversal by s n/(n+m), so both land on the weighted mean of all
// (rounded to whole cells); n and m are the grids' frame counts, so a store needs no record beside
// its grids. Rotation is not estimated (a heading bias of 0.05 degrees moves a line 9 cm over
// 100 m).
#pragma once

#include "core/bev/bev_grid.h"

#include <Eigen/Core>

#include <string>

namespace lanemap::bev {

struct AlignOptions {
  double search_m = 1.5;          // the largest offset looked for, per axis
  double smooth_sigma_m = 0.2;    // Gaussian on the line images (lines are 0.1-0.3 m wide)
  int min_overlap_cells = 4000;   // cells observed in both grids (40 m^2 at 0.1 m)
  double min_correlation = 0.3;   // normalised cross-correlation at the peak
  // Along a road of continuous lines the correlation hardly changes with the along-road shift:
  // among near-equal scores the smaller shift wins (score - shift_prior * |shift in m|^2).
  double shift_prior = 0.003;
  double min_peak_margin = 0.0;   // required peak over the best score >= 0.5 m from it (reported)
};

struct Alignment {
  bool ok = false;               // a shift was found and is trusted
  Eigen::Vector2i shift_cells = Eigen::Vector2i::Zero();  // add to the traversal's cells to match
  Eigen::Vector2d shift_m = Eigen::Vector2d::Zero();      // the same in metres (east, north)
  double correlation = 0.0;      // at the peak
  double margin = 0.0;           // peak minus the best correlation >= 0.5 m from it
  int overlap_cells = 0;
  std::string why;               // when !ok: why no shift is trusted
};

// The shift of `traversal` onto `reference` (same resolution, else BevError).
Alignment estimateShift(const BevGrid& reference, const BevGrid& traversal, const AlignOptions& options = {});

// `grid` with every count moved by `shift` cells (frames, traversals and agreement kept).
BevGrid shiftedGrid(const BevGrid& grid, const Eigen::Vector2i& shift);

// Merges `traversal` into `fused` (an empty fused grid becomes the traversal). With `align`, the
// traversal is registered first and both are moved onto the frame-weighted mean (see above).
// Returns the alignment measured (!ok when not aligned, with why). A merge into evidence already
// there counts in fused.agreement() by the alignment's correlation (0 when `align` is false).
Alignment mergeAligned(const BevGrid& traversal, BevGrid& fused, bool align, const AlignOptions& options = {});

}  // namespace lanemap::bev
