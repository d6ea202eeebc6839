// Polyline helpers (see polyline.h).
#include "core/geo/polyline.h"

namespace lanemap::geo {

double polylineLength(const std::vector<Eigen::Vector2d>& pts) {
  double len = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).norm();
  return len;
}

double polylineLength(const std::vector<Eigen::Vector3d>& pts) {
  double len = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).norm();
  return len;
}

double polylineLengthXy(const std::vector<Eigen::Vector3d>& pts) {
  double len = 0.0;
  for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).head<2>().norm();
  return len;
}

}  // namespace lanemap::geo
