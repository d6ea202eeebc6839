// DBSCAN (Ester et al. 1996) over 2D points, grid-accelerated: cells of side eps, so a point's
// eps-neighbourhood is searched in its 3x3 cells. Deterministic (points visited in input order).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace lanemap::lanes {

// Cluster label per point: 0..K-1, or -1 for noise. A core point has at least min_points points
// (itself included) within eps. *num_clusters receives K when given.
std::vector<int> dbscan(const std::vector<Eigen::Vector2d>& points, double eps, int min_points,
                        int* num_clusters = nullptr);

// The same on scalars (O(n log n): sort, sliding-window neighbour counts). A border point within
// eps of two clusters joins the one of its nearest core point.
std::vector<int> dbscan1d(const std::vector<double>& values, double eps, int min_points, int* num_clusters = nullptr);

}  // namespace lanemap::lanes
