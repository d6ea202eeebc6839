// The BEV projection of METHOD.md section 3: one segmented camera frame (class ids of METHOD.md
// section 2) is put on the ground in ENU with the camera model (intrinsics, distortion, mount), the
// vehicle pose RT_t and a ground model (flat plane under the car, or the LIDAR mesh), and becomes a
// FrameSplat: the BEV cells it saw, each with the absolute layers of bev_grid.h it saw there.
//
// Design:
// - Rays are computed once per camera (CameraModel::rayVehicle, exact undistortion). Candidate
//   pixels are those whose ray meets the vehicle's ground plane within max_range_m (horizontal,
//   from the camera): everything above the horizon, and the far road where a pixel spans metres,
//   never counts.
// - Pixel sampling: near the car a 0.1 m cell holds dozens of pixels, at 30 m one pixel is 1.5 m
//   long. Projecting all 230k pixels would mostly re-hit the same cells, so a lattice is chosen
//   once per camera on the flat ground: rows are kept when they are sample_spacing_m (default: the
//   cell size) beyond the last kept row, and in a kept row every k-th pixel with k such that pixels
//   are about sample_spacing_m apart across. That is roughly one pixel per cell near the car and
//   every pixel far away (tools/bench/bev_bench.cc prints the count). sample_spacing_m = 0 projects
//   every candidate pixel.
// - Counting: a frame counts at most once per cell and layer (the splat is deduplicated), so a
//   cell's kObserved count is the number of frames that saw it and fraction() is "share of the
//   frames that saw this cell that saw this class", independent of how many pixels fell there.
// - Classes -> layers (bev_grid.h): background -> observed only; the five ego-relative lane classes
//   -> kDrivable; dashed/solid/crosswalk/curb/stop line -> their layer. kLaneSeparation: in every
//   kept row, two lane pixels of different lane classes (ego | left, ...) with nothing between them
//   but line paint (dashed, solid), at most max_separation_gap_m apart on the flat ground, lie on
//   either side of a lane separation; the paint pixels between them, or the two pixels themselves
//   where they touch (an unpainted separation), are marked. These pixels are projected even when the
//   lattice skips them, so a one-pixel separation is never lost to sampling. Only rows are scanned:
//   lane separations run along the road, i.e. across image rows, except far ahead in sharp turns.
// - Ground: with a MeshGround, each ray is intersected with the mesh (up to max_range_m
//   horizontally); where the mesh has no triangle under the flat-ground hit the pixel falls back to
//   the flat plane; a ray that misses a mesh that does lie under it (it goes over a crest, or past
//   max range) is dropped, because putting it on the flat plane would be wrong by metres.
// - Mesh raster (mesh_raster, default): casting every ray into the mesh's grid index costs ~20x the
//   flat projection (thin ring-to-ring triangles, dozens per index cell). The mesh is a surface seen
//   from one camera, so it is rasterised into the image instead: every triangle in range is put in
//   the camera frame (vertices V0, V1, V2 relative to the optical centre), and the pixel ray
//   r = (x, y, 1) (undistorted normalised coordinates, computed once per pixel) is written as
//   r = a V0 + b V1 + c V2 with a = r.(V1 x V2) / det(V0, V1, V2), ...: the ray meets the triangle
//   in front of the camera exactly when a, b, c >= 0, at camera depth 1 / (a + b + c). Perspective
//   maps the triangle's edges to straight lines in (x, y), so this test is exact under distortion
//   (it runs on the undistorted coordinates of the real pixels) and needs no clipping for
//   triangles reaching behind the camera. Each triangle visits the lattice pixels of the kept rows
//   inside its exact x span on each row (a per-row lookup table gives the first one) and keeps, per
//   pixel, the nearest triangle (a z-buffer of inverse depth). The pixel's hit is then the ray's
//   intersection with that triangle's plane, in double. A separation pixel off the lattice takes
//   the nearer of its two lattice neighbours' triangles that its own ray meets, and is ray-cast
//   when neither does. So the cells are those of the ray cast up to float rounding at triangle
//   edges (tests/bev/mesh_raster_test.cc: 0 to 0.007 % of the cells differ). mesh_raster = false
//   casts every ray (the reference). lanemap-bench-bev: 24x the flat projection before, 1.95-2.0x
//   now with the decimated mesh (core/ground/sweep_ground.h), 2.7x on the full mesh.
#pragma once

#include "core/bev/bev_grid.h"
#include "core/bev/road_crown.h"
#include "core/camera/camera_model.h"
#include "core/ground/ground_mesh.h"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace lanemap::bev {

// Class ids of label_image_t / METHOD.md section 2.
inline constexpr int kNumClasses = 11;
inline constexpr uint8_t kClassDashed = 6, kClassSolid = 7;
inline bool isLaneClass(uint8_t c) { return c >= 1 && c <= 5; }
// The layer bit mask (bit i = Layer i) one pixel of class c adds, kObserved included.
uint8_t layerBits(uint8_t label_class);
inline uint8_t bit(Layer l) { return static_cast<uint8_t>(1u << static_cast<int>(l)); }

struct ProjectorOptions {
  double resolution_m = 0.1;          // the BEV cell (splat cells have this size)
  double max_range_m = 30.0;          // horizontal distance from the camera
  double sample_spacing_m = 0.1;      // pixel lattice spacing on the flat ground; 0: every pixel
  bool lane_separation = true;        // derive kLaneSeparation from lane-class transitions
  double max_separation_gap_m = 0.6;  // paint between two lane classes at most this wide
  bool mesh_raster = true;            // rasterise the mesh into the image; false: ray-cast each pixel
};

struct SplatCell {
  int32_t x = 0, y = 0;  // BevGrid cell (column east, row north)
  uint8_t layers = 0;    // bit i = Layer i; kObserved always set
};

struct FrameSplat {
  int64_t utime = 0;
  double resolution = 0.1;
  std::vector<SplatCell> cells;  // unique, sorted by (y, x)
  // What happened to the projected pixels.
  size_t pixels = 0;          // projected (lattice + separation pixels)
  size_t mesh_hits = 0;       // placed on the mesh
  size_t flat = 0;            // placed on the flat plane (flat model, or no mesh triangle there)
  size_t crowned = 0;         // placed on the road's crown (no mesh; road_crown.h)
  size_t dropped = 0;         // ray missed a mesh lying under it
  size_t raycast = 0;         // mesh pixels the raster did not settle, ray-cast into the index
};

// Adds a frame's splat to a grid (each cell's layers once) and counts the frame.
void addSplat(const FrameSplat& splat, BevGrid& grid);

enum class LabelCheck { kOk, kWrongSize, kWrongType, kUnknownClass };
const char* toString(LabelCheck c);

class Projector {
 public:
  Projector(const camera::CameraModel& camera, const ProjectorOptions& options = {});

  // Checks a label image against this camera: CV_8UC1 of its size, every id < kNumClasses.
  LabelCheck check(const cv::Mat& labels) const;

  // Projects a checked label image taken at vehicle pose vehicle_to_enu. mesh == nullptr: the flat
  // plane under the vehicle, or with a crown (RoadCrown::around the same pose) the road's crowned
  // surface (a pixel whose ray the crown does not settle keeps its flat hit). A mesh wins over a crown.
  FrameSplat project(const cv::Mat& labels, const Eigen::Isometry3d& vehicle_to_enu,
                     const ground::MeshGround* mesh = nullptr, const RoadCrown* crown = nullptr) const;

  const ProjectorOptions& options() const { return options_; }
  const camera::CameraModel& camera() const { return camera_; }
  size_t candidatePixels() const { return candidates_; }
  size_t latticePixels() const { return lattice_.size(); }
  // Whether mesh projection rasterises (mesh_raster and a camera whose kept rows allow it).
  bool rasterises() const { return options_.mesh_raster && raster_ok_; }

 private:
  struct Ray {
    Eigen::Vector3f dir;       // unit, vehicle frame
    Eigen::Vector3f flat_hit;  // on the vehicle's z = 0 plane, vehicle frame
  };
  struct Row {
    int v = 0;
    int u0 = 0, u1 = -1;  // candidate columns [u0, u1]
    int step = 1;         // lattice: every step-th column from u0
  };
  // A kept row as the mesh raster sees it: its lattice pixels are compact indices
  // [offset, offset + n) of rqx_ / rqy_ (undistorted normalised coordinates, x increasing).
  struct RasterRow {
    int v = 0, u0 = 0, u1 = -1, step = 1;
    int offset = 0, n = 0;
    float qy_lo = 0, qy_hi = 0;     // y range over the row's pixels
    float qx_lo = 0, lut_step = 1;  // lookup table: bin k starts at qx_lo + k * lut_step ...
    float lut_inv_step = 1;
    int lut_begin = 0, lut_n = 0;   // ... and lut_[lut_begin + k] is the first pixel (from u0) at or past it
  };
  void buildRays();
  void buildLattice();
  void buildRaster();
  // One frame's raster: the triangles in view and, per compact pixel, the nearest of them.
  struct ViewTriangle {
    std::array<Eigen::Vector3f, 3> l;  // (x, y, 1) . l[k]: barycentric weight k over camera depth
    Eigen::Vector3d n;                 // plane normal (ENU, unnormalised) ...
    double nd = 0;                     // ... and n . (vertex - optical centre): hit t = nd / n . d
    int32_t index = 0;                 // in the mesh
  };
  struct MeshRaster {
    std::vector<ViewTriangle> view;
    std::vector<int32_t> tri;  // per compact pixel: index into view, -1: no triangle
  };
  void rasterise(const ground::MeshGround& mesh, const Eigen::Isometry3d& vehicle_to_enu, MeshRaster& out) const;
  // Appends the separation pixels of kept row r to `out` as (pixel index, layer bits).
  void separationPixels(const cv::Mat& labels, const Row& r, std::vector<std::pair<int, uint8_t>>& out) const;

  camera::CameraModel camera_;
  ProjectorOptions options_;
  Eigen::Vector3f centre_;          // optical centre, vehicle frame
  std::vector<Ray> rays_;           // every pixel (row-major); dir.z >= 0 where not a candidate
  std::vector<uint8_t> candidate_;  // per pixel
  size_t candidates_ = 0;
  std::vector<Row> rows_;           // kept rows
  std::vector<int> lattice_;        // pixel indices of the lattice
  // Mesh raster (see the header comment).
  bool raster_ok_ = false;
  std::vector<RasterRow> raster_rows_;      // kept rows, v ascending
  std::vector<float> row_qy_hi_max_;        // running max of qy_hi (ascending v)
  std::vector<float> row_qy_lo_min_;        // running min of qy_lo from the end
  std::vector<float> rqx_, rqy_;            // per compact pixel
  std::vector<int32_t> compact_;            // per pixel: compact index, -1 off the lattice
  std::vector<int32_t> raster_row_of_v_;    // image row -> raster_rows_ index, -1 if not kept
  std::vector<int32_t> lut_;
  float qx_min_ = 0, qx_max_ = 0, qy_min_ = 0, qy_max_ = 0;  // box of all compact pixels
};

}  // namespace lanemap::bev
