#include "core/skeleton/road_direction.h"

#include "core/geo/polyline.h"

#include <algorithm>

namespace lanemap::skeleton {

Eigen::Vector2d directionAtJunction(const Skeleton& sk, const AtomicRoad& road, bool incoming, double over_m) {
  const double s_edge = incoming ? road.s_end : road.s_begin;
  const double s_far = incoming ? std::max(0.0, s_edge - over_m) : std::min(road.length, s_edge + over_m);
  const Eigen::Vector2d p_edge = sk.pointAt(road, s_edge), p_far = sk.pointAt(road, s_far);
  return geo::unit(incoming ? Eigen::Vector2d(p_edge - p_far) : Eigen::Vector2d(p_far - p_edge), sk.tangentAt(road, s_edge));
}

}  // namespace lanemap::skeleton
