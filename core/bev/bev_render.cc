#include "core/bev/bev_render.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <string>

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

BevPicture bevPicture(const BevGrid& grid, int max_px, float min_fraction) {
  if (max_px < 1) throw BevError("BEV picture: max_px must be >= 1, got " + std::to_string(max_px));
  const auto box = grid.cellBounds();
  if (box.isEmpty()) throw BevError("BEV picture of an empty grid");
  const int cols = box.sizes().x(), rows = box.sizes().y(), t = grid.options().tile_cells;
  BevPicture pic;
  pic.stride = std::max(1, (std::max(cols, rows) + max_px - 1) / max_px);
  const int s = pic.stride;
  pic.width = (cols + s - 1) / s;
  pic.height = (rows + s - 1) / s;
  // Per pixel: 1 + the strongest layer shown among its cells (0: none observed). Layers are in
  // rising order of strength, as renderBev paints them.
  cv::Mat top(pic.height, pic.width, CV_8U, cv::Scalar(0));
  grid.forEachTile([&](const BevGrid::Cell& origin, const uint16_t* counts) {
    for (int r = 0; r < t; ++r) {
      const int y = origin.y() + r - box.min().y();
      uint8_t* row = top.ptr<uint8_t>(pic.height - 1 - y / s);
      for (int c = 0; c < t; ++c) {
        const size_t k = static_cast<size_t>(r) * t + c;
        const uint16_t seen = counts[k];
        if (!seen) continue;
        uint8_t best = 1;  // kObserved + 1
        for (int l = kNumLayers - 1; l >= 1; --l) {
          if (counts[static_cast<size_t>(l) * t * t + k] >= min_fraction * seen) {
            best = static_cast<uint8_t>(l + 1);
            break;
          }
        }
        uint8_t& px = row[(origin.x() + c - box.min().x()) / s];
        px = std::max(px, best);
      }
    }
  });
  cv::Mat bgra(pic.height, pic.width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (int r = 0; r < pic.height; ++r) {
    const uint8_t* in = top.ptr<uint8_t>(r);
    auto* out = bgra.ptr<cv::Vec4b>(r);
    for (int c = 0; c < pic.width; ++c) {
      if (!in[c]) continue;
      const cv::Vec3b colour = layerColour(static_cast<Layer>(in[c] - 1));
      out[c] = cv::Vec4b(colour[0], colour[1], colour[2], in[c] == 1 ? kPictureBackgroundAlpha : 255);
    }
  }
  if (!cv::imencode(".png", bgra, pic.png)) throw BevError("cannot encode a BEV picture");
  const double res = grid.resolution();
  const Eigen::Vector2d lo = box.min().cast<double>() * res;
  pic.enu = Eigen::AlignedBox2d(lo, lo + Eigen::Vector2d(pic.width, pic.height) * (s * res));
  return pic;
}

}  // namespace lanemap::bev
