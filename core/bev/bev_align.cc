#include "core/bev/bev_align.h"

#include "core/bev/bev_store.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace lanemap::bev {

namespace {

// The share of a cell's observations that saw a line of any kind, over the cells of `box`
// (row = north index - box.min().y()); *observed (optional): 1 where the cell was observed.
cv::Mat lineImage(const BevGrid& g, const Eigen::AlignedBox2i& box, cv::Mat* observed) {
  const int w = box.sizes().x(), h = box.sizes().y();
  cv::Mat img(h, w, CV_32F, cv::Scalar(0));
  if (observed) *observed = cv::Mat(h, w, CV_8U, cv::Scalar(0));
  const int t = g.options().tile_cells;
  const size_t plane = static_cast<size_t>(t) * t;
  g.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    for (int r = 0; r < t; ++r) {
      const int y = origin.y() + r - box.min().y();
      if (y < 0 || y >= h) continue;
      for (int c = 0; c < t; ++c) {
        const int x = origin.x() + c - box.min().x();
        if (x < 0 || x >= w) continue;
        const size_t i = static_cast<size_t>(r) * t + c;
        const double n = counts[static_cast<size_t>(Layer::kObserved) * plane + i];
        if (n <= 0) continue;
        double lines = 0;
        for (Layer l : {Layer::kLaneSeparation, Layer::kDashedLine, Layer::kSolidLine, Layer::kCurb, Layer::kStopLine}) {
          lines += counts[static_cast<size_t>(l) * plane + i];
        }
        img.at<float>(y, x) = static_cast<float>(std::min(1.0, lines / n));
        if (observed) observed->at<uint8_t>(y, x) = 1;
      }
    }
  });
  return img;
}

Eigen::AlignedBox2i grown(const Eigen::AlignedBox2i& b, int by) {
  return Eigen::AlignedBox2i(b.min() - Eigen::Vector2i(by, by), b.max() + Eigen::Vector2i(by, by));
}

}  // namespace

Alignment estimateShift(const BevGrid& reference, const BevGrid& traversal, const AlignOptions& o) {
  if (reference.resolution() != traversal.resolution() ||
      reference.options().tile_cells != traversal.options().tile_cells) {
    throw BevError("cannot align BEV grids of different resolution or tile size");
  }
  Alignment a;
  const double res = reference.resolution();
  const int radius = std::max(1, static_cast<int>(std::lround(o.search_m / res)));
  const Eigen::AlignedBox2i box = reference.cellBounds().intersection(traversal.cellBounds());
  if (box.isEmpty() || box.sizes().minCoeff() <= 2 * radius) {
    a.why = "the grids do not overlap";
    return a;
  }
  // A long diagonal road's box is mostly empty; past ~40 M cells (a 630 m square at 0.1 m: ~0.5 GB
  // of images) the road is merged unaligned rather than risk the memory.
  if (static_cast<double>(box.sizes().x() + 2 * radius) * (box.sizes().y() + 2 * radius) > 40e6) {
    a.why = "the overlap's box is too large to align (" + std::to_string(box.sizes().x()) + " x " +
            std::to_string(box.sizes().y()) + " cells)";
    return a;
  }
  cv::Mat seen_t, seen_r;
  cv::Mat templ = lineImage(traversal, box, &seen_t);
  cv::Mat search = lineImage(reference, grown(box, radius), &seen_r);
  cv::Mat both;
  cv::bitwise_and(seen_t, seen_r(cv::Rect(radius, radius, templ.cols, templ.rows)), both);
  a.overlap_cells = cv::countNonZero(both);
  if (a.overlap_cells < o.min_overlap_cells) {
    a.why = "overlap of " + std::to_string(a.overlap_cells) + " cells, fewer than " + std::to_string(o.min_overlap_cells);
    return a;
  }
  // Zero-mean over the observed cells and 0 elsewhere: where a grid's observed area ends (the
  // road corridor's edge, fixed in the map frame whatever the pose error) is no feature.
  for (auto [img, seen] : {std::pair<cv::Mat*, cv::Mat*>{&templ, &seen_t}, {&search, &seen_r}}) {
    const double mean = cv::mean(*img, *seen)[0];
    cv::subtract(*img, cv::Scalar(mean), *img, *seen);
  }
  if (o.smooth_sigma_m > 0) {
    const double sigma = o.smooth_sigma_m / res;
    cv::GaussianBlur(templ, templ, cv::Size(), sigma);
    cv::GaussianBlur(search, search, cv::Size(), sigma);
  }
  // The prior on a shift of (sx, sy) cells (see shift_prior).
  const auto shiftPrior = [&](int sx, int sy) {
    const double dx = sx * res, dy = sy * res;
    return o.shift_prior * (dx * dx + dy * dy);
  };
  cv::Mat score;
  cv::matchTemplate(search, templ, score, cv::TM_CCORR_NORMED);  // (2 radius + 1)^2
  for (int y = 0; y < score.rows; ++y) {
    for (int x = 0; x < score.cols; ++x) score.at<float>(y, x) -= static_cast<float>(shiftPrior(x - radius, y - radius));
  }
  double best = 0;
  cv::Point at;
  cv::minMaxLoc(score, nullptr, &best, nullptr, &at);
  a.correlation = best;
  a.shift_cells = Eigen::Vector2i(at.x - radius, at.y - radius);
  a.shift_m = a.shift_cells.cast<double>() * res;
  // How clear the peak is: the best score at least 0.5 m away from it.
  const int away = std::max(1, static_cast<int>(std::lround(0.5 / res)));
  double second = -1;
  for (int y = 0; y < score.rows; ++y) {
    for (int x = 0; x < score.cols; ++x) {
      if (std::max(std::abs(x - at.x), std::abs(y - at.y)) >= away) second = std::max(second, static_cast<double>(score.at<float>(y, x)));
    }
  }
  a.margin = best - second;
  if (!(best >= o.min_correlation)) {
    a.why = "line correlation " + std::to_string(best) + " below " + std::to_string(o.min_correlation);
    return a;
  }
  if (a.margin < o.min_peak_margin) {
    a.why = "no clear peak (margin " + std::to_string(a.margin) + ")";
    return a;
  }
  a.ok = true;
  if (o.max_rotation_deg > 0.0 && o.rotation_step_deg > 0.0) {
    // The pivot: the middle of the cells both grids observed, so that the shift stays the offset
    // where the evidence is (drive_offsets.h reads it so) whatever the rotation.
    const cv::Moments mo = cv::moments(both, true);
    const cv::Point pivot(static_cast<int>(std::lround(mo.m10 / mo.m00)), static_cast<int>(std::lround(mo.m01 / mo.m00)));
    a.pivot_cell = box.min() + Eigen::Vector2i(pivot.x, pivot.y);
    // The template turned about the pivot, matched within rotation_shift_cells of the shift.
    const int k = std::max(0, o.rotation_shift_cells);
    const int x_lo = std::max(0, at.x - k), x_hi = std::min(2 * radius, at.x + k);
    const int y_lo = std::max(0, at.y - k), y_hi = std::min(2 * radius, at.y + k);
    const cv::Mat window = search(cv::Rect(x_lo, y_lo, templ.cols + x_hi - x_lo, templ.rows + y_hi - y_lo));
    const int steps = static_cast<int>(std::floor(o.max_rotation_deg / o.rotation_step_deg + 1e-9));
    // A rotation must beat none by min_rotation_gain: the correlation hardly changes with a turn
    // of a tenth of a degree, which moves a line a few centimetres over a road.
    double turned_best = best + o.min_rotation_gain;
    cv::Mat turned, sc;
    for (int i = -steps; i <= steps; ++i) {
      if (i == 0) continue;
      const double deg = i * o.rotation_step_deg, rad = deg * M_PI / 180.0;
      // dst(q) = src(R(-rad) (q - pivot) + pivot): the content turned by +rad (x east, y north).
      const double c = std::cos(rad), sn = std::sin(rad);
      const cv::Matx23d m(c, sn, pivot.x - (c * pivot.x + sn * pivot.y), -sn, c, pivot.y - (-sn * pivot.x + c * pivot.y));
      cv::warpAffine(templ, turned, m, templ.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, 0);
      cv::matchTemplate(window, turned, sc, cv::TM_CCORR_NORMED);
      for (int y = 0; y < sc.rows; ++y) {
        for (int x = 0; x < sc.cols; ++x) {
          const Eigen::Vector2i shift(x + x_lo - radius, y + y_lo - radius);
          const double v = sc.at<float>(y, x) - shiftPrior(shift.x(), shift.y()) - o.rotation_prior * deg * deg;
          if (v > turned_best) {
            turned_best = v;
            a.correlation = v;
            a.rotation_rad = rad;
            a.shift_cells = shift;
          }
        }
      }
    }
    a.shift_m = a.shift_cells.cast<double>() * res;
  }
  return a;
}

BevGrid shiftedGrid(const BevGrid& grid, const Eigen::Vector2i& shift) { return movedGrid(grid, CellMove{shift}); }

BevGrid movedGrid(const BevGrid& grid, const CellMove& move) {
  BevGrid out(grid.options());
  mergeGrid(grid, out, move);
  return out;
}

Alignment mergeAligned(const BevGrid& traversal, BevGrid& fused, bool align, const AlignOptions& o) {
  Alignment a;
  if (fused.tileCount() == 0) {
    mergeGrid(traversal, fused);
    a.why = "the first traversal";
    return a;
  }
  if (align) a = estimateShift(fused, traversal, o);
  if (!align) a.why = "alignment off";
  if (!a.ok) {
    mergeGrid(traversal, fused);
    fused.addMerge(align ? a.correlation : 0.0);  // unaligned: how well they agree is not known
    return a;
  }
  // Both onto the frame-weighted mean: fused by -s m/(n+m), the traversal by s - s m/(n+m); the
  // rotation likewise, both about the alignment's pivot (for a few tenths of a degree, turning the
  // shift too would move it under a tenth of a cell).
  const double n = std::max(1, fused.frames()), m = std::max(1, traversal.frames());
  const double w = m / (n + m);
  CellMove fused_move{Eigen::Vector2i(static_cast<int>(std::lround(-a.shift_cells.x() * w)),
                                      static_cast<int>(std::lround(-a.shift_cells.y() * w))),
                      -a.rotation_rad * w, a.pivot_cell};
  const CellMove traversal_move{a.shift_cells + fused_move.shift, a.rotation_rad + fused_move.rotation_rad, a.pivot_cell};
  if (!fused_move.identity()) fused = movedGrid(fused, fused_move);
  mergeGrid(traversal, fused, traversal_move);
  fused.addMerge(a.correlation);
  return a;
}

}  // namespace lanemap::bev
