#include "core/seg/segmenter.h"

#include "core/config/yaml_reader.h"
#include "core/io/image_header.h"

#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace fs = std::filesystem;

namespace lanemap::seg {

namespace {

constexpr int kLanemapClasses = 11;

// "mean: 0.5" or "mean: [0.5, 0.4, 0.3]".
std::array<double, 3> triple(const config::YamlReader& r, const char* key, std::array<double, 3> fallback) {
  const YAML::Node v = r.raw(key);
  if (!v.IsDefined() || v.IsNull()) return fallback;
  if (v.IsScalar()) {
    const double x = r.get<double>(key, 0.0);
    return {x, x, x};
  }
  std::array<double, 3> out{};
  if (!v.IsSequence() || v.size() != 3 || !r.read(key, out)) r.fail(key, "must be 3 numbers (or one for all three)");
  return out;
}

}  // namespace

ModelConfig ModelConfig::fromSegmenterConfig(const YAML::Node& config, const std::string& model_path,
                                              const std::string& base_dir) {
  const YAML::Node node = config["model"] ? YAML::Clone(config["model"]) : YAML::Node(YAML::NodeType::Map);
  try {
    const config::YamlReader r(node);
    ModelConfig c = fromYaml(r, base_dir, model_path);
    r.finish();
    return c;
  } catch (const config::ConfigError& e) {
    throw ModelError(std::string("model config: ") + e.what());
  }
}

ModelConfig ModelConfig::fromYaml(const YAML::Node& node, const std::string& base_dir) {
  try {
    const config::YamlReader r(node);
    if (!r.present()) r.failHere("expected a map with at least 'path'");
    ModelConfig c = fromYaml(r, base_dir);
    r.finish();
    return c;
  } catch (const config::ConfigError& e) {
    throw ModelError(std::string("model config: ") + e.what());
  }
}

ModelConfig ModelConfig::fromYaml(const config::YamlReader& r, const std::string& base_dir, const std::string& model_path) {
  auto resolve = [&](const std::string& path) {
    if (!base_dir.empty() && fs::path(path).is_relative() && !fs::exists(path) && fs::exists(fs::path(base_dir) / path)) {
      return (fs::path(base_dir) / path).lexically_normal().string();
    }
    return path;
  };
  ModelConfig c;
  const std::string configured = resolve(r.get<std::string>("path", ""));
  c.path = model_path.empty() ? configured : resolve(model_path);
  if (c.path.empty()) r.fail("path", "(the ONNX file) is required");
  // The config's name names the config's file: a model given instead of it (another file) is
  // named by its own stem, so a summary never credits one model with another's labels.
  std::error_code ec;
  const bool same_file = c.path == configured || fs::equivalent(c.path, configured, ec);
  c.name = fs::path(c.path).stem().string();
  if (same_file) r.read("name", c.name);
  else r.allow({"name"});
  r.read("input_width", c.input_width);
  r.read("input_height", c.input_height);
  if (c.input_width < 8 || c.input_height < 8 || c.input_width > 8192 || c.input_height > 8192)
    r.failHere("input_width/input_height must be in [8, 8192]");
  if (r.read("crop_top", c.crop_top) && (c.crop_top < 0 || c.crop_top > 8192)) r.fail("crop_top", "must be in [0, 8192] rows");
  r.read("rgb", c.rgb);
  r.read("scale", c.scale);
  c.mean = triple(r, "mean", c.mean);
  c.std = triple(r, "std", c.std);
  for (double s : c.std)
    if (!(std::abs(s) > 1e-12)) r.fail("std", "entries must be non-zero");
  const std::string output = r.get<std::string>("output", "scores");
  if (output == "scores") c.output = Output::kScores;
  else if (output == "labels") c.output = Output::kLabels;
  else r.fail("output", "must be scores or labels, not '" + output + "'");
  if (r.read("class_map", c.class_map) && (c.class_map.empty() || c.class_map.size() > 256)) {
    r.fail("class_map", "must have 1..256 entries");
  }
  const std::string up = r.get<std::string>("upsample", "scores");
  if (up == "scores") c.upsample_scores = true;
  else if (up == "labels") c.upsample_scores = false;
  else r.fail("upsample", "must be scores or labels, not '" + up + "'");
  const std::string d2s = r.get<std::string>("depth_to_space", "segmenter");
  if (d2s == "segmenter") c.shuffle_in_segmenter = true;
  else if (d2s == "model") c.shuffle_in_segmenter = false;
  else r.fail("depth_to_space", "must be segmenter or model, not '" + d2s + "'");
  return c;
}

struct Segmenter::Impl {
  cv::dnn::Net net;
  cv::Mat blob;
  // A trailing DepthToSpace done here (findShuffle): the layer whose output it takes, its block.
  std::string shuffle_from;
  int block = 0;
  cv::Mat scores;            // 1 x C x H x W, the shuffled scores (reused)
  std::vector<cv::Mat> up;   // per-class scores at the frame's size (reused)

  // The model's scores: the whole network, or up to shuffle_from and the pixel shuffle here.
  cv::Mat forward() {
    if (block == 0) return net.forward();
    const cv::Mat in = net.forward(shuffle_from);
    const int Cb = in.size[1], h = in.size[2], w = in.size[3], C = Cb / (block * block);
    const int sizes[4] = {1, C, h * block, w * block};
    scores.create(4, sizes, CV_32F);
    depthToSpaceCrd(in, block, scores);
    return scores;
  }

  // ONNX DepthToSpace, mode CRD (what PyTorch's PixelShuffle exports): out[c][y][x] =
  // in[c*b*b + (y%b)*b + x%b][y/b][x/b].
  static void depthToSpaceCrd(const cv::Mat& in, int b, cv::Mat& out) {
    const int h = in.size[2], w = in.size[3], C = out.size[1], W = w * b;
    for (int c = 0; c < C; ++c)
      for (int by = 0; by < b; ++by)
        for (int bx = 0; bx < b; ++bx) {
          const float* src = in.ptr<float>(0, c * b * b + by * b + bx);
          float* dst = out.ptr<float>(0, c);
          for (int y = 0; y < h; ++y) {
            const float* s = src + static_cast<size_t>(y) * w;
            float* d = dst + static_cast<size_t>(y * b + by) * W + bx;
            for (int x = 0; x < w; ++x) d[static_cast<size_t>(x) * b] = s[x];
          }
        }
  }

  // Looks among the last layers before the output for one whose output the pixel shuffle turns into
  // the network's own output, exactly, on a random input: then forward() stops there.
  void findShuffle(int input_width, int input_height) {
    const int sizes[4] = {1, 3, input_height, input_width};
    cv::Mat probe(4, sizes, CV_32F);
    cv::RNG rng(0x5eed);
    rng.fill(probe, cv::RNG::UNIFORM, -2.0, 2.0);
    net.setInput(probe);
    const cv::Mat whole = net.forward().clone();
    if (whole.dims != 4) return;
    const int C = whole.size[1], H = whole.size[2], W = whole.size[3];
    const std::vector<cv::String> names = net.getLayerNames();
    for (int back = 2; back <= 6 && back <= static_cast<int>(names.size()); ++back) {
      const std::string& name = names[names.size() - static_cast<size_t>(back)];
      cv::Mat in;
      try {
        net.setInput(probe);
        in = net.forward(name);
      } catch (const cv::Exception&) {
        continue;
      }
      if (in.dims != 4 || in.type() != CV_32F || in.size[0] != 1) continue;
      for (int b = 2; b <= 8; ++b) {
        if (in.size[1] != C * b * b || in.size[2] * b != H || in.size[3] * b != W) continue;
        cv::Mat shuffled(4, whole.size.p, CV_32F);
        depthToSpaceCrd(in, b, shuffled);
        if (std::memcmp(shuffled.data, whole.data, whole.total() * sizeof(float)) != 0) continue;
        shuffle_from = name;
        block = b;
        return;
      }
    }
  }
};

Segmenter::Segmenter(const ModelConfig& config) : config_(config), impl_(std::make_unique<Impl>()) {
  if (config_.name.empty()) config_.name = fs::path(config_.path).stem().string();
  std::error_code ec;
  if (config_.path.empty()) throw ModelError("segmentation model: no model path given");
  if (!fs::exists(config_.path, ec)) throw ModelError("segmentation model '" + config_.path + "' does not exist");
  if (!fs::is_regular_file(config_.path, ec) || fs::file_size(config_.path, ec) == 0)
    throw ModelError("segmentation model '" + config_.path + "' is not a regular, non-empty file");
  try {
    impl_->net = cv::dnn::readNetFromONNX(config_.path);
  } catch (const cv::Exception& e) {
    throw ModelError("segmentation model '" + config_.path + "' is not an ONNX model OpenCV can load: " + e.what());
  }
  if (impl_->net.empty()) throw ModelError("segmentation model '" + config_.path + "' is not an ONNX model (empty network)");
  impl_->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  impl_->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);

  // One forward pass on a grey frame: the output must be 4-D (scores) or hold one id per pixel.
  cv::Mat out;
  try {
    cv::Mat probe(config_.input_height, config_.input_width, CV_8UC3, cv::Scalar(128, 128, 128));
    cv::Mat blob;
    cv::dnn::blobFromImage(probe, 1.0, cv::Size(), cv::Scalar(), false, false, CV_32F).copyTo(blob);
    impl_->net.setInput(blob);
    out = impl_->net.forward();
  } catch (const cv::Exception& e) {
    throw ModelError("segmentation model '" + config_.path + "' fails on a " + std::to_string(config_.input_width) +
                     "x" + std::to_string(config_.input_height) + " input: " + e.what());
  }
  if (config_.output == ModelConfig::Output::kScores) {
    if (out.dims != 4 || out.size[0] != 1)
      throw ModelError("segmentation model '" + config_.path + "': expected scores N x C x H x W, got a " +
                       std::to_string(out.dims) + "-D output");
    model_classes_ = out.size[1];
    const size_t want = config_.class_map.empty() ? kLanemapClasses : config_.class_map.size();
    if (static_cast<size_t>(model_classes_) != want)
      throw ModelError("segmentation model '" + config_.path + "' outputs " + std::to_string(model_classes_) +
                       " classes but the config maps " + std::to_string(want) + " (set class_map)");
  } else {
    model_classes_ = config_.class_map.empty() ? kLanemapClasses : static_cast<int>(config_.class_map.size());
    const size_t total = out.total();
    const int h = out.size[out.dims - 2], w = out.size[out.dims - 1];
    if (out.dims < 2 || total != static_cast<size_t>(h) * w)
      throw ModelError("segmentation model '" + config_.path + "': expected one class id per pixel (N x H x W)");
  }
  if (config_.output == ModelConfig::Output::kScores && config_.shuffle_in_segmenter) {
    try {
      impl_->findShuffle(config_.input_width, config_.input_height);
    } catch (const cv::Exception&) {
      impl_->block = 0;  // the network runs whole
    }
  }
  map_.fill(0);
  for (int i = 0; i < 256; ++i) {
    int c = i;
    if (!config_.class_map.empty()) c = i < static_cast<int>(config_.class_map.size()) ? config_.class_map[i] : 0;
    map_[i] = static_cast<uint8_t>(c >= 0 && c < kLanemapClasses ? c : 0);
  }
}

Segmenter::~Segmenter() = default;

int Segmenter::shuffleBlock() const { return impl_->block; }

cv::Mat Segmenter::segment(const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw FrameError("segment: need a BGR CV_8UC3 image");
  const int top = config_.crop_top;
  if (top == 0) return segmentRegion(bgr);
  if (bgr.rows < top + 8)
    throw FrameError("segment: a frame of " + std::to_string(bgr.rows) + " rows has nothing below the model's crop_top " +
                     std::to_string(top));
  cv::Mat labels(bgr.size(), CV_8UC1, cv::Scalar(0));
  segmentRegion(bgr.rowRange(top, bgr.rows)).copyTo(labels.rowRange(top, bgr.rows));
  return labels;
}

cv::Mat Segmenter::segmentRegion(const cv::Mat& bgr) {
  const int W = config_.input_width, H = config_.input_height;
  cv::Mat resized;
  const bool shrink = bgr.cols >= W && bgr.rows >= H;
  cv::resize(bgr, resized, cv::Size(W, H), 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  if (config_.rgb) cv::cvtColor(resized, resized, cv::COLOR_BGR2RGB);
  // NCHW blob with (pixel * scale - mean) / std per channel.
  const int sizes[4] = {1, 3, H, W};
  impl_->blob.create(4, sizes, CV_32F);
  cv::Mat planes[3];
  for (int c = 0; c < 3; ++c) planes[c] = cv::Mat(H, W, CV_32F, impl_->blob.ptr<float>(0, c));
  cv::Mat split[3];
  cv::split(resized, split);
  for (int c = 0; c < 3; ++c) {
    const double a = config_.scale / config_.std[c], b = -config_.mean[c] / config_.std[c];
    split[c].convertTo(planes[c], CV_32F, a, b);
  }
  impl_->net.setInput(impl_->blob);
  const cv::Mat out = impl_->forward();

  const cv::Size frame = bgr.size();
  cv::Mat labels(frame, CV_8UC1);
  if (config_.output == ModelConfig::Output::kLabels) {
    const int h = out.size[out.dims - 2], w = out.size[out.dims - 1];
    cv::Mat ids(h, w, out.type(), out.data);
    cv::Mat ids8;
    ids.convertTo(ids8, CV_8U);  // ids 0..255, rounded
    cv::resize(ids8, labels, frame, 0, 0, cv::INTER_NEAREST);
    labels.forEach<uint8_t>([this](uint8_t& v, const int*) { v = map_[v]; });
    return labels;
  }
  const int C = out.size[1], h = out.size[2], w = out.size[3];
  if (config_.upsample_scores && (h != frame.height || w != frame.width)) {
    std::vector<cv::Mat>& up = impl_->up;
    up.resize(static_cast<size_t>(C));
    for (int c = 0; c < C; ++c) {
      cv::Mat plane(h, w, CV_32F, const_cast<float*>(out.ptr<float>(0, c)));
      cv::resize(plane, up[static_cast<size_t>(c)], frame, 0, 0, cv::INTER_LINEAR);
    }
    for (int r = 0; r < frame.height; ++r) {
      uint8_t* dst = labels.ptr<uint8_t>(r);
      const float* p0 = up[0].ptr<float>(r);
      std::vector<const float*> rows(static_cast<size_t>(C));
      for (int c = 0; c < C; ++c) rows[static_cast<size_t>(c)] = up[static_cast<size_t>(c)].ptr<float>(r);
      for (int x = 0; x < frame.width; ++x) {
        float best = p0[x];
        int arg = 0;
        for (int c = 1; c < C; ++c) {
          const float v = rows[static_cast<size_t>(c)][x];
          if (v > best) {
            best = v;
            arg = c;
          }
        }
        dst[x] = map_[static_cast<size_t>(arg)];
      }
    }
    return labels;
  }
  cv::Mat small(h, w, CV_8UC1);
  const size_t plane = static_cast<size_t>(h) * w;
  const float* base = out.ptr<float>();
  for (size_t i = 0; i < plane; ++i) {
    float best = base[i];
    int arg = 0;
    for (int c = 1; c < C; ++c) {
      const float v = base[static_cast<size_t>(c) * plane + i];
      if (v > best) {
        best = v;
        arg = c;
      }
    }
    small.data[i] = map_[static_cast<size_t>(arg)];
  }
  if (small.size() == frame) return small;
  cv::resize(small, labels, frame, 0, 0, cv::INTER_NEAREST);
  return labels;
}

cv::Mat decodeFrame(int32_t pixelformat, int width, int height, int row_stride, const uint8_t* data, size_t size) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw FrameError("frame: bad size " + std::to_string(width) + "x" + std::to_string(height));
  if (data == nullptr || size == 0) throw FrameError("frame: no image data");
  cv::Mat bgr;
  switch (pixelformat) {
    case kPixelJpeg:
    case kPixelMjpeg: {
      // The header's size first: a JPEG that claims 65535x65535 in a few kB would otherwise make
      // imdecode allocate gigabytes before it fails (fuzz/regressions/lcm_decode).
      const auto header = io::jpegSize(data, size);
      if (!header) throw FrameError("frame: corrupt JPEG (no frame header in " + std::to_string(size) + " bytes)");
      if (header->width != width || header->height != height)
        throw FrameError("frame: JPEG is " + std::to_string(header->width) + "x" + std::to_string(header->height) +
                         " but the message says " + std::to_string(width) + "x" + std::to_string(height) +
                         " (from its header; not decoded)");
      if (size > static_cast<size_t>(std::numeric_limits<int>::max())) throw FrameError("frame: JPEG too large");
      const cv::Mat buf(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
      try {
        bgr = cv::imdecode(buf, cv::IMREAD_COLOR);
      } catch (const cv::Exception& e) {
        throw FrameError(std::string("frame: corrupt JPEG: ") + e.what());
      }
      if (bgr.empty()) throw FrameError("frame: corrupt JPEG (" + std::to_string(size) + " bytes do not decode)");
      if (bgr.cols != width || bgr.rows != height)
        throw FrameError("frame: JPEG is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                         " but the message says " + std::to_string(width) + "x" + std::to_string(height));
      return bgr;
    }
    case kPixelBgr:
    case kPixelRgb:
    case kPixelGray:
    case kPixelYuyv: {
      const int bpp = pixelformat == kPixelGray ? 1 : pixelformat == kPixelYuyv ? 2 : 3;
      const size_t stride = row_stride > 0 ? static_cast<size_t>(row_stride) : static_cast<size_t>(width) * bpp;
      if (stride < static_cast<size_t>(width) * bpp || size < stride * (height - 1) + static_cast<size_t>(width) * bpp)
        throw FrameError("frame: raw buffer of " + std::to_string(size) + " bytes is too short for " +
                         std::to_string(width) + "x" + std::to_string(height));
      const cv::Mat raw(height, width, bpp == 1 ? CV_8UC1 : bpp == 2 ? CV_8UC2 : CV_8UC3, const_cast<uint8_t*>(data), stride);
      try {
        if (pixelformat == kPixelBgr) raw.copyTo(bgr);
        else if (pixelformat == kPixelRgb) cv::cvtColor(raw, bgr, cv::COLOR_RGB2BGR);
        else if (pixelformat == kPixelGray) cv::cvtColor(raw, bgr, cv::COLOR_GRAY2BGR);
        else cv::cvtColor(raw, bgr, cv::COLOR_YUV2BGR_YUYV);
      } catch (const cv::Exception& e) {  // e.g. an odd YUYV width
        throw FrameError(std::string("frame: cannot convert the raw frame: ") + e.what());
      }
      return bgr;
    }
    default: {
      char code[5] = {static_cast<char>(pixelformat & 0xff), static_cast<char>((pixelformat >> 8) & 0xff),
                      static_cast<char>((pixelformat >> 16) & 0xff), static_cast<char>((pixelformat >> 24) & 0xff), 0};
      for (char& ch : code)
        if (ch != 0 && (ch < 32 || ch > 126)) ch = '?';
      throw FrameError(std::string("frame: unsupported pixel format '") + code + "'");
    }
  }
}

std::vector<uint8_t> encodeLabelsPng(const cv::Mat& labels) {
  std::vector<uint8_t> png;
  cv::imencode(".png", labels, png, {cv::IMWRITE_PNG_COMPRESSION, 3});
  return png;
}

cv::Mat decodeLabels(int8_t encoding, int width, int height, const std::vector<uint8_t>& data) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw FrameError("labels: bad size " + std::to_string(width) + "x" + std::to_string(height));
  if (encoding == 0) {
    if (data.size() != static_cast<size_t>(width) * height) throw FrameError("labels: raw size does not match");
    return cv::Mat(height, width, CV_8UC1, const_cast<uint8_t*>(data.data())).clone();
  }
  if (encoding != 1) throw FrameError("labels: unknown encoding " + std::to_string(encoding));
  const auto header = io::pngSize(data.data(), data.size());
  if (!header || header->width != width || header->height != height)
    throw FrameError("labels: PNG header does not say " + std::to_string(width) + "x" + std::to_string(height));
  cv::Mat m;
  try {
    m = cv::imdecode(data, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw FrameError(std::string("labels: corrupt PNG: ") + e.what());
  }
  if (m.empty() || m.type() != CV_8UC1 || m.cols != width || m.rows != height)
    throw FrameError("labels: PNG does not decode to a " + std::to_string(width) + "x" + std::to_string(height) + " class image");
  return m;
}

}  // namespace lanemap::seg
