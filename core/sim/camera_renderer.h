// The simulator's front camera: renders what a CameraModel sees of a World — an RGB image and the
// ground-truth 10-class label image (sim::LabelClass, relative to the ego lane) — by casting one ray
// per pixel centre (so a label is exactly the class of the surface the pixel centre looks at).
//
// RGB: per-surface colours (grey asphalt with world-fixed texture, white paint, yellow solid lines
// between opposite directions, light grey curbs, sidewalk, grass), obstacles shaded by their face
// normal, a sky gradient, sun lighting scaled by RenderOptions::light, soft obstacle shadows on the
// ground, distance haze, and per-pixel sensor noise drawn from the seed (deterministic whatever the
// thread count). Columns are rendered in parallel with cv::parallel_for_, each from the bottom up.
#pragma once

#include "core/camera/camera_model.h"
#include "core/sim/raycast.h"
#include "core/sim/world.h"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <vector>

namespace lanemap::sim {

struct RenderOptions {
  double max_range_m = 200.0;        // farther than this is sky
  double light = 1.0;                // global brightness (1 = a bright day, 0.3 = dusk)
  double sun_azimuth_deg = 135.0;    // compass bearing of the sun (clockwise from north)
  double sun_elevation_deg = 40.0;   // above the horizon; <= 0: no direct sun, no shadows
  double ambient = 0.45;             // share of light that is not direct sun
  bool shadows = true;               // soft shadows of obstacles on the ground
  double shadow_range_m = 30.0;      // longest shadow cast (metres along the sun ray)
  double shadow_softness_deg = 1.5;  // angular radius of the sun disc used for soft edges
  bool yellow_centre_lines = true;   // solid paint between opposite directions is yellow
  // Whether two road lanelets run in opposite directions (then solid paint between them is a
  // yellow centre line). Empty: lanelets with no World::laneOffset between them count as opposite.
  // A World whose laneOffset also spans opposite directions should supply it (e.g. SimWorld:
  // a.from_node == b.to_node && a.to_node == b.from_node). Called from the render threads.
  std::function<bool(int64_t, int64_t)> opposite_directions;
  double sensor_noise = 2.5;         // standard deviation of per-pixel noise, 0-255 units
  double haze_distance_m = 350.0;    // distance at which haze covers 63 % of a surface's colour
  RaycastOptions raycast;            // ground marching / obstacle query settings
  // Start each pixel's ground march where the pixel below it was still above the ground (see
  // clearanceCarriesOver): about half the march steps; the hits are the same surface points to
  // within raycast.tolerance_m but on grazing rays (see raycast). false: every march starts at the
  // optical centre, as before 2026-12-02 (the frames then differ from the default's in about 0.3 %
  // of the pixels, at paint, curb and texture-cell edges: tests/render/camera_renderer_test.cc).
  bool march_from_pixel_below = true;
};

struct RenderedFrame {
  cv::Mat rgb;     // CV_8UC3, BGR (OpenCV order)
  cv::Mat labels;  // CV_8UC1, sim::LabelClass ids
  cv::Mat range;   // CV_32FC1, metres along the pixel ray to the hit; +inf for sky
};

class CameraRenderer {
 public:
  // Caches the vehicle-frame ray of every pixel centre. Throws std::invalid_argument on bad options.
  explicit CameraRenderer(const camera::CameraModel& camera, const RenderOptions& options = RenderOptions());

  // vehicle_to_enu: the vehicle pose; ego_lanelet: the lanelet the car drives in (-1: none) that
  // labels are relative to; seed: the sensor noise (same inputs + seed -> same image).
  RenderedFrame render(const World& world, const Eigen::Isometry3d& vehicle_to_enu,
                       int64_t ego_lanelet, uint64_t seed) const;

  const camera::CameraModel& camera() const { return camera_; }
  const RenderOptions& options() const { return options_; }

 private:
  camera::CameraModel camera_;
  RenderOptions options_;
  std::vector<Eigen::Vector3d> rays_vehicle_;  // unit, row-major per pixel centre
};

}  // namespace lanemap::sim
