// The topographic ground model of METHOD.md section 3: the LIDAR's ground points (ENU), one mesh
// vertex per point (buildSweepGround first merges them per 0.3 m cell, sweep_ground.h),
// Delaunay-triangulated in (east, north) with their height kept (2.5D), and camera rays
// intersected with the triangles (the Projector rasterises the mesh instead, projector.h).
//
// - triangulateGround (delaunay.cc, the only file that includes CGAL): CGAL's
//   Delaunay_triangulation_2 over (x, y) with each vertex's index as info, so z comes back exactly.
//   The Delaunay triangulation covers the convex hull, so it bridges every gap: the shadow behind a
//   parked car, the rim of the hull, the hole under the car inside the innermost ring. Triangles
//   with an edge longer than max_edge_m are dropped; the default (config/bev_builder.yaml) is
//   long enough to keep the ring-to-ring triangles of a VLP-16 within camera range (ring spacing
//   grows to ~14 m at 20-35 m) and the chords across the blind circle (~14 m across).
// - MeshGround: a uniform 2D grid over the mesh's bounding box; each cell lists the triangles whose
//   bounding box overlaps it (CSR arrays) and the z range of those triangles. A ray walks the
//   cells its (x, y) projection crosses, nearest first (Amanatides-Woo), skips a cell when the
//   ray's z over the cell cannot touch the cell's z range, and returns the first triangle hit
//   (Moller-Trumbore) inside the current cell's stretch of the ray, which is the first hit overall.
//   covers() tells whether a triangle lies under a point: the Projector falls back to the flat
//   plane only where it does not (METHOD.md: "where the mesh has no triangle").
#pragma once

#include "core/ground/ground_model.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace lanemap::ground {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;  // vertex indices, counter-clockwise seen from above
};

// 2.5D Delaunay triangulation of `points` (duplicates in x, y keep one of them). Drops triangles
// with an edge longer than max_edge_m (<= 0: keeps all).
TriangleMesh triangulateGround(const std::vector<Eigen::Vector3d>& points, double max_edge_m);

struct MeshGroundOptions {
  double cell_m = 1.0;  // grid index cell side
};

class MeshGround : public GroundModel {
 public:
  explicit MeshGround(TriangleMesh mesh, MeshGroundOptions options = {});

  // First triangle the ray meets (t in (0, max_t]); nullopt when it meets none.
  std::optional<double> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                  double max_t) const override;
  // Height of the mesh at (east, north), nullopt where no triangle lies under the point.
  std::optional<double> heightAt(double east, double north) const;
  bool covers(double east, double north) const { return heightAt(east, north).has_value(); }

  const TriangleMesh& mesh() const { return mesh_; }
  size_t triangleCount() const { return mesh_.triangles.size(); }
  size_t memoryBytes() const;

 private:
  struct Cell {
    uint32_t begin = 0, end = 0;  // range in tri_index_
    float zmin = 0.0f, zmax = 0.0f;
  };
  void buildIndex();
  const Cell* cellAt(int ix, int iy) const;
  // Nearest hit among a cell's triangles with t in [t0, t1].
  std::optional<double> hitInCell(const Cell& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                                  double t1) const;

  TriangleMesh mesh_;
  MeshGroundOptions options_;
  Eigen::Vector2d min_ = Eigen::Vector2d::Zero();
  int nx_ = 0, ny_ = 0;
  std::vector<Cell> cells_;
  std::vector<uint32_t> tri_index_;
};

// Ray / triangle intersection (Moller-Trumbore): t of the hit, nullopt when it misses.
std::optional<double> rayTriangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace lanemap::ground
