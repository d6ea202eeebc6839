// Fewer points, same shape: Douglas-Peucker simplification of polylines and of a whole LaneMap.
// The simulator's truth is sampled densely (every few decimetres); written as Lanelet2 that is
// tens of thousands of nodes for a small town. Simplifying with a 1 cm tolerance keeps the
// geometry far inside any evaluation threshold and cuts the file several times.
#pragma once

#include "core/map/lane_map.h"

#include <Eigen/Core>

#include <vector>

namespace lanemap::map {

// Keeps the first and last point and every point needed so that no dropped point is farther than
// `tolerance` (metres, 3D) from the kept polyline. tolerance <= 0 returns the input.
std::vector<Eigen::Vector3d> simplifyPolyline(const std::vector<Eigen::Vector3d>& points, double tolerance);

// Every line string and centre line simplified; ids, types and topology untouched.
LaneMap simplified(const LaneMap& map, double tolerance);

}  // namespace lanemap::map
