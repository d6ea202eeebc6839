// extractGround: the one translation unit that includes PCL (its headers are slow to compile).
#include "core/ground/ground_extraction.h"

#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>

#include <algorithm>
#include <cmath>

namespace lanemap::ground {

namespace {

struct Plane {
  Eigen::Vector4d c = Eigen::Vector4d(0.0, 0.0, 1.0, 0.0);  // a x + b y + c z + d = 0, c > 0
  double zAt(double x, double y) const { return -(c[0] * x + c[1] * y + c[3]) / c[2]; }
};

// Fits a near-horizontal plane to `cloud` (PCL RANSAC); returns its inliers (indices into cloud).
bool fitPlane(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud, const GroundExtractionOptions& o, Plane& plane,
              pcl::Indices& inliers) {
  auto model = std::make_shared<pcl::SampleConsensusModelPerpendicularPlane<pcl::PointXYZ>>(cloud);
  model->setAxis(Eigen::Vector3f::UnitZ());
  model->setEpsAngle(o.max_tilt_deg * M_PI / 180.0);
  pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model, o.distance_threshold_m);
  ransac.setMaxIterations(o.max_iterations);
  if (!ransac.computeModel()) return false;
  ransac.getInliers(inliers);
  Eigen::VectorXf coeff;
  ransac.getModelCoefficients(coeff);
  if (coeff.size() != 4 || static_cast<int>(inliers.size()) < std::max(3, o.min_points / 2)) return false;
  Eigen::Vector4d c = coeff.cast<double>();
  if (c[2] < 0) c = -c;
  if (c[2] < 1e-3) return false;
  plane.c = c / c.head<3>().norm();
  return true;
}

// Indices 0..n-1 grouped by key (a counting sort: ascending index within a key); key < 0: left out.
// One flat array instead of a vector per key: a sweep has ~20k points in 360 slices and 96 cells.
struct Buckets {
  std::vector<int> start;  // key k holds items[start[k] .. start[k + 1])
  std::vector<int> items;
  Buckets(const std::vector<int>& key, int keys) : start(static_cast<size_t>(keys) + 1, 0) {
    for (int k : key) {
      if (k >= 0) ++start[k + 1];
    }
    for (int k = 0; k < keys; ++k) start[k + 1] += start[k];
    items.resize(start[keys]);
    std::vector<int> next(start.begin(), start.end() - 1);
    for (size_t i = 0; i < key.size(); ++i) {
      if (key[i] >= 0) items[next[key[i]]++] = static_cast<int>(i);
    }
  }
  const int* begin(int k) const { return items.data() + start[k]; }
  const int* end(int k) const { return items.data() + start[k + 1]; }
};

// One azimuth sector: range bins from the car outwards, each predicted by the previous plane.
// cells: the sweep's points by sector * nbins + bin.
void sectorGround(const std::vector<Eigen::Vector3d>& pts, const Buckets& cells, int sector, int nbins,
                  const GroundExtractionOptions& o, std::vector<int>& ground) {
  Plane plane;  // the vehicle's ground plane
  double ref_range = 0.0;
  for (int b = 0; b < nbins; ++b) {
    const double far = o.range_edges_m[b + 1];
    const double band = o.band_base_m + o.band_slope * (far - ref_range);
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    std::vector<int> ids;
    const int cell = sector * nbins + b;
    cloud->reserve(cells.end(cell) - cells.begin(cell));
    ids.reserve(cells.end(cell) - cells.begin(cell));
    for (const int* it = cells.begin(cell); it != cells.end(cell); ++it) {
      const int i = *it;
      const auto& p = pts[i];
      if (std::abs(p.z() - plane.zAt(p.x(), p.y())) > band) continue;
      cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
      ids.push_back(i);
    }
    if (static_cast<int>(ids.size()) < o.min_points) continue;
    pcl::Indices inliers;
    if (!fitPlane(cloud, o, plane, inliers)) continue;
    for (int k : inliers) ground.push_back(ids[k]);
    ref_range = 0.5 * (o.range_edges_m[b] + far);
  }
}

// Marks the points on vertical structures (see the header). az: atan2(y, x) + pi, r: horizontal
// range, per point (computed once for this and the binning).
std::vector<uint8_t> verticalStructures(const std::vector<Eigen::Vector3d>& pts, const std::vector<double>& az,
                                        const std::vector<double>& r, const GroundExtractionOptions& o) {
  const int slices = std::max(1, static_cast<int>(std::lround(360.0 / o.azimuth_slice_deg)));
  std::vector<int> slice_of(pts.size(), -1);
  for (size_t i = 0; i < pts.size(); ++i) {
    if (pts[i].allFinite()) slice_of[i] = std::min(slices - 1, static_cast<int>(az[i] / (2.0 * M_PI) * slices));
  }
  const Buckets by_slice(slice_of, slices);
  std::vector<uint8_t> vertical(pts.size(), 0);
  std::vector<std::pair<double, int>> slice;
  for (int s = 0; s < slices; ++s) {
    slice.clear();
    for (const int* it = by_slice.begin(s); it != by_slice.end(s); ++it) slice.emplace_back(r[*it], *it);
    std::sort(slice.begin(), slice.end());
    for (size_t k = 0; k + 1 < slice.size(); ++k) {
      const double dz = std::abs(pts[slice[k + 1].second].z() - pts[slice[k].second].z());
      const double dr = slice[k + 1].first - slice[k].first;
      if (dz > o.vertical_step_m && dz > o.vertical_slope * dr) vertical[slice[k].second] = vertical[slice[k + 1].second] = 1;
    }
  }
  return vertical;
}

}  // namespace

std::vector<int> extractGround(const std::vector<Eigen::Vector3d>& points, const GroundExtractionOptions& o) {
  // A bin without a plane is normal (a wall, an empty sector); PCL would print a warning for each.
  static const bool quiet = [] {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // "no model" is reported as an error
    return true;
  }();
  (void)quiet;
  const int nbins = static_cast<int>(o.range_edges_m.size()) - 1;
  if (nbins < 1 || o.sectors < 1) return {};
  std::vector<double> az(points.size(), 0.0), range(points.size(), 0.0);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    az[i] = std::atan2(points[i].y(), points[i].x()) + M_PI;  // [0, 2 pi]
    range[i] = std::hypot(points[i].x(), points[i].y());
  }
  const std::vector<uint8_t> vertical = verticalStructures(points, az, range, o);
  std::vector<int> cell_of(points.size(), -1);  // sector * nbins + bin
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (!p.allFinite() || vertical[i]) continue;
    const double r = range[i];
    const auto it = std::upper_bound(o.range_edges_m.begin(), o.range_edges_m.end(), r);
    if (it == o.range_edges_m.begin() || it == o.range_edges_m.end()) continue;
    const int bin = static_cast<int>(it - o.range_edges_m.begin()) - 1;
    const int sector = std::min(o.sectors - 1, static_cast<int>(az[i] / (2.0 * M_PI) * o.sectors));
    cell_of[i] = sector * nbins + bin;
  }
  const Buckets cells(cell_of, o.sectors * nbins);
  std::vector<int> found;
  for (int sector = 0; sector < o.sectors; ++sector) sectorGround(points, cells, sector, nbins, o, found);
  // Ascending (each point is in one cell, so at most once): flags instead of a sort.
  std::vector<uint8_t> is_ground(points.size(), 0);
  for (int i : found) is_ground[i] = 1;
  std::vector<int> ground;
  ground.reserve(found.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (is_ground[i]) ground.push_back(static_cast<int>(i));
  }
  return ground;
}

}  // namespace lanemap::ground
