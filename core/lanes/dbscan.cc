#include "core/lanes/dbscan.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace lanemap::lanes {

std::vector<int> dbscan(const std::vector<Eigen::Vector2d>& pts, double eps, int min_points, int* num_clusters) {
  const size_t n = pts.size();
  std::vector<int> label(n, -2);  // -2 unvisited, -1 noise
  auto cellKey = [](int64_t x, int64_t y) { return (x << 32) ^ (y & 0xffffffff); };
  std::unordered_map<int64_t, std::vector<int>> grid;
  std::vector<std::pair<int64_t, int64_t>> cell(n);
  for (size_t i = 0; i < n; ++i) {
    cell[i] = {static_cast<int64_t>(std::floor(pts[i].x() / eps)), static_cast<int64_t>(std::floor(pts[i].y() / eps))};
    grid[cellKey(cell[i].first, cell[i].second)].push_back(static_cast<int>(i));
  }
  const double eps2 = eps * eps;
  std::vector<int> nb;
  auto neighbours = [&](int i) {
    nb.clear();
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        auto it = grid.find(cellKey(cell[i].first + dx, cell[i].second + dy));
        if (it == grid.end()) continue;
        for (int j : it->second) {
          if ((pts[j] - pts[i]).squaredNorm() <= eps2) nb.push_back(j);
        }
      }
    }
  };
  int k = 0;
  std::vector<int> queue;
  for (size_t i = 0; i < n; ++i) {
    if (label[i] != -2) continue;
    neighbours(static_cast<int>(i));
    if (static_cast<int>(nb.size()) < min_points) {
      label[i] = -1;
      continue;
    }
    label[i] = k;
    queue.assign(nb.begin(), nb.end());
    for (size_t q = 0; q < queue.size(); ++q) {
      const int j = queue[q];
      if (label[j] == -1) label[j] = k;  // border point
      if (label[j] != -2) continue;
      label[j] = k;
      neighbours(j);
      if (static_cast<int>(nb.size()) >= min_points) queue.insert(queue.end(), nb.begin(), nb.end());
    }
    ++k;
  }
  if (num_clusters) *num_clusters = k;
  return label;
}

std::vector<int> dbscan1d(const std::vector<double>& v, double eps, int min_points, int* num_clusters) {
  const size_t n = v.size();
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b] || (v[a] == v[b] && a < b); });
  std::vector<double> x(n);
  for (size_t i = 0; i < n; ++i) x[i] = v[order[i]];
  std::vector<char> core(n, 0);
  size_t lo = 0, hi = 0;
  for (size_t i = 0; i < n; ++i) {
    while (x[i] - x[lo] > eps) ++lo;
    if (hi < i) hi = i;
    while (hi + 1 < n && x[hi + 1] - x[i] <= eps) ++hi;
    core[i] = static_cast<int>(hi - lo + 1) >= min_points;
  }
  std::vector<int> sorted_label(n, -1);
  int k = -1;
  double last_core = -INFINITY;
  for (size_t i = 0; i < n; ++i) {
    if (!core[i]) continue;
    if (x[i] - last_core > eps) ++k;
    sorted_label[i] = k;
    last_core = x[i];
  }
  // Border points: the cluster of the nearest core point within eps.
  double prev_core = -INFINITY;
  int prev_label = -1;
  std::vector<double> next_core(n, INFINITY);
  std::vector<int> next_label(n, -1);
  for (size_t i = n; i-- > 0;) {
    if (core[i]) {
      next_core[i] = x[i];
      next_label[i] = sorted_label[i];
    } else if (i + 1 < n) {
      next_core[i] = next_core[i + 1];
      next_label[i] = next_label[i + 1];
    }
  }
  for (size_t i = 0; i < n; ++i) {
    if (core[i]) {
      prev_core = x[i];
      prev_label = sorted_label[i];
      continue;
    }
    const double dp = x[i] - prev_core, dn = next_core[i] - x[i];
    if (dp <= eps && dp <= dn) sorted_label[i] = prev_label;
    else if (dn <= eps) sorted_label[i] = next_label[i];
  }
  std::vector<int> label(n, -1);
  for (size_t i = 0; i < n; ++i) label[order[i]] = sorted_label[i];
  if (num_clusters) *num_clusters = k + 1;
  return label;
}

}  // namespace lanemap::lanes
