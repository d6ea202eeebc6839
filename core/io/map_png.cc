// PNG picture of a LaneMap (see map_png.h).
#include "core/io/map_png.h"

#include "core/geo/polyline.h"
#include "core/io/lanelet2.h"
#include "core/skeleton/skeleton.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lanemap::io {

using namespace map_png_colours;

cv::Point2d MapImageInfo::toPixel(const Eigen::Vector2d& enu) const {
  return {(enu.x() - bbox.min().x()) / metres_per_pixel, (bbox.max().y() - enu.y()) / metres_per_pixel};
}

std::vector<std::vector<Eigen::Vector2d>> skeletonPolylines(const skeleton::Skeleton& skeleton) {
  std::vector<std::vector<Eigen::Vector2d>> out;
  for (const auto& road : skeleton.roads()) out.push_back(road.polyline);
  return out;
}

namespace {

constexpr int kShift = 4;  // sub-pixel bits for OpenCV drawing
constexpr int kMinWidthPx = 480;  // room for the scale bar and the attribution

using Polyline = std::vector<Eigen::Vector2d>;

Polyline toPolyline2d(const std::vector<Eigen::Vector3d>& pts) {
  Polyline out;
  out.reserve(pts.size());
  for (const auto& p : pts) out.push_back(p.head<2>());
  return out;
}

// The piece of a polyline between arc lengths s0 and s1.
Polyline slice(const Polyline& pts, double s0, double s1) {
  Polyline out;
  double s = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) {
    const double seg = (pts[i] - pts[i - 1]).norm();
    if (seg <= 0.0) continue;
    const double a = std::max(s0, s), b = std::min(s1, s + seg);
    if (a < b) {
      const Eigen::Vector2d pa = pts[i - 1] + (a - s) / seg * (pts[i] - pts[i - 1]);
      const Eigen::Vector2d pb = pts[i - 1] + (b - s) / seg * (pts[i] - pts[i - 1]);
      if (out.empty() || (out.back() - pa).norm() > 1e-9) out.push_back(pa);
      out.push_back(pb);
    }
    s += seg;
    if (s >= s1) break;
  }
  return out;
}

// The polyline moved sideways by `offset` metres (left positive), vertex normals averaged.
Polyline offsetPolyline(const Polyline& pts, double offset) {
  Polyline out;
  for (size_t i = 0; i < pts.size(); ++i) {
    Eigen::Vector2d dir = Eigen::Vector2d::Zero();
    if (i > 0) dir += (pts[i] - pts[i - 1]).normalized();
    if (i + 1 < pts.size()) dir += (pts[i + 1] - pts[i]).normalized();
    if (dir.norm() < 1e-9) dir = Eigen::Vector2d::UnitX();
    dir.normalize();
    out.push_back(pts[i] + offset * Eigen::Vector2d(-dir.y(), dir.x()));
  }
  return out;
}

class Painter {
 public:
  Painter(cv::Mat& img, const MapImageInfo& info) : img_(img), info_(info) {}

  int px(double metres, int min_px) const {
    return std::max(min_px, static_cast<int>(std::lround(metres / info_.metres_per_pixel)));
  }
  double metres(double pixels) const { return pixels * info_.metres_per_pixel; }

  std::vector<cv::Point> points(const Polyline& pts) const {
    std::vector<cv::Point> out;
    out.reserve(pts.size());
    for (const auto& p : pts) {
      const cv::Point2d q = info_.toPixel(p);
      out.emplace_back(cvRound(q.x * (1 << kShift)), cvRound(q.y * (1 << kShift)));
    }
    return out;
  }

  void polyline(const Polyline& pts, const cv::Scalar& colour, int thickness) {
    if (pts.size() < 2) return;
    const auto p = points(pts);
    cv::polylines(img_, std::vector<std::vector<cv::Point>>{p}, false, colour, thickness, cv::LINE_AA, kShift);
  }

  void polygon(const Polyline& ring, const cv::Scalar& colour) {
    if (ring.size() < 3) return;
    const auto p = points(ring);
    // Not anti-aliased: neighbouring lanelets share edges, and blended edges would leave seams.
    cv::fillPoly(img_, std::vector<std::vector<cv::Point>>{p}, colour, cv::LINE_8, kShift);
  }

  void dashed(const Polyline& pts, const cv::Scalar& colour, int thickness, double dash_m, double gap_m) {
    const double total = geo::polylineLength(pts);
    for (double s = 0.0; s < total; s += dash_m + gap_m) polyline(slice(pts, s, s + dash_m), colour, thickness);
  }

  // A small arrow in the middle of a centre line, pointing in the driving direction.
  void directionArrow(const Polyline& pts, const cv::Scalar& colour) {
    const double total = geo::polylineLength(pts);
    const double arrow = std::max(2.0, metres(10));
    if (total < 2.0 * arrow) return;
    const Polyline piece = slice(pts, 0.5 * total - 0.5 * arrow, 0.5 * total + 0.5 * arrow);
    if (piece.size() < 2) return;
    const auto p = points({piece.front(), piece.back()});
    cv::arrowedLine(img_, p[0], p[1], colour, 1, cv::LINE_AA, kShift, 0.6);
  }

 private:
  cv::Mat& img_;
  const MapImageInfo& info_;
};

Eigen::AlignedBox2d defaultExtent(const map::LaneMap& map, const MapPngOptions& options) {
  Eigen::AlignedBox2d box;  // empty
  for (const auto& l : map.lines) for (const auto& p : l.points) box.extend(p.head<2>());
  for (const auto& ll : map.lanelets) for (const auto& p : ll.centre) box.extend(p.head<2>());
  for (const auto& pl : options.background_polylines) for (const auto& p : pl) box.extend(p);
  if (box.isEmpty()) box = Eigen::AlignedBox2d(Eigen::Vector2d(-50, -50), Eigen::Vector2d(50, 50));
  const Eigen::Vector2d margin = Eigen::Vector2d::Constant(std::max(0.0, options.margin_m));
  return Eigen::AlignedBox2d(box.min() - margin, box.max() + margin);
}

void drawLanelets(Painter& painter, const map::LaneMap& map) {
  // Intersection lanelets overlap one another; road lanelets go on top of them.
  for (const auto kind : {map::LaneletKind::kIntersection, map::LaneletKind::kRoad}) {
    for (const auto& ll : map.lanelets) {
      if (ll.kind != kind) continue;
      painter.polygon(toPolyline2d(laneletOutline(map, ll)),
                      kind == map::LaneletKind::kRoad ? kRoadLane : kIntersectionLane);
    }
  }
}

void drawBoundary(Painter& painter, const map::LineString& line) {
  const Polyline pts = toPolyline2d(line.points);
  const int marking = painter.px(0.15, 1);
  switch (line.type) {
    case map::LineType::kDashed: painter.dashed(pts, kMarking, marking, 3.0, 3.0); break;
    case map::LineType::kSolid: painter.polyline(pts, kMarking, marking); break;
    case map::LineType::kSolidSolid: {
      const double half_gap = std::max(0.12, painter.metres(1.5));
      painter.polyline(offsetPolyline(pts, half_gap), kDoubleSolid, marking);
      painter.polyline(offsetPolyline(pts, -half_gap), kDoubleSolid, marking);
      break;
    }
    case map::LineType::kCurb: painter.polyline(pts, kCurb, painter.px(0.3, 2)); break;
    case map::LineType::kVirtual: painter.polyline(pts, kVirtual, 1); break;
    case map::LineType::kStopLine: painter.polyline(pts, kStopLine, painter.px(0.4, 2)); break;
  }
}

void drawBoundaries(Painter& painter, const map::LaneMap& map) {
  // Virtual lines first, stop lines last, so real markings stay visible where lines meet.
  const auto rank = [](map::LineType t) {
    return t == map::LineType::kVirtual ? 0 : t == map::LineType::kStopLine ? 2 : 1;
  };
  for (int r = 0; r <= 2; ++r) {
    for (const auto& line : map.lines) {
      if (rank(line.type) == r) drawBoundary(painter, line);
    }
  }
}

// 1, 2 or 5 times a power of ten, near a fifth of the map's width.
double niceScaleLength(double width_m) {
  const double target = std::max(width_m / 5.0, 1e-3);
  const double power = std::pow(10.0, std::floor(std::log10(target)));
  for (const double f : {5.0, 2.0, 1.0}) {
    if (f * power <= target) return f * power;
  }
  return power;
}

void drawFooter(cv::Mat& img, const MapImageInfo& info, int map_width_px, const std::string& attribution) {
  const int top = info.map_height_px;
  const int h = info.footer_height_px;
  cv::rectangle(img, cv::Rect(0, top, img.cols, h), cv::Scalar(255, 255, 255), cv::FILLED);
  cv::line(img, cv::Point(0, top), cv::Point(img.cols - 1, top), cv::Scalar(160, 160, 160), 1);
  const double font = 0.45 * h / 28.0;
  const int baseline_y = top + h / 2 + static_cast<int>(5 * h / 28.0);

  // Scale bar: alternating black/white halves, end ticks, label.
  const double len_m = niceScaleLength(map_width_px * info.metres_per_pixel);
  const int len_px = std::max(1, static_cast<int>(std::lround(len_m / info.metres_per_pixel)));
  const int x0 = 10, y = top + h / 2, bar_h = std::max(4, h / 6);
  cv::rectangle(img, cv::Rect(x0, y - bar_h / 2, len_px, bar_h), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::rectangle(img, cv::Rect(x0 + len_px / 2, y - bar_h / 2 + 1, len_px - len_px / 2 - 1, bar_h - 2),
                cv::Scalar(255, 255, 255), cv::FILLED);
  char label[32];
  if (len_m >= 1000.0) {
    std::snprintf(label, sizeof(label), "%g km", len_m / 1000.0);
  } else {
    std::snprintf(label, sizeof(label), "%g m", len_m);
  }
  cv::putText(img, label, cv::Point(x0 + len_px + 8, baseline_y), cv::FONT_HERSHEY_SIMPLEX, font,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);

  int baseline = 0;
  const cv::Size text = cv::getTextSize(attribution, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline);
  cv::putText(img, attribution, cv::Point(img.cols - text.width - 8, baseline_y), cv::FONT_HERSHEY_SIMPLEX,
              font, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
}

}  // namespace

cv::Mat renderMapImage(const map::LaneMap& map, const MapPngOptions& options, MapImageInfo* info_out) {
  if (!(options.metres_per_pixel > 0.0) || options.max_image_size <= 0) {
    throw IoError("renderMapImage: metres_per_pixel and max_image_size must be positive (got " +
                  std::to_string(options.metres_per_pixel) + ", " + std::to_string(options.max_image_size) + ")");
  }
  MapImageInfo info;
  info.bbox = options.bbox ? *options.bbox : defaultExtent(map, options);
  if (info.bbox.isEmpty() || info.bbox.sizes().minCoeff() <= 0.0) {
    throw IoError("renderMapImage: empty bounding box");
  }
  const Eigen::Vector2d size = info.bbox.sizes();
  info.metres_per_pixel = std::max(options.metres_per_pixel, size.maxCoeff() / options.max_image_size);
  const int map_w = std::max(1, static_cast<int>(std::ceil(size.x() / info.metres_per_pixel - 1e-9)));
  info.map_height_px = std::max(1, static_cast<int>(std::ceil(size.y() / info.metres_per_pixel - 1e-9)));
  info.footer_height_px = map_w >= 2000 ? 44 : 28;

  cv::Mat img(info.map_height_px + info.footer_height_px, std::max(map_w, kMinWidthPx), CV_8UC3, kBackground);
  cv::Mat map_area = img(cv::Rect(0, 0, img.cols, info.map_height_px));
  Painter painter(map_area, info);
  for (const auto& pl : options.background_polylines) painter.polyline(pl, kSkeleton, painter.px(2.0, 2));
  drawLanelets(painter, map);
  drawBoundaries(painter, map);
  if (options.draw_centre_lines) {
    for (const auto& ll : map.lanelets) {
      const Polyline centre = toPolyline2d(ll.centre);
      painter.polyline(centre, kCentre, 1);
      painter.directionArrow(centre, kCentre);
    }
  }
  drawFooter(img, info, map_w, options.attribution);
  if (info_out) *info_out = info;
  return img;
}

MapImageInfo writeMapPng(const map::LaneMap& map, const std::string& path, const MapPngOptions& options) {
  MapImageInfo info;
  const cv::Mat img = renderMapImage(map, options, &info);
  std::vector<uchar> png;
  if (!cv::imencode(".png", img, png)) throw IoError("cannot encode PNG for '" + path + "'");
  writeFileAtomically(path, png.data(), png.size());
  return info;
}

}  // namespace lanemap::io
