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
// its grids.
//
// A small rotation can be estimated too (max_rotation_deg; off by default): a heading that drifts,
// a position bias that wanders while the car drives the road turn the evidence as well as shift it
// (0.3 degrees moves a line 0.16 m 30 m from the road's middle). After the shift search, the
// traversal's line image is turned about the middle of the cells both grids observed (the pivot,
// so the shift is still the offset where the evidence is) by every rotation_step_deg up to
// max_rotation_deg either way and matched again within a few cells of that shift; a rotation wins
// only where it correlates better than none by min_rotation_gain, after its prior (score -
// rotation_prior * degrees^2). The grids are then turned by bev_grid.h CellMove, which keeps
// every count.
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
  // Rotation: searched in steps of rotation_step_deg up to max_rotation_deg either way (0, the
  // default: shift only; kRotationSearchDeg turns it on); a rotation's score is lowered by
  // rotation_prior * degrees^2 and must beat the unturned best by min_rotation_gain (a true 0.3
  // degree turn of a 60 m road gains 0.05; on simulated drives with no heading error the best
  // turn gained 0.0001-0.004). Off by default: on the simulator's campaigns it has not yet made a
  // fused map better (README, "A small rotation in the alignment").
  static constexpr double kRotationSearchDeg = 0.5;
  double max_rotation_deg = 0.0;
  double rotation_step_deg = 0.1;
  double rotation_prior = 0.01;
  double min_rotation_gain = 0.01;
  int rotation_shift_cells = 3;   // with a rotation, shifts within this of the unrotated best
};

struct Alignment {
  bool ok = false;               // a shift was found and is trusted
  Eigen::Vector2i shift_cells = Eigen::Vector2i::Zero();  // add to the traversal's cells to match
  Eigen::Vector2d shift_m = Eigen::Vector2d::Zero();      // the same in metres (east, north)
  // Turn the traversal's cells by rotation_rad (counter-clockwise) about pivot_cell before the
  // shift (0: none found better than none). move() is both as one CellMove.
  double rotation_rad = 0.0;
  Eigen::Vector2i pivot_cell = Eigen::Vector2i::Zero();
  CellMove move() const { return CellMove{shift_cells, rotation_rad, pivot_cell}; }
  double correlation = 0.0;      // at the peak
  double margin = 0.0;           // peak minus the best correlation >= 0.5 m from it
  int overlap_cells = 0;
  std::string why;               // when !ok: why no shift is trusted
};

// The shift of `traversal` onto `reference` (same resolution, else BevError).
Alignment estimateShift(const BevGrid& reference, const BevGrid& traversal, const AlignOptions& options = {});

// `grid` with every count moved by `shift` cells, or by `move` (frames, traversals and agreement
// kept).
BevGrid shiftedGrid(const BevGrid& grid, const Eigen::Vector2i& shift);
BevGrid movedGrid(const BevGrid& grid, const CellMove& move);

// Merges `traversal` into `fused` (an empty fused grid becomes the traversal). With `align`, the
// traversal is registered first and both are moved onto the frame-weighted mean (see above), the
// rotation shared out by the same weights.
// Returns the alignment measured (!ok when not aligned, with why). A merge into evidence already
// there counts in fused.agreement() by the alignment's correlation (0 when `align` is false).
Alignment mergeAligned(const BevGrid& traversal, BevGrid& fused, bool align, const AlignOptions& options = {});

}  // namespace lanemap::bev
