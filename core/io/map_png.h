// Draws a LaneMap as a picture a person can check at a glance: lane polygons (road lanes dark
// grey, intersection lanes blue-grey), boundaries by type (dashed white, solid white, double
// solid yellow, curb light grey, virtual thin, stop lines red), centre lines with direction
// arrows, optionally the OSM skeleton's roads underneath, a metric scale bar and the OSM
// attribution in a footer. Written as PNG, atomically.
#pragma once

#include "core/io/atomic_file.h"
#include "core/map/lane_map.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace lanemap::skeleton { class Skeleton; }

namespace lanemap::io {

struct MapPngOptions {
  double metres_per_pixel = 0.1;
  std::optional<Eigen::AlignedBox2d> bbox;  // ENU metres; default: the map's extent + margin
  double margin_m = 10.0;
  int max_image_size = 4096;  // longest side of the map area in pixels; the scale is coarsened
                              // (metres_per_pixel raised) to fit
  bool draw_centre_lines = true;
  // Drawn first, light grey, e.g. skeletonPolylines(skeleton) (the OSM roads). Part of the
  // default extent.
  std::vector<std::vector<Eigen::Vector2d>> background_polylines;
  std::string attribution = "(c) OpenStreetMap contributors, ODbL";
};

// Where the map landed in the picture.
struct MapImageInfo {
  double metres_per_pixel = 0.0;  // after the max_image_size cap
  Eigen::AlignedBox2d bbox;       // ENU area shown
  int map_height_px = 0;          // rows above the footer
  int footer_height_px = 0;
  // Pixel (column, row) of an ENU point; x to the right (east), y up (north).
  cv::Point2d toPixel(const Eigen::Vector2d& enu) const;
};

// The skeleton's atomic road polylines (one per direction of travel) for background_polylines.
std::vector<std::vector<Eigen::Vector2d>> skeletonPolylines(const skeleton::Skeleton& skeleton);

// The picture (BGR, 8 bit). Throws IoError for a non-positive scale or image size.
cv::Mat renderMapImage(const map::LaneMap& map, const MapPngOptions& options = {},
                       MapImageInfo* info = nullptr);

// renderMapImage + PNG encoding, written atomically. Throws IoError naming the path on failure.
MapImageInfo writeMapPng(const map::LaneMap& map, const std::string& path,
                         const MapPngOptions& options = {});

// Colours (BGR) used, for tests and legends.
namespace map_png_colours {
inline const cv::Scalar kBackground{236, 239, 240};
inline const cv::Scalar kRoadLane{88, 88, 88};
inline const cv::Scalar kIntersectionLane{120, 96, 72};
inline const cv::Scalar kMarking{255, 255, 255};
inline const cv::Scalar kDoubleSolid{40, 200, 240};
inline const cv::Scalar kCurb{185, 185, 185};
inline const cv::Scalar kVirtual{170, 150, 130};
inline const cv::Scalar kStopLine{40, 40, 230};
inline const cv::Scalar kCentre{230, 190, 60};
inline const cv::Scalar kSkeleton{205, 205, 205};
}  // namespace map_png_colours

}  // namespace lanemap::io
