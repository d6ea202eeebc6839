// A picture of a BEV grid (lanemap-render --bev): north up, one pixel per cell (times `scale`),
// each layer in its own colour where its fraction of the observations reaches min_fraction, the
// strongest evidence painted last: unobserved black, observed grey, drivable blue, lane separation
// yellow, dashed white, solid orange, crosswalk cyan, curb red, stop line magenta; polylines (the
// skeleton) in green over it.
#pragma once

#include "core/bev/bev_grid.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
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

// A picture of a grid for people to look at (the viewer): BGRA PNG, north up, at most max_px pixels
// on its longest side (one pixel per `stride` x `stride` cells, the strongest evidence among them
// wins, so thin lines stay visible when it is shrunk), unobserved cells transparent and cells seen
// only as background faint (alpha kPictureBackgroundAlpha), so a map under it shows through.
// `enu` is the ENU extent the picture covers (south-west corner = the allocated area's, a whole
// number of strides). Cost: the allocated cells once (a road's corridor: a few ms).
inline constexpr uint8_t kPictureBackgroundAlpha = 64;
struct BevPicture {
  std::vector<unsigned char> png;
  Eigen::AlignedBox2d enu;
  int width = 0, height = 0, stride = 1;
};
// Throws BevError on a grid with no allocated cell or max_px < 1.
BevPicture bevPicture(const BevGrid& grid, int max_px, float min_fraction = RenderOptions{}.min_fraction);

// Pixel (column, row) of an ENU point in renderBev's picture of `grid`.
cv::Point2d bevPixel(const BevGrid& grid, const Eigen::Vector2d& enu, int scale = 1);

}  // namespace lanemap::bev
