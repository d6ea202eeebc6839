#include "core/bev/bev_render.h"

#include <opencv2/imgproc.hpp>

namespace lanemap::bev {

cv::Vec3b layerColour(Layer layer) {
  switch (layer) {
    case Layer::kObserved: return {70, 70, 70};
    case Layer::kDrivable: return {140, 60, 20};
    case Layer::kLaneSeparation: return {0, 220, 255};
    case Layer::kDashedLine: return {255, 255, 255};
    case Layer::kSolidLine: return {0, 140, 255};
    case Layer::kCrosswalk: return {255, 255, 0};
    case Layer::kCurb: return {0, 0, 255};
    case Layer::kStopLine: return {255, 0, 255};
    case Layer::kCount: break;
  }
  return {0, 0, 0};
}

cv::Point2d bevPixel(const BevGrid& grid, const Eigen::Vector2d& enu, int scale) {
  const auto box = grid.cellBounds();
  const double res = grid.resolution();
  return cv::Point2d((enu.x() / res - box.min().x()) * scale, (box.max().y() - enu.y() / res) * scale);
}

cv::Mat renderBev(const BevGrid& grid, const std::vector<std::vector<Eigen::Vector2d>>& polylines,
                  const RenderOptions& o) {
  const auto box = grid.cellBounds();
  if (box.isEmpty()) return cv::Mat(1, 1, CV_8UC3, cv::Scalar(0, 0, 0));
  const int w = box.sizes().x(), h = box.sizes().y(), t = grid.options().tile_cells;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
  grid.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    for (int r = 0; r < t; ++r) {
      for (int c = 0; c < t; ++c) {
        const size_t k = static_cast<size_t>(r) * t + c;
        const uint16_t seen = counts[k];
        if (!seen) continue;
        cv::Vec3b colour = layerColour(Layer::kObserved);
        for (int l = 1; l < kNumLayers; ++l) {
          if (counts[static_cast<size_t>(l) * t * t + k] >= o.min_fraction * seen) colour = layerColour(static_cast<Layer>(l));
        }
        img.at<cv::Vec3b>(box.max().y() - 1 - (origin.y() + r), origin.x() + c - box.min().x()) = colour;
      }
    }
  });
  if (o.scale > 1) cv::resize(img, img, cv::Size(), o.scale, o.scale, cv::INTER_NEAREST);
  for (const auto& line : polylines) {
    for (size_t i = 0; i + 1 < line.size(); ++i) {
      const cv::Point2d a = bevPixel(grid, line[i], o.scale), b = bevPixel(grid, line[i + 1], o.scale);
      cv::line(img, a, b, cv::Scalar(0, 200, 0), o.line_thickness, cv::LINE_AA);
    }
  }
  return img;
}

}  // namespace lanemap::bev
