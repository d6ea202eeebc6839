// Camera frames and their truth labels rendered straight from the simulator's core (no LCM log):
// the training set of the segmentation model (tools/seg_dataset.cc) and the held-out frames its
// test scores (tests/seg/). A seeded auto drive over a street network; every ~frame_spacing_s one
// frame is rendered under seeded conditions (light, sun, shadows, haze, sensor noise, camera pitch /
// roll / yaw / height jitter), JPEG-encoded as the camera driver would publish it.
//
// Regions: the network's road extent is split along east. kValidation is the western
// `validation_fraction` of it; kTrain starts `guard_m` east of that line (the camera sees ~50 m, so
// no validation street is seen in training). Whole networks can be held out too (kAll).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lanemap::seg {

enum class SimRegion { kAll, kTrain, kValidation };

struct SimFrameOptions {
  std::string osm_path;        // street network (.osm / .osm.pbf)
  std::string vehicle_yaml;    // camera (config/vehicle.yaml)
  std::string world_yaml;      // world generation (config/sim_world.yaml); empty: defaults
  std::string drive_yaml;      // driving style (config/sim_drive.yaml); empty: defaults
  uint64_t seed = 1;           // world, route, conditions, noise
  int max_frames = 100;
  double frame_spacing_s = 1.0;  // mean time between kept frames (jittered +-40 %)
  double duration_s = 400.0;     // the drive (frames stop at its end or at max_frames)
  SimRegion region = SimRegion::kAll;
  double validation_fraction = 0.3;
  double guard_m = 60.0;
  bool vary_conditions = true;   // false: the simulator's default look (as lanemap-sim renders)
  int condition_sets = 4;        // lighting presets drawn per seed (one renderer each)
  double pitch_jitter_deg = 1.5; // uniform +- (camera nod on the suspension, mount tolerance)
  double roll_jitter_deg = 1.0;
  double yaw_jitter_deg = 1.5;
  double height_jitter_m = 0.08;
  double faded_marking = -1.0;   // >= 0: overrides the world's faded-marking probability
  int jpeg_quality = 90;
};

struct SimFrame {
  int index = 0;                   // 0, 1, ... in the order produced
  double t = 0.0;                  // seconds into the drive
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // vehicle, ENU
  std::vector<uint8_t> jpeg;       // the camera image as CAMERA_FRONT carries it
  cv::Mat bgr;                     // the JPEG decoded (what a segmenter sees)
  cv::Mat labels;                  // CV_8UC1 truth classes (label_image_t ids)
  double light = 1.0, sun_elevation_deg = 40.0, pitch_offset_deg = 0.0;
};

// Renders frames and hands each to `sink` (return false to stop). Returns how many were produced.
// Throws std::runtime_error (bad files, no road in the region, ...).
int renderSimFrames(const SimFrameOptions& options, const std::function<bool(const SimFrame&)>& sink);

// Confusion matrix (rows truth, columns prediction) -> per-class IoU; NaN for a class absent from
// both. mIoU over the non-NaN entries of `classes`.
class ConfusionMatrix {
 public:
  explicit ConfusionMatrix(int num_classes);
  void add(const cv::Mat& truth, const cv::Mat& predicted);  // CV_8UC1, same size
  double iou(int c) const;
  double meanIou(const std::vector<int>& classes) const;
  double pixelAccuracy() const;
  int64_t truthPixels(int c) const;
  int numClasses() const { return n_; }

 private:
  int n_;
  std::vector<int64_t> m_;
};

}  // namespace lanemap::seg
