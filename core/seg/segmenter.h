// Semantic segmentation of camera frames through OpenCV's DNN module (METHOD.md section 2), LCM-free.
// Any ONNX segmentation model works: input size, pixel normalisation, channel order, the output's
// kind (per-class scores or class ids) and the mapping of the model's classes onto lanemap's
// 11 classes (label_image_t ids) all come from the config, so the shipped LaneSegNet
// (models/README.md) and a user's own DeepLab-v3+ load the same way.
//
// Per frame: resize the BGR frame to the input size, (pixel * scale - mean) / std per channel (in
// the model's channel order), forward, bring the scores back to the frame size (bilinear, before
// the argmax: thin markings keep sub-pixel edges) and map classes.
#pragma once

#include <yaml-cpp/yaml.h>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::config { class YamlReader; }

namespace lanemap::seg {

// A model that cannot be used (missing file, not ONNX, wrong output shape) or a bad config.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A camera frame that cannot be decoded (corrupt JPEG, wrong size, unknown pixel format).
class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ModelConfig {
  std::string path;                  // the ONNX file (relative paths: to the config file's folder
                                     // when read by fromYaml with a base folder)
  std::string name;                  // label_image_t.source; default: the file's stem
  int input_width = 320, input_height = 176;
  int crop_top = 0;                  // frame rows at the top the model never sees (the sky): they are
                                     // labelled background, the rest is resized to the input size
  bool rgb = true;                   // the model takes RGB (false: BGR, OpenCV's order)
  double scale = 1.0 / 255.0;        // pixel (0-255) * scale ...
  std::array<double, 3> mean{{0.0, 0.0, 0.0}};  // ... - mean ... (in the model's channel order)
  std::array<double, 3> std{{1.0, 1.0, 1.0}};   // ... / std
  enum class Output { kScores, kLabels } output = Output::kScores;  // N x C x H x W, or class ids
  // lanemap class (0..10) of each model class; empty: identity (the model has lanemap's 11
  // classes). A negative entry or one > 10 maps to background (0).
  std::vector<int> class_map;
  bool upsample_scores = true;       // bilinear scores to the frame size, then argmax (false:
                                     // argmax at the model's size, nearest-neighbour upsampling)
  // A model whose scores end in a DepthToSpace (a pixel shuffle, as the shipped LaneSegNet's do):
  // OpenCV 4.6 runs it as a 6-D Permute that takes a quarter of the forward pass. true: the
  // segmenter takes the layer before it and lays the scores out itself, after checking at load, on
  // a random input, that the result equals the model's own output exactly (else the model's own).
  bool shuffle_in_segmenter = true;

  // Keys: path, name, input_width, input_height, crop_top, rgb, scale, mean, std, output (scores|labels),
  // class_map, upsample (scores|labels), depth_to_space (segmenter|model). Relative paths resolve against base_dir (if not empty)
  // when the file is not found as given. Throws ModelError naming the key.
  static ModelConfig fromYaml(const YAML::Node& node, const std::string& base_dir = "");
  // The same from a config section (config/segmenter.yaml `model:`), `model_path` (when not empty)
  // instead of its path; errors are config::ConfigError naming the file and key. The section's
  // `name` names its own file: a model_path that is another file is named by its stem.
  static ModelConfig fromYaml(const config::YamlReader& r, const std::string& base_dir = "",
                              const std::string& model_path = "");
  // The `model:` block of a segmenter config (config/segmenter.yaml), its path replaced by
  // `model_path` when that is not empty (named by its stem unless it is the config's own file):
  // how lanemap-segmenter and lanemap-offline load the configured model.
  static ModelConfig fromSegmenterConfig(const YAML::Node& config, const std::string& model_path = "",
                                         const std::string& base_dir = "");
};

class Segmenter {
 public:
  // Loads and checks the model (one forward pass on a blank image). Throws ModelError with a clear
  // message: missing file, not an ONNX model, output not 4-D / class count not matching class_map.
  explicit Segmenter(const ModelConfig& config);
  ~Segmenter();
  Segmenter(const Segmenter&) = delete;
  Segmenter& operator=(const Segmenter&) = delete;

  // BGR CV_8UC3 frame of any size -> CV_8UC1 lanemap classes of the same size. Throws FrameError
  // when the frame is not taller than crop_top + 8 rows. Not thread-safe (one Segmenter per thread).
  cv::Mat segment(const cv::Mat& bgr);

  const ModelConfig& config() const { return config_; }
  const std::string& name() const { return config_.name; }
  int modelClasses() const { return model_classes_; }
  // The model's trailing DepthToSpace is done by the segmenter (shuffle_in_segmenter and the load
  // check passed): its block size, 0 when the network runs whole.
  int shuffleBlock() const;

 private:
  cv::Mat segmentRegion(const cv::Mat& bgr);  // the model's classes for all of bgr

  struct Impl;
  ModelConfig config_;
  std::unique_ptr<Impl> impl_;
  int model_classes_ = 0;
  std::array<uint8_t, 256> map_{};
};

// Pixel formats (V4L2 fourcc, as lanemap.image_t's PIXEL_FORMAT_*).
inline constexpr int32_t kPixelGray = 0x59455247, kPixelYuyv = 0x56595559, kPixelRgb = 0x33424752,
                         kPixelBgr = 0x33524742, kPixelMjpeg = 0x47504a4d, kPixelJpeg = 0x4745504a;

// A camera frame's bytes -> BGR CV_8UC3. width/height are the message's; a compressed image whose
// decoded size differs, a raw buffer too short for width x height (row_stride 0: tightly packed),
// a corrupt JPEG or an unknown format throw FrameError.
cv::Mat decodeFrame(int32_t pixelformat, int width, int height, int row_stride, const uint8_t* data, size_t size);

// Class image <-> PNG / raw bytes (label_image_t encodings).
std::vector<uint8_t> encodeLabelsPng(const cv::Mat& labels);
cv::Mat decodeLabels(int8_t encoding, int width, int height, const std::vector<uint8_t>& data);  // throws FrameError

}  // namespace lanemap::seg
