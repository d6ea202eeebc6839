#include "core/ground/ground_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace lanemap::ground {

std::optional<double> rayTriangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-15) return std::nullopt;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) * inv;
  if (u < -1e-9 || u > 1.0 + 1e-9) return std::nullopt;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < -1e-9 || u + v > 1.0 + 1e-9) return std::nullopt;
  return e2.dot(q) * inv;
}

MeshGround::MeshGround(TriangleMesh mesh, MeshGroundOptions options) : mesh_(std::move(mesh)), options_(options) {
  if (!(options_.cell_m > 0.0)) throw std::invalid_argument("MeshGround: cell_m must be > 0");
  buildIndex();
}

void MeshGround::buildIndex() {
  if (mesh_.triangles.empty()) return;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& t : mesh_.triangles) {
    for (int k : t) {
      lo = lo.cwiseMin(mesh_.vertices[k].head<2>());
      hi = hi.cwiseMax(mesh_.vertices[k].head<2>());
    }
  }
  const double cs = options_.cell_m;
  min_ = lo;
  nx_ = static_cast<int>(std::floor((hi.x() - lo.x()) / cs)) + 1;
  ny_ = static_cast<int>(std::floor((hi.y() - lo.y()) / cs)) + 1;
  cells_.assign(static_cast<size_t>(nx_) * ny_, Cell{});
  std::vector<float> zmin(cells_.size(), std::numeric_limits<float>::infinity());
  std::vector<float> zmax(cells_.size(), -std::numeric_limits<float>::infinity());
  // Two passes over the triangles' bounding boxes: count, then fill (CSR).
  auto forCells = [&](const std::array<int, 3>& t, auto&& f) {
    const auto& a = mesh_.vertices[t[0]];
    const auto& b = mesh_.vertices[t[1]];
    const auto& c = mesh_.vertices[t[2]];
    const int x0 = static_cast<int>((std::min({a.x(), b.x(), c.x()}) - min_.x()) / cs);
    const int x1 = static_cast<int>((std::max({a.x(), b.x(), c.x()}) - min_.x()) / cs);
    const int y0 = static_cast<int>((std::min({a.y(), b.y(), c.y()}) - min_.y()) / cs);
    const int y1 = static_cast<int>((std::max({a.y(), b.y(), c.y()}) - min_.y()) / cs);
    const float z0 = static_cast<float>(std::min({a.z(), b.z(), c.z()}));
    const float z1 = static_cast<float>(std::max({a.z(), b.z(), c.z()}));
    for (int y = y0; y <= std::min(y1, ny_ - 1); ++y) {
      for (int x = x0; x <= std::min(x1, nx_ - 1); ++x) f(static_cast<size_t>(y) * nx_ + x, z0, z1);
    }
  };
  std::vector<uint32_t> count(cells_.size() + 1, 0);
  for (const auto& t : mesh_.triangles) {
    forCells(t, [&](size_t i, float z0, float z1) {
      ++count[i + 1];
      zmin[i] = std::min(zmin[i], z0);
      zmax[i] = std::max(zmax[i], z1);
    });
  }
  for (size_t i = 1; i < count.size(); ++i) count[i] += count[i - 1];
  tri_index_.resize(count.back());
  std::vector<uint32_t> fill(count.begin(), count.end() - 1);
  for (uint32_t ti = 0; ti < mesh_.triangles.size(); ++ti) {
    forCells(mesh_.triangles[ti], [&](size_t i, float, float) { tri_index_[fill[i]++] = ti; });
  }
  for (size_t i = 0; i < cells_.size(); ++i) cells_[i] = Cell{count[i], count[i + 1], zmin[i], zmax[i]};
}

const MeshGround::Cell* MeshGround::cellAt(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return nullptr;
  return &cells_[static_cast<size_t>(iy) * nx_ + ix];
}

std::optional<double> MeshGround::hitInCell(const Cell& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                            double t0, double t1) const {
  std::optional<double> best;
  for (uint32_t k = c.begin; k < c.end; ++k) {
    const auto& t = mesh_.triangles[tri_index_[k]];
    const auto hit = rayTriangle(o, d, mesh_.vertices[t[0]], mesh_.vertices[t[1]], mesh_.vertices[t[2]]);
    if (hit && *hit > 0.0 && *hit >= t0 && *hit <= t1 && (!best || *hit < *best)) best = hit;
  }
  return best;
}

std::optional<double> MeshGround::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t) const {
  if (cells_.empty() || !(max_t > 0.0)) return std::nullopt;
  const double cs = options_.cell_m;
  // Clip the ray's (x, y) projection to the grid's box.
  double t_in = 0.0, t_out = max_t;
  const Eigen::Vector2d box_hi = min_ + Eigen::Vector2d(nx_ * cs, ny_ * cs);
  for (int a = 0; a < 2; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < min_[a] || o[a] >= box_hi[a]) return std::nullopt;
      continue;
    }
    double ta = (min_[a] - o[a]) / d[a], tb = (box_hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t_in = std::max(t_in, ta);
    t_out = std::min(t_out, tb);
  }
  if (t_in > t_out) return std::nullopt;
  const Eigen::Vector3d p = o + t_in * d;
  int ix = std::clamp(static_cast<int>(std::floor((p.x() - min_.x()) / cs)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((p.y() - min_.y()) / cs)), 0, ny_ - 1);
  const int sx = d.x() > 0 ? 1 : -1, sy = d.y() > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  auto nextBoundary = [&](int a, int i, int s) {
    if (std::abs(d[a]) < 1e-15) return inf;
    return (min_[a] + (i + (s > 0 ? 1 : 0)) * cs - o[a]) / d[a];
  };
  double tx = nextBoundary(0, ix, sx), ty = nextBoundary(1, iy, sy);
  const double dtx = std::abs(d.x()) < 1e-15 ? inf : cs / std::abs(d.x());
  const double dty = std::abs(d.y()) < 1e-15 ? inf : cs / std::abs(d.y());
  double t = t_in;
  while (const Cell* c = cellAt(ix, iy)) {
    const double t_end = std::min({tx, ty, t_out});
    if (c->end > c->begin) {
      const double za = o.z() + d.z() * t, zb = o.z() + d.z() * t_end;
      if (std::min(za, zb) <= c->zmax + 1e-6 && std::max(za, zb) >= c->zmin - 1e-6) {
        if (auto hit = hitInCell(*c, o, d, t - 1e-9, t_end + 1e-9)) return hit;
      }
    }
    if (t_end >= t_out) break;
    t = t_end;
    if (tx < ty) {
      ix += sx;
      tx += dtx;
    } else {
      iy += sy;
      ty += dty;
    }
  }
  return std::nullopt;
}

std::optional<double> MeshGround::heightAt(double east, double north) const {
  if (cells_.empty()) return std::nullopt;
  const int ix = static_cast<int>(std::floor((east - min_.x()) / options_.cell_m));
  const int iy = static_cast<int>(std::floor((north - min_.y()) / options_.cell_m));
  const Cell* c = cellAt(ix, iy);
  if (!c) return std::nullopt;
  // rayTriangle with the vertical ray, written out in 2D (the same u, v and tolerances): this runs
  // for every projected pixel that misses the mesh, over dozens of thin triangles per cell.
  for (uint32_t k = c->begin; k < c->end; ++k) {
    const auto& t = mesh_.triangles[tri_index_[k]];
    const Eigen::Vector3d& a = mesh_.vertices[t[0]];
    const Eigen::Vector3d& b = mesh_.vertices[t[1]];
    const Eigen::Vector3d& cc = mesh_.vertices[t[2]];
    const double e1x = b.x() - a.x(), e1y = b.y() - a.y(), e2x = cc.x() - a.x(), e2y = cc.y() - a.y();
    const double det = e1x * e2y - e1y * e2x;
    if (std::abs(det) < 1e-15) continue;
    const double inv = 1.0 / det, sx = east - a.x(), sy = north - a.y();
    const double u = (sx * e2y - sy * e2x) * inv;
    if (u < -1e-9 || u > 1.0 + 1e-9) continue;
    const double v = (e1x * sy - e1y * sx) * inv;
    if (v < -1e-9 || u + v > 1.0 + 1e-9) continue;
    return a.z() + u * (b.z() - a.z()) + v * (cc.z() - a.z());
  }
  return std::nullopt;
}

size_t MeshGround::memoryBytes() const {
  return mesh_.vertices.size() * sizeof(Eigen::Vector3d) + mesh_.triangles.size() * sizeof(std::array<int, 3>) +
         cells_.size() * sizeof(Cell) + tri_index_.size() * sizeof(uint32_t);
}

}  // namespace lanemap::ground
