#include "core/bev/drive_offsets.h"

#include <Eigen/Dense>

#include <cmath>
#include <numeric>
#include <stdexcept>

namespace lanemap::bev {

Eigen::Vector2i correctionCells(const Eigen::Vector2d& offset_m, double resolution_m) {
  const Eigen::Vector2d c = -offset_m / resolution_m;
  return {static_cast<int>(std::lround(c.x())), static_cast<int>(std::lround(c.y()))};
}

int DriveOffsetSolver::addRoad(const std::vector<std::pair<size_t, const BevGrid*>>& grids) {
  int trusted = 0;
  for (size_t a = 0; a < grids.size(); ++a) {
    for (size_t b = a + 1; b < grids.size(); ++b) {
      const auto& [i, gi] = grids[a];
      const auto& [j, gj] = grids[b];
      if (i == j || i >= drives_ || j >= drives_) throw std::invalid_argument("DriveOffsetSolver::addRoad: two grids of one drive, or no such drive");
      // The shift that moves j's evidence onto i's: j + s = i, so o_i - o_j = s.
      const Alignment al = estimateShift(*gi, *gj, options_);
      if (!al.ok) continue;
      pairs_.push_back({i, j, al.shift_m, al.correlation});
      ++trusted;
    }
  }
  return trusted;
}

DriveOffsets DriveOffsetSolver::solve() const {
  const size_t n = drives_;
  DriveOffsets out;
  out.offset_m.assign(n, Eigen::Vector2d::Zero());
  out.measurements.assign(n, 0);
  out.component.resize(n);
  // Components of the drives linked by a trusted pair (union-find).
  std::vector<size_t> parent(n);
  std::iota(parent.begin(), parent.end(), size_t{0});
  const auto find = [&](size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& p : pairs_) {
    parent[find(p.i)] = find(p.j);
    ++out.measurements[p.i];
    ++out.measurements[p.j];
  }
  for (size_t d = 0; d < n; ++d) out.component[d] = static_cast<int>(find(d));
  if (pairs_.empty()) return out;
  // Weighted least squares on the graph Laplacian, both axes at once; each component's offsets are
  // fixed up to a common shift, taken as the one that gives them zero mean.
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, 2);
  for (const auto& p : pairs_) {
    L(p.i, p.i) += p.weight;
    L(p.j, p.j) += p.weight;
    L(p.i, p.j) -= p.weight;
    L(p.j, p.i) -= p.weight;
    b.row(p.i) += p.weight * p.shift_m.transpose();
    b.row(p.j) -= p.weight * p.shift_m.transpose();
  }
  // The exact zero-mean gauge: add (1/size) 1 1^T per component (it leaves a zero-mean solution
  // alone and removes the null space).
  std::vector<size_t> size(n, 0);
  for (size_t d = 0; d < n; ++d) ++size[find(d)];
  for (size_t a = 0; a < n; ++a) {
    for (size_t c = 0; c < n; ++c) {
      if (find(a) == find(c)) L(a, c) += 1.0 / static_cast<double>(size[find(a)]);
    }
  }
  const Eigen::MatrixXd o = L.ldlt().solve(b);
  for (size_t d = 0; d < n; ++d) {
    if (out.measurements[d] > 0) out.offset_m[d] = o.row(d).transpose();
  }
  return out;
}

void LiveDriveOffset::addStored(int64_t road_id, bool merged, const Eigen::Vector2i& applied, const Alignment& a, int frames) {
  const bool own = !stored_.insert(road_id).second;
  if (merged && !own) addMerge(applied, a, frames);
}

void LiveDriveOffset::addMerge(const Eigen::Vector2i& applied, const Alignment& a, int frames) {
  if (!options_.enabled || !a.ok) return;
  measured_.emplace_back((applied + a.shift_cells).cast<double>(), std::max(1, frames));
  if (static_cast<int>(measured_.size()) < options_.min_roads) return;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  double total = 0.0;
  for (const auto& [c, w] : measured_) {
    mean += w * c;
    total += w;
  }
  mean /= total;
  consistent_ = true;
  for (const auto& [c, w] : measured_) consistent_ = consistent_ && (c - mean).norm() * resolution_m_ <= options_.max_spread_m;
  correction_ = consistent_ ? Eigen::Vector2i(static_cast<int>(std::lround(mean.x())), static_cast<int>(std::lround(mean.y())))
                            : Eigen::Vector2i::Zero();
}

}  // namespace lanemap::bev
