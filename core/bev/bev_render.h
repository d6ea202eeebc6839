// A picture of a BEV grid (lanemap-render --bev): north up, one pixel per cell (times `scale`),
// each layer in its own colour where its fraction of the observations reaches min_fraction, the
// strongest evidence painted last: unobserved black, observed grey, drivable blue, lane separation
// yellow, dashed white, solid orange, crosswalk cyan, curb red, stop line magenta; polylines (the
// skeleton) in green over it.
#pragma once

#include "core/bev/bev_grid.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace lanemap::bev {

struct RenderOptions {
  int scale = 1;               // pixels per cell side
  float min_fraction = 0.3f;   // a layer shows where count / observed reaches this
  int line_thickness = 2;
};

// BGR colour of a layer in the picture.
cv::Vec3b layerColour(Layer layer);

// Renders the grid's allocated area. polylines: ENU metres (e.g. the skeleton's roads).
cv::Mat renderBev(const BevGrid& grid, const std::vector<std::vector<Eigen::Vector2d>>& polylines = {},
                  const RenderOptions& options = {});

// Pixel (column, row) of an ENU point in renderBev's picture of `grid`.
cv::Point2d bevPixel(const BevGrid& grid, const Eigen::Vector2d& enu, int scale = 1);

}  // namespace lanemap::bev
