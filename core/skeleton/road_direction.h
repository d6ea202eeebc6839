// A road's direction where it meets an intersection, as the intersection builder measures turns
// (METHOD.md section 5) and the coverage planner avoids U-turns with it.
#pragma once

#include "core/skeleton/skeleton.h"

#include <Eigen/Core>

namespace lanemap::skeleton {

// From the road's ROI edge to `over_m` past it, along the road: at its end (`incoming`) the
// direction it arrives in, at its start the direction it leaves in; the polyline's tangent at the
// edge when that stretch has no length.
Eigen::Vector2d directionAtJunction(const Skeleton& skeleton, const AtomicRoad& road, bool incoming, double over_m);

}  // namespace lanemap::skeleton
