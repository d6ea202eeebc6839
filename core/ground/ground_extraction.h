// Ground points of one LIDAR sweep (METHOD.md section 3, topographic model): which points lie on
// the road surface (and the ground next to it) rather than on cars, buildings, poles.
//
// Method: sector-wise RANSAC planes grown outwards (in the spirit of Patchwork), with PCL's
// RandomSampleConsensus over SampleConsensusModelPerpendicularPlane (a plane whose normal is within
// max_tilt_deg of up). The sweep, in the vehicle frame (z = 0 is the ground under the car), is
// cut into azimuth sectors x range bins. In each sector the bins are visited from the car outwards:
// a bin's candidates are the points within `band` of the plane predicted by the previous bin
// (the vehicle's own ground plane for the first), band = band_base_m + band_slope * (range step),
// which keeps car roofs, walls and kerb-side clutter out even where they outnumber the ground
// points; RANSAC fits the bin's plane to the candidates; its inliers (within distance_threshold_m)
// are ground, and the plane becomes the next bin's prediction. A bin with too few candidates keeps
// the previous prediction.
//
// Before that, points on vertical structures are taken out: within a thin azimuth slice, sorted by
// horizontal range, two neighbours more than vertical_step_m apart in height and steeper than
// vertical_slope are a wall, a car side or a pole (consecutive rings on the ground are metres
// apart, on a wall centimetres), so neither can be ground. Without this, a bin that holds only a
// wall's lowest ring (a horizontal line of points 0.15 m up) would fit a "ground" plane to it.
//
// Why not a single plane: the simulator's (and a real city's) roads are crowned and hilly; one
// plane over 60 m is off by decimetres. Why not PCL's ProgressiveMorphologicalFilter: it works on a
// dense raster and costs hundreds of ms on a 30k-point sweep; sparse VLP-16 rings (2 deg apart)
// leave most raster cells empty. This costs a few ms (tools/bench/bev_bench.cc).
//
// Deterministic: PCL's RANSAC draws from a fixed seed.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace lanemap::ground {

struct GroundExtractionOptions {
  int sectors = 16;                                              // azimuth sectors
  std::vector<double> range_edges_m = {1.5, 9.0, 13.0, 18.0, 26.0, 40.0, 70.0};  // range bins (horizontal)
  double band_base_m = 0.25;         // candidates: within this of the predicted plane ...
  double band_slope = 0.04;          // ... plus this times the range step (grade changes)
  double distance_threshold_m = 0.08;  // RANSAC inlier distance
  double max_tilt_deg = 12.0;        // plane normal within this of up
  int min_points = 12;               // fewer candidates: no plane in that bin
  int max_iterations = 60;           // RANSAC iterations per bin
  double azimuth_slice_deg = 1.0;    // vertical-structure test: slice width ...
  double vertical_step_m = 0.1;      // ... neighbours this much apart in height ...
  double vertical_slope = 1.0;       // ... and steeper than this are not ground
};

// Indices of the ground points among `points_vehicle` (vehicle frame: x forward, y left, z up,
// z = 0 the ground under the car), ascending.
std::vector<int> extractGround(const std::vector<Eigen::Vector3d>& points_vehicle,
                               const GroundExtractionOptions& options = {});

}  // namespace lanemap::ground
