// triangulateGround: the one translation unit that includes CGAL (its headers are slow to compile).
#include "core/ground/ground_mesh.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <utility>

namespace lanemap::ground {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;

bool shortEnough(const TriangleMesh& m, const std::array<int, 3>& t, double max_edge2) {
  if (max_edge2 <= 0.0) return true;
  for (int i = 0; i < 3; ++i) {
    const auto& a = m.vertices[t[i]];
    const auto& b = m.vertices[t[(i + 1) % 3]];
    if ((a.head<2>() - b.head<2>()).squaredNorm() > max_edge2) return false;
  }
  return true;
}

}  // namespace

TriangleMesh triangulateGround(const std::vector<Eigen::Vector3d>& points, double max_edge_m) {
  TriangleMesh mesh;
  mesh.vertices = points;
  std::vector<std::pair<Kernel::Point_2, int>> input;
  input.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    input.emplace_back(Kernel::Point_2(points[i].x(), points[i].y()), static_cast<int>(i));
  }
  Delaunay dt;
  dt.insert(input.begin(), input.end());  // spatially sorted insertion
  const double max_edge2 = max_edge_m > 0.0 ? max_edge_m * max_edge_m : 0.0;
  mesh.triangles.reserve(2 * points.size());
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) {
    const std::array<int, 3> t{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
    if (shortEnough(mesh, t, max_edge2)) mesh.triangles.push_back(t);
  }
  return mesh;
}

}  // namespace lanemap::ground
